"""Fixtures of the MMG tests: a run an MMG model produced itself (its own prediction is exact)."""

from __future__ import annotations

import numpy as np
import pytest

from shipid.data.trial import Trial
from shipid.models import mmg

UNITS = {"x": "m", "y": "m", "psi": "rad", "u": "m/s", "v": "m/s", "r": "rad/s", "delta": "rad", "n": "1/s"}


def own_zigzag_run(model: mmg.MmgModel, seconds: float = 80.0, *, rudder_deg: float = 15.0,
                   period: float = 40.0, psi0: float = 0.0, units: bool = False,
                   source: str = "simulated") -> Trial:
    """``model`` simulated (:func:`shipid.models.mmg.simulate_batch`) from ``u = 0.4`` m/s, heading
    ``psi0``, with the rudder switching between ±``rudder_deg`` every ``period``/2 s at n = 10 1/s,
    sampled at 0.1 s; channels x, y, psi, u, v, r, delta, n (units stated when ``units``)."""
    t = np.arange(0.0, seconds, 0.1)
    U = np.zeros((t.size, 4))
    U[:, 0] = np.deg2rad(rudder_deg) * np.sign(np.sin(2 * np.pi * t / period))
    U[:, 1] = 10.0
    X = mmg.simulate_batch(model, t, np.array([[0, 0, psi0, 0.4, 0, 0]]), U)[0]
    ch = {c: X[:, i] for i, c in enumerate(mmg.STATE_NAMES)}
    ch.update(delta=U[:, 0], n=U[:, 1])
    return Trial(t, ch, dict(UNITS) if units else {}, {"source": source})


@pytest.fixture
def own_run():
    """:func:`own_zigzag_run`, the run a model produced itself."""
    return own_zigzag_run
