"""Channel offsets and re-timing (shipid.methods.mmg.timing)."""

import numpy as np
import pytest

from shipid.io.trial import Trial
from shipid.methods.mmg import timing as T


def _run(seed, lag_psi, lag_uv, lag_r, dur=240.0, noise=0.0):
    """A zig-zag-like run with consistent kinematics (fine Euler steps), then psi, u, v, r delayed."""
    g = np.random.default_rng(seed)
    tf = np.arange(0.0, dur + 3.0, 0.001)
    per = g.uniform(30.0, 50.0)
    r = 0.04 * np.sin(2 * np.pi * tf / per)
    u = 0.3 + 0.03 * np.cos(2 * np.pi * tf / per)
    v = -0.2 * r
    psi = np.concatenate([[0.0], np.cumsum(r[:-1]) * 0.001])
    x = np.concatenate([[0.0], np.cumsum((u * np.cos(psi) - v * np.sin(psi))[:-1]) * 0.001])
    y = np.concatenate([[0.0], np.cumsum((u * np.sin(psi) + v * np.cos(psi))[:-1]) * 0.001])
    t = np.arange(0.0, dur, 0.1) + 2.0
    ch = {"x": np.interp(t, tf, x), "y": np.interp(t, tf, y)}
    for name, a, lag in (("psi", psi, lag_psi), ("u", u, lag_uv), ("v", v, lag_uv), ("r", r, lag_r)):
        ch[name] = np.interp(t - lag, tf, a)
    ch["psi"] = np.angle(np.exp(1j * ch["psi"]))
    if noise:
        ch["x"] = ch["x"] + noise * g.standard_normal(t.size)
        ch["y"] = ch["y"] + noise * g.standard_normal(t.size)
    ch["delta"], ch["n"] = np.zeros(t.size), np.full(t.size, 10.0)
    return Trial(t - 2.0, ch, {}, {"source": f"synthetic-{seed}"})


def test_estimate_lags_finds_the_offsets_of_a_consistent_run():
    trials = [_run(s, 0.8, 0.5, 0.8, noise=0.002) for s in range(3)]
    lag = T.estimate_lags(trials, grid=np.round(np.arange(-0.2, 1.01, 0.1), 10))
    assert lag.psi == pytest.approx(0.8, abs=0.1001)
    assert lag.uv == pytest.approx(0.5, abs=0.1001)
    assert lag.r == pytest.approx(0.8, abs=0.1001)
    assert lag.mismatch_after < lag.mismatch_before
    zero = T.estimate_lags([_run(s, 0.0, 0.0, 0.0) for s in range(2)], grid=np.round(np.arange(-0.3, 0.31, 0.1), 10))
    assert (zero.psi, zero.uv, zero.r) == (0.0, 0.0, 0.0)


def test_retime_undoes_the_delay_and_records_one_repair():
    lagged, clean = _run(7, 0.8, 0.5, 0.8), _run(7, 0.0, 0.0, 0.0)
    out = T.retime(lagged, T.Lags(psi=0.8, uv=0.5, r=0.8, mismatch_before=0.0, mismatch_after=0.0, runs=1))
    n = out.t.size
    assert n == lagged.t.size - 8 and out.t[-1] <= lagged.t[-1] - 0.8 + 1e-9
    for c in ("psi", "u", "v", "r"):
        np.testing.assert_allclose(out[c], clean[c][:n], atol=2e-5)
    for c in ("x", "y", "delta", "n"):
        np.testing.assert_array_equal(out[c], lagged[c][:n])
    (rep,) = out.meta["repairs"]
    assert rep["kind"] == "retimed" and "0.80 s" in rep["text"] and "\n" not in rep["text"]
    assert lagged.meta.get("repairs") is None
