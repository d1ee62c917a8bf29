"""DP trials at a logger's rate: block-mean decimation, undetermined noise levels profiled, the hard regime."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from shipid.io.trial import Trial
from shipid.methods.dp import pem
from shipid.methods.dp.coverage import HARD_DURATION_S, HARD_RATE_HZ, HARD_SCALES, hard_draw, hard_noise
from shipid.methods.dp.estimator import DPOptions, run_stage
from shipid.methods.dp.stage_models import decimate, prepare
from shipid.methods.dp.trials import TrialNoise, simulate_dp_trial
from shipid.models.dp import dp_vessel
from shipid.vessels import load_vessel

V = dp_vessel(load_vessel("supply"))


def test_block_means_keep_white_noise_white_and_the_mean_thrust_exact():
    """Block means of q samples: noise variance σ²/q, lag-1 correlation ≈ 0; ∫u dt over each step exact."""
    rng = np.random.default_rng(0)
    n, q = 40000, 10
    t = np.arange(n) * 0.1
    Z = rng.normal(scale=0.5, size=(n, 3))
    U = np.column_stack([rng.uniform(-1, 1, size=(n, 6)), rng.uniform(-np.pi, np.pi, n)])
    tb, Zb, Ub = decimate(t, Z, U, q)
    assert tb.size == n // q and np.allclose(np.diff(tb), 1.0)
    var = Zb.var(axis=0)
    assert np.all(np.abs(var / (0.25 / q) - 1.0) < 0.06)
    r1 = np.mean(Zb[1:, 0] * Zb[:-1, 0]) / var[0]
    assert abs(r1) < 0.05
    # exact mean of the held inputs over the step [tb_k, tb_k+1): u1..u5 and u6 (cos α, sin α)
    k = 7
    sel = (t >= tb[k] - 1e-12) & (t < tb[k + 1] - 1e-12)
    w = np.minimum(t[sel] + 0.1, tb[k + 1]) - t[sel]
    i0 = np.flatnonzero(sel)[0] - 1          # the sample held at tb_k
    w0 = t[i0 + 1] - tb[k]
    mean = (np.sum(U[sel, :5] * w[:, None], axis=0) + U[i0, :5] * w0) / (tb[k + 1] - tb[k])
    assert np.allclose(Ub[k, :5], mean, atol=1e-12)
    c = (np.sum(U[sel, 5] * np.cos(U[sel, 6]) * w) + U[i0, 5] * np.cos(U[i0, 6]) * w0) / (tb[k + 1] - tb[k])
    assert Ub[k, 5] * np.cos(Ub[k, 6]) == pytest.approx(c, abs=1e-12)


def test_prepare_decimates_a_fast_trial_and_keeps_a_1hz_one():
    tr10 = simulate_dp_trial(V, "sway-yaw", 120.0, 1, dt=0.1)
    d10 = prepare(tr10, V, "sway-yaw", 1.0)
    assert d10["decimated"][0] == 10 and d10["t"].size == 121
    tr1 = simulate_dp_trial(V, "sway-yaw", 120.0, 1, dt=1.0)
    d1 = prepare(tr1, V, "sway-yaw", 1.0)
    assert d1["decimated"] is None and d1["t"].size == 121
    assert prepare(tr10, V, "sway-yaw", None)["t"].size == 1201


def test_gaps_in_the_fixes_survive_decimation():
    tr = simulate_dp_trial(V, "azimuth", 120.0, 2, dt=0.2)
    ch = {k: np.array(tr[k], dtype=float) for k in tr.channels}
    for k in ("x", "y", "psi"):
        ch[k][50:80] = np.nan                  # 6 s without fixes: one whole block and parts of two
    d = prepare(Trial(tr.t, ch, meta=dict(tr.meta)), V, "azimuth", 1.0)
    missing = ~np.all(np.isfinite(d["Z"]), axis=1)
    assert missing.sum() >= 4 and np.all(np.isfinite(d["U"]))


def test_hard_draws_lie_in_their_ranges():
    rng = np.random.default_rng(5)
    ds = [hard_draw(rng) for _ in range(200)]
    for k in ("s_m", "s_p", "s_b", "s_b0"):
        v = np.array([d[k] for d in ds])
        assert v.min() >= HARD_SCALES[0] and v.max() <= HARD_SCALES[1]
        assert np.median(np.log(v)) == pytest.approx(0.5 * np.log(HARD_SCALES[0] * HARD_SCALES[1]), abs=0.3)
    r = np.array([d["rate_hz"] for d in ds])
    L = np.array([d["duration_s"] for d in ds])
    assert HARD_RATE_HZ[0] <= r.min() and r.max() <= HARD_RATE_HZ[1]
    assert HARD_DURATION_S[0] <= L.min() and L.max() <= HARD_DURATION_S[1]
    nz = hard_noise(ds[0])
    assert nz.q_b == pytest.approx(1e-10 * ds[0]["s_b"] ** 2) and nz.bias_tau is None


@pytest.fixture(scope="module")
def surge_no_drift():
    """Two 10-Hz surge trials without process noise or bias drift: q_h and q_b are not determined."""
    noise = TrialNoise(q_h=0.0, q_b=0.0, b0=1e-4)
    return [simulate_dp_trial(V, "surge", 600.0, 30 + j, dt=0.1, noise=noise) for j in range(2)]


def test_undetermined_noise_is_profiled_and_widens_the_std(surge_no_drift, monkeypatch):
    """SI1 at 10 Hz: converged, θ within 3 std; q_b profiled over its interval; the std never shrinks."""
    th = np.array(DPOptions().theta0)
    th[8] = V.theta[8]
    st = run_stage("SI1", surge_no_drift, V, th, DPOptions())
    d = st.diagnostics
    assert d["converged"] and all(x["factor"] == 10 for x in d["decimated"])
    free = list(st.free)
    z = (st.theta_full[free] - V.theta[free]) / np.sqrt(np.diag(st.theta_cov)[free])
    assert np.all(np.abs(z) < 3.0), z
    prof = d["pem"]["noise_profiles"]
    assert set(prof) >= {"q_b"}
    for p in prof.values():
        assert p["log_scale_interval"][0] <= p["grid_inside"][0] <= p["grid_inside"][1] <= p["log_scale_interval"][1]
        assert sum(p["weights"]) == pytest.approx(1.0)
    assert not d["noise"]["q_b"]["determined"] and "allowed_scale_vs_nominal" in d["noise"]["q_b"]
    monkeypatch.setattr(pem, "PROFILE_MAX_STEPS", 0)   # no profile: the noise level held at its optimum
    held = run_stage("SI1", surge_no_drift, V, th, DPOptions())
    assert np.all(np.diag(st.theta_cov)[free] >= np.diag(held.theta_cov)[free] * (1 - 1e-9))


@pytest.mark.slow
def test_hard_regime_campaign_covers():
    """8 hard-regime realisations (seed 7, never used to choose anything): pooled ±2 std ≥ 0.85."""
    from shipid.campaign.engine import run_campaign
    from shipid.methods.dp.coverage import summarise

    res = run_campaign("shipid.methods.dp.coverage:run_one", 8, seed=7, workers=2, progress=False,
                       kwargs={"regime": "hard"})
    s = summarise(res.outputs)
    assert s["ok"] == 8
    assert s["pooled"]["cover_2sd"] >= 0.85
    assert 0.6 <= s["pooled"]["rms_error_over_std"] <= 1.5


def test_the_cli_default_trials_identify():
    """One path: the six trials `shipid simulate supply dp-* --noise` makes (10 Hz, 600 s, seeds 1, 2), then
    ``shipid.identify("dp", ...)``: converged, every θ within 3 std of the truth, one data-repair line."""
    import shipid

    trials = {k: [shipid.simulate("supply", f"dp-{k}", noise=True, seed=s) for s in (1, 2)]
              for k in ("surge", "sway-yaw", "azimuth")}
    assert np.median(np.diff(trials["surge"][0].t)) == pytest.approx(0.1)
    res = shipid.identify("dp", trials, vessel="supply")
    assert res.diagnostics["converged"]
    z = [(res.estimates[f"theta{i + 1}"].value - V.theta[i]) / res.estimates[f"theta{i + 1}"].std for i in range(9)]
    assert np.all(np.abs(z) < 3.0), z
    rep = [w for w in res.diagnostics["warnings"] if w.startswith("data repaired")]
    assert len(rep) == 1 and "10 Hz" in rep[0]
