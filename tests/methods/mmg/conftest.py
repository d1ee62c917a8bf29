"""Fixtures of the MMG tests: runs an MMG model produced itself.

``own_run``: a noise-free zig-zag (the model's own prediction of it is exact); ``noisy_run``: random
rudder/propeller orders in a steady wind with seeded measurement noise (for identification).
Both are session-scoped factories (pure functions of their arguments). ``replay_ref``: the reference
open-loop replay of one run (one :func:`shipid.models.mmg.simulate_batch` per run), against which the batched
replays of :mod:`shipid.methods.mmg.turning_selection` are checked. ``esso_published``: the published Esso
Osaka 3-m model (skips without the shared data); :func:`esso_states`: a factory of seeded states for force comparisons.
"""

from __future__ import annotations

import numpy as np
import pytest

from shipid.io import data_root
from shipid.io.trial import Trial
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


def random_orders_run(model: mmg.MmgModel, seed: int, seconds: float) -> Trial:
    """``model`` simulated from ``u = 0.35`` m/s under rudder (±30°) and propeller (6–12 1/s) orders
    drawn anew every 8 s, wind 1 m/s from 0.7 rad, sampled at 0.1 s; Gaussian noise of standard
    deviation 0.02 m, 0.02 m, 0.005 rad, 0.01 m/s, 0.01 m/s, 0.003 rad/s on x, y, psi, u, v, r
    (``numpy.random.default_rng(seed)`` draws orders and noise)."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, 0.1)
    k = np.arange(t.size) // 80
    U = np.zeros((t.size, 4))
    U[:, 0] = np.deg2rad(rng.uniform(-30, 30, k.max() + 1))[k]
    U[:, 1] = rng.uniform(6, 12, k.max() + 1)[k]
    U[:, 2], U[:, 3] = 1.0, 0.7
    X = mmg.simulate_batch(model, t, np.array([[0, 0, 0, 0.35, 0, 0]]), U)[0]
    ch = {c: X[:, i] + s * rng.standard_normal(t.size)
          for i, (c, s) in enumerate(zip(mmg.STATE_NAMES, (0.02, 0.02, 0.005, 0.01, 0.01, 0.003)))}
    ch.update(delta=U[:, 0], n=U[:, 1], wind_speed=U[:, 2], wind_dir=U[:, 3])
    return Trial(t, ch, {}, {"source": f"sim {seed}"})


@pytest.fixture(scope="session")
def own_run():
    """:func:`own_zigzag_run`, a noise-free zig-zag a model produced itself."""
    return own_zigzag_run


@pytest.fixture(scope="session")
def noisy_run():
    """:func:`random_orders_run`, a seeded noisy run under random orders."""
    return random_orders_run


@pytest.fixture(scope="module")
def esso_published():
    """The published Esso Osaka 3-m model (``params/`` of the shared data); skips where it is absent."""
    root = data_root()
    if root is None or not (root / "params").is_dir():
        pytest.skip("shared data (params/) not found (set SHIPID_DATA)")
    return mmg.load_published("esso_osaka_3m")


def _random_states(seed: int = 0, k: int = 200, n_max: float = 15.0):
    """``k`` seeded states ``(u, v, r, delta, n)`` over the low-speed Esso range (forces compared state by state)."""
    g = np.random.default_rng(seed)
    return (g.uniform(-0.1, 0.4, k), g.uniform(-0.05, 0.05, k), g.uniform(-0.05, 0.05, k),
            g.uniform(-0.6, 0.6, k), g.uniform(-15.0, n_max, k))


@pytest.fixture(scope="session")
def esso_states():
    """A factory ``(seed=0, k=200, n_max=15.0) -> (u, v, r, delta, n)`` of seeded low-speed Esso states."""
    return _random_states


def replay_one(model: mmg.MmgModel, tr: Trial) -> dict:
    """Open-loop replay of ``tr``'s measured rudder and propeller from its measured state at execute, one run
    at a time: whole-run heading RMS error (deg) and the peak-yaw-rate error per side (%)."""
    from shipid.methods.mmg import validate as V
    from shipid.methods.mmg.turning_selection import execute_index

    Z = V.measured_states(tr)
    U = V.trial_inputs(tr)
    k0 = execute_index(tr["delta"])
    t = np.asarray(tr.t[k0:], float)
    X = mmg.simulate_batch(model, t - t[0], Z[k0][None], U[k0:][None])[0]
    zr, xr = Z[k0:, 5], X[:, 5]
    e_psi = np.degrees(np.unwrap(X[:, 2]) - np.unwrap(Z[k0:, 2]))
    out = {"psi_rms": float(np.sqrt(np.mean(e_psi ** 2))) if np.all(np.isfinite(e_psi)) else float("inf")}
    for side, sg in (("stbd", 1.0), ("port", -1.0)):
        m_pk, p_pk = float(np.max(sg * zr)), float(np.max(sg * xr)) if np.all(np.isfinite(xr)) else float("nan")
        out[f"r_peak_{side}_err_pct"] = 100.0 * (p_pk - m_pk) / m_pk if np.isfinite(p_pk) else float("inf")
    return out


@pytest.fixture(scope="session")
def replay_ref():
    """:func:`replay_one`, the reference open-loop replay of one run."""
    return replay_one
