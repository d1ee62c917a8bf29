"""Per-run randomness of a campaign: run *i* depends on (campaign seed, *i*) only.

A campaign with seed ``S`` hands run ``i`` the seed sequence
``numpy.random.SeedSequence([S, i])``. NumPy's ``SeedSequence`` hashes its whole
entropy list, so streams for different ``i`` (or ``S``) are independent for all
practical purposes, and the stream of run ``i`` does not depend on how many
workers there are, which worker ran it, in which order, or whether the campaign
was resumed. A single run can be reproduced on its own with::

    rng = np.random.default_rng(run_seed_sequence(S, i))
"""

from __future__ import annotations

import numpy as np

from shipid.errors import ShipidError


def check_seed(seed) -> int:
    """Return ``seed`` as a Python int, or raise a one-line error if it is not a seed.

    Parameters
    ----------
    seed : int
        Campaign seed; a non-negative integer (NumPy ``SeedSequence`` entropy).
    """
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        raise ShipidError(f"campaign seed must be a non-negative integer, got {seed!r}")
    seed = int(seed)
    if seed < 0:
        raise ShipidError(f"campaign seed must be a non-negative integer, got {seed}")
    return seed


def run_entropy(seed: int, i: int) -> list[int]:
    """Entropy of run ``i`` of a campaign with seed ``seed``: ``[seed, i]`` (stored with each run)."""
    return [int(seed), int(i)]


def run_seed_sequence(seed: int, i: int) -> np.random.SeedSequence:
    """The ``SeedSequence`` that run ``i`` of a campaign with seed ``seed`` receives."""
    return np.random.SeedSequence(run_entropy(seed, i))


def run_rng(seed: int, i: int) -> np.random.Generator:
    """A fresh ``Generator`` for run ``i`` (``default_rng(SeedSequence([seed, i]))``)."""
    return np.random.default_rng(run_seed_sequence(seed, i))
