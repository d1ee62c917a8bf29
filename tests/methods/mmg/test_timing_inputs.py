"""Input-channel offsets and re-timing (shipid.methods.mmg.timing_inputs)."""

import numpy as np
import pytest

from shipid.io.trial import Trial
from shipid.methods.mmg import timing as T
from shipid.methods.mmg import timing_inputs as TI


def _run(seed, lag_delta, lag_n, dur=300.0):
    """Yaw and surge driven by rudder and propeller (fine Euler steps), then delta and n logged late."""
    g = np.random.default_rng(seed)
    dt = 0.002
    tf = np.arange(0.0, dur + 4.0, dt)
    w = g.uniform(0.1, 0.4, 3)
    delta = sum(0.2 * np.sin(wi * tf + g.uniform(0, 6)) for wi in w)
    n = 10.0 + 2.0 * np.sin(0.05 * tf + g.uniform(0, 6)) + 0.5 * np.sin(0.31 * tf)
    u, r, v = np.empty(tf.size), np.empty(tf.size), np.zeros(tf.size)
    u[0], r[0] = 0.3, 0.0
    for k in range(tf.size - 1):
        du = -0.3 * u[k] * abs(u[k]) + 0.002 * n[k] ** 2 - 0.01 * u[k] * n[k]
        dr = -0.8 * u[k] * r[k] + 0.6 * delta[k] * u[k] ** 2 + 0.0008 * delta[k] * n[k] ** 2
        u[k + 1], r[k + 1] = u[k] + dt * du, r[k] + dt * dr
    t = np.arange(0.0, dur, 0.1) + 2.0
    ch = {c: np.interp(t, tf, a) for c, a in (("u", u), ("v", v), ("r", r))}
    ch["delta"] = np.interp(t - lag_delta, tf, delta)
    ch["n"] = np.interp(t - lag_n, tf, n)
    ch["x"] = ch["y"] = ch["psi"] = np.zeros(t.size)
    return Trial(t - 2.0, ch, {}, {"source": f"synthetic-{seed}"})


def test_estimate_input_lags_finds_the_offsets():
    lag = TI.estimate_input_lags([_run(s, 0.4, -0.3) for s in range(3)], wind=False)
    assert lag.delta == pytest.approx(0.4, abs=0.1001)
    assert lag.n == pytest.approx(-0.3, abs=0.1001)
    assert lag.wind == 0.0 and lag.runs == 3
    assert abs(lag.delta_median - 0.4) <= 0.1001 and np.isfinite(lag.delta_se)


def _lags(delta=0.0, n=0.0, wind=0.0):
    return T.Lags(psi=0.0, uv=0.0, r=0.0, mismatch_before=0.0, mismatch_after=0.0, runs=1, delta=delta, n=n, wind=wind)


def test_retime_moves_the_inputs_in_one_repair_line():
    lagged, clean = _run(5, 0.5, -0.3), _run(5, 0.0, 0.0)
    out = T.retime(lagged, _lags(0.5, -0.3))
    assert out.t[0] >= lagged.t[0] + 0.3 - 1e-9 and out.t[-1] <= lagged.t[-1] - 0.5 + 1e-9
    k0 = int(np.searchsorted(lagged.t, out.t[0] - 1e-9))
    sl = slice(k0, k0 + out.t.size)
    for c in ("delta", "n"):
        np.testing.assert_allclose(out[c], clean[c][sl], atol=2e-4)
    for c in ("u", "v", "r", "x"):
        np.testing.assert_array_equal(out[c], lagged[c][sl])
    (rep,) = out.meta["repairs"]
    assert rep["kind"] == "retimed" and "0.50 s" in rep["text"] and "rudder" in rep["text"] and "\n" not in rep["text"]


def test_retime_with_zero_input_offsets_is_the_state_retiming_bit_for_bit():
    tr = _run(6, 0.4, 0.2)
    state = T.Lags(psi=0.9, uv=0.6, r=0.9, mismatch_before=0.0, mismatch_after=0.0, runs=1)
    a = T.retime(tr, state)
    b = T.retime(tr, TI.with_inputs(state, TI.InputLags(delta=0.0, n=0.0, wind=0.0)))
    np.testing.assert_array_equal(a.t, b.t)
    for c in a.channels:
        np.testing.assert_array_equal(a[c], b[c])
    assert a.meta["repairs"] == b.meta["repairs"] and "rudder" not in a.meta["repairs"][0]["text"]
    np.testing.assert_array_equal(a["delta"], tr["delta"][: a.t.size])


def test_an_offset_on_the_grid_end_is_named():
    top = float(TI.GRID[-1])
    assert TI.at_bound(TI.InputLags(delta=0.8, n=-0.3, wind=top)) == ["wind"]
    assert TI.at_bound(TI.InputLags(delta=0.8, n=float(TI.GRID[0]), wind=0.2)) == ["propeller rate"]
    assert TI.at_bound(TI.InputLags(delta=0.8, n=-0.3, wind=1.5)) == []
    # a narrower grid passed in is the one checked
    assert TI.at_bound(TI.InputLags(delta=0.8, n=-0.3, wind=1.5), np.arange(-1.0, 1.51, 0.5)) == ["wind"]


def test_the_samples_left_out_at_each_end_cover_the_largest_offset_at_any_sample_rate():
    # a column shifted by tau is held constant over the last tau seconds; those samples, and the smoothing
    # window's half width, must lie in the part left out (at 10 Hz the filter margin already covers 3 s)
    for dt in (0.1, 0.05, 0.02):
        d = {"t": np.arange(0.0, 200.0, dt)}
        e = TI._edge(d, TI.GRID)
        assert e * dt >= float(np.max(np.abs(TI.GRID)))
        assert e >= TI._EDGE
    assert TI._edge({"t": np.arange(0.0, 200.0, 0.1)}, TI.GRID) == TI._EDGE
