"""A cheap, deterministic toy task for the campaign engine (tests and cluster smoke tests).

Each run draws a small noisy straight line from its own seed sequence and fits it
by least squares. The outputs are plain floats and ints, so a campaign's results
can be compared bit for bit across executors.
"""

from __future__ import annotations

import os
import time

import numpy as np


def toy_run(i: int, seedseq: np.random.SeedSequence, *, n: int = 200, slope: float = 2.0,
            noise: float = 0.1, fail_every: int = 0, sleep: float = 0.0,
            die_at: int | None = None, marker: str | None = None) -> dict:
    """One toy run: fit ``y = a + b x`` to ``n`` noisy points drawn from ``seedseq``.

    Parameters
    ----------
    i : int
        Run index.
    seedseq : numpy.random.SeedSequence
        The run's seed sequence (``SeedSequence([campaign_seed, i])``).
    n, slope, noise : int, float, float
        Number of points, true slope (intercept 1), noise standard deviation.
    fail_every : int
        If positive, runs with ``i % fail_every == fail_every - 1`` raise ``ValueError``.
    sleep : float
        Seconds to sleep per run (lets tests interrupt a campaign part-way).
    die_at : int or None
        Run index at which the *process* running it dies (``os._exit``), to test
        recovery from a lost worker: every time if ``marker`` is None, else only while
        the file ``marker`` does not exist (it is created just before dying, so the
        retried run proceeds).
    marker : str or None
        See ``die_at``.

    Returns
    -------
    dict
        ``a``, ``b`` (least-squares estimates), ``rss`` and ``draw`` (an integer draw).
    """
    if die_at is not None and i == die_at:
        if marker is None:
            os._exit(17)
        if not os.path.exists(marker):
            with open(marker, "w") as fh:
                fh.write(str(os.getpid()))
            os._exit(17)
    if fail_every and i % fail_every == fail_every - 1:
        raise ValueError(f"toy failure at run {i}")
    if sleep:
        time.sleep(sleep)
    rng = np.random.default_rng(seedseq)
    x = np.linspace(0.0, 1.0, n)
    y = 1.0 + slope * x + noise * rng.standard_normal(n)
    A = np.column_stack([np.ones(n), x])
    coef, rss, *_ = np.linalg.lstsq(A, y, rcond=None)
    return {"a": float(coef[0]), "b": float(coef[1]), "rss": float(rss[0]),
            "draw": int(rng.integers(0, 2**31))}


#: Process id of the process :func:`toy_warm_up` ran in (inherited by processes forked after it).
WARMED_IN: int | None = None


def toy_warm_up(fail: bool = False, **_run_kwargs) -> None:
    """A campaign warm-up for tests: records the process it ran in (:data:`WARMED_IN`);
    raises ``RuntimeError`` with ``fail=True``."""
    global WARMED_IN
    if fail:
        raise RuntimeError("toy warm-up failure")
    WARMED_IN = os.getpid()


def toy_probe(i: int, seedseq: np.random.SeedSequence, **_kwargs) -> dict:
    """A task that reports where it ran and whether its process came warm (``warmed_in``)."""
    return {"pid": os.getpid(), "warmed_in": WARMED_IN}
