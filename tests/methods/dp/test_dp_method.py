"""DP identification pipeline of Fossen, Sagatun & Sørensen (1996) §4.2–4.3 on simulated trials.

Truth: the paper's identified values (eqs. 48–49) with M'' (eq. 30) and T'' (eq. 29).
Noise (shipid.methods.dp.trials.TrialNoise defaults): position 0.5 m and heading 0.25°
(1σ, 1 Hz), white force noise q_h = 1e-8 and a drifting body-fixed bias (random walk
q_b = 1e-10 from an initial 3e-4 m g), bis units; yaw components with a 0.1 L lever.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from known.fossen1996 import THETA_EQ46_49

from shipid.methods.dp.estimator import DPOptions, fit_dp, identify_dp, run_stage
from shipid.methods.dp.series import with_series
from shipid.methods.dp.trials import DP_CHANNELS, simulate_dp_trial, simulate_dp_trials
from shipid.models import dp
from shipid.result import Result
from shipid.vessels import load_vessel


@pytest.fixture(scope="module")
def supply():
    return dp.dp_vessel(load_vessel("supply"))


@pytest.fixture(scope="module")
def short_run(supply):
    """Six 600-s trials (seed 0), identified, with the report series: the unmarked, fast version of the study."""
    trials = simulate_dp_trials(supply, 0, duration=600.0)
    fit = fit_dp(trials["surge"], trials["sway-yaw"], trials["azimuth"], supply, theta_true=supply.theta)
    # identify makes no report series: with the truth given, only the true-vs-estimated table
    assert set(fit.result.series) == {"tables"}
    return trials, with_series(fit)


def test_simulated_trials_have_the_cli_channels(short_run):
    trials, _ = short_run
    assert set(trials) == {"surge", "sway-yaw", "azimuth"}
    for kind, trs in trials.items():
        assert len(trs) == 2
        for tr in trs:
            assert set(DP_CHANNELS) <= set(tr.names)
            assert tr.duration == pytest.approx(600.0)
    # decoupled manoeuvres (§4.2): surge uses only the main propellers and the heading
    # thruster; sway-yaw only the tunnel thrusters; azimuth only thruster 6
    s = trials["surge"][0]
    assert np.all(s["p3"] == 0) and np.all(s["p6"] == 0) and np.any(s["p1"] != 0)
    y = trials["sway-yaw"][0]
    assert np.all(y["p1"] == 0) and np.all(y["p6"] == 0) and np.any(y["p3"] != 0)
    a = trials["azimuth"][0]
    assert np.all(a["p1"] == 0) and np.all(a["p5"] == 0) and np.ptp(a["alpha6"]) > 1.0
    assert s.meta["heading_control_saturated_fraction"] == 0.0


def test_pipeline_recovers_theta_within_3_sigma(short_run, supply):
    """|error| < 3σ for every θ; θ within 5 % where 600-s trials allow it.

    On 600-s trials the weak couplings θ3 (sway-yaw) and θ4 (yaw-sway) are not determined to
    5 %: for them the test asserts that the reported σ is CRLB-sized (large), not the 5 %.
    """
    _, res = short_run
    d = res.diagnostics
    assert d["converged"], d["warnings"]
    err_sigma = np.asarray(d["error_sigma"])
    rel = np.abs(np.asarray(d["relative_error"]))
    assert np.all(np.abs(err_sigma) < 3.0), err_sigma
    well = [0, 1, 4, 5, 6, 7, 8]  # θ1, θ2, θ5, θ6..θ9
    assert np.all(rel[well] < 0.05), rel
    std = np.array([res.std(n) for n in dp.THETA_NAMES])
    # honest uncertainty of the weak couplings: their relative σ is far above the others'
    rel_std = std / np.abs(supply.theta)
    assert rel_std[2] > 3 * np.max(rel_std[well]) and rel_std[3] > 0.02


def test_result_contents_and_json(short_run, supply):
    _, res = short_run
    d = json.loads(res.to_json())
    assert d["method"] == "dp"
    assert set(d["estimates"]) == set(dp.THETA_NAMES)
    for key in ("A_h", "K", "A", "B", "theta", "theta_std"):
        assert key in d["model"]
    A_h, K = dp.matrices_from_theta(np.asarray(d["model"]["theta"]))
    np.testing.assert_allclose(np.asarray(d["model"]["A"]), dp.derived_A(supply.M, A_h))
    np.testing.assert_allclose(np.asarray(d["model"]["B"]), dp.derived_B(supply.M, supply.T(), K))
    assert set(d["series"]["histories"]) == set(dp.THETA_NAMES)
    h = d["series"]["histories"]["theta2"]
    assert len(h["t"]) == len(h["value"]) == len(h["std"]) == 601
    assert h["true"] == pytest.approx(THETA_EQ46_49[1])              # eq. 48: A_h''[1, 1]
    back = Result.from_json(res.to_json())
    assert back.value("theta6") == res.value("theta6")
    # the covariance is a valid 9 x 9 covariance (considered parameters carry cross terms)
    C = np.asarray(d["covariance"])
    assert C.shape == (9, 9) and np.all(np.linalg.eigvalsh(C) > 0)
    np.testing.assert_allclose(np.sqrt(np.diag(C)), [res.std(n) for n in dp.THETA_NAMES])


def test_stage_freezes_earlier_parameters(short_run, supply):
    _, res = short_run
    st = res.diagnostics["stages"]
    assert st["SI1"]["considered"] == []
    assert st["SI2"]["considered"] == ["theta1", "theta6"]
    assert st["SI3"]["considered"] == [f"theta{i}" for i in range(1, 9)]


def test_parallel_two_trials_beat_one_trial_of_same_total_length(supply):
    """The paper's point (§3.2): N = 2 trials with *different excitation sequences* in parallel.

    SI2, seeded. Parallel: a 300-s "sway" trial (all tunnel thrusters pushing the same way)
    and a 300-s "yaw" trial (aft and bow thrusters opposed), processed together. Single: one
    600-s "sway" trial, the same total length with one excitation sequence. The single trial
    leaves the yaw side (θ4, θ5) poorly determined: its σ is more than twice the parallel
    one and its estimate does not settle. (With two equally rich random trials a single trial
    of double length does as well: the gain comes from the different excitation, which is
    what §3.2 asks for.) The parallel filter's errors are within 3σ for this seed; on such
    short single-signal trials that is not guaranteed (|error|/σ up to 4.6 was seen on
    another seed), which is why the pipeline tests use 600-s random trials.
    """
    opt = DPOptions()
    theta = np.array(opt.theta0)
    theta[[0, 5, 8]] = supply.theta[[0, 5, 8]]  # surge and azimuth as if found by SI1/SI3
    par = [simulate_dp_trial(supply, "sway-yaw", 300.0, 11, pattern="sway"),
           simulate_dp_trial(supply, "sway-yaw", 300.0, 12, pattern="yaw")]
    one = [simulate_dp_trial(supply, "sway-yaw", 600.0, 13, pattern="sway")]
    sp = run_stage("SI2", par, supply, theta, opt)
    so = run_stage("SI2", one, supply, theta, opt)
    true = supply.theta[list(sp.free)]  # θ2, θ3, θ4, θ5, θ7, θ8
    z_par = (sp.free_theta[-1] - true) / sp.free_std[-1]
    assert np.all(np.abs(z_par) < 3.0), z_par
    yaw = [2, 3]  # θ4, θ5 within the free vector
    assert np.all(so.free_std[-1, yaw] > 2.0 * sp.free_std[-1, yaw])
    assert not so.diagnostics["converged"]


def test_bad_input_is_one_line_error(supply):
    from shipid.errors import InputError
    from shipid.io.trial import Trial

    tr = Trial(np.arange(100.0), {"x": np.zeros(100), "y": np.zeros(100)})
    with pytest.raises(InputError, match="psi"):
        run_stage("SI1", [tr], supply, supply.theta)
    with pytest.raises(InputError, match="at least one"):
        run_stage("SI2", [], supply, supply.theta)


@pytest.mark.slow
def test_full_length_study(supply):
    """Full-length version: six 1200-s trials (seed 0)."""
    trials = simulate_dp_trials(supply, 0, duration=1200.0)
    res = identify_dp(trials["surge"], trials["sway-yaw"], trials["azimuth"], supply, theta_true=supply.theta)
    d = res.diagnostics
    assert d["converged"]
    assert np.all(np.abs(d["error_sigma"]) < 3.0)
    rel = np.abs(np.asarray(d["relative_error"]))
    assert np.all(rel[[0, 1, 4, 5, 6, 7, 8]] < 0.05)


def test_measurement_gaps_are_skipped_and_input_gaps_refused(supply):
    from shipid.errors import InputError

    tr = simulate_dp_trial(supply, "sway-yaw", 200.0, 31)
    x = tr["x"].copy()
    x[50:60] = np.nan
    psi = tr["psi"].copy()
    psi[0] = np.nan
    gappy = tr.with_channels(x=x, psi=psi)
    theta = supply.theta.copy()
    st = run_stage("SI2", [gappy], supply, theta, DPOptions(passes=1))
    assert np.all(np.isfinite(st.free_theta[-1]))
    assert np.isnan(st.ekf.nis[0][55]) and np.isfinite(st.ekf.nis[0][70])
    p3 = tr["p3"].copy()
    p3[7] = np.nan
    with pytest.raises(InputError, match="p3.*row 8"):
        run_stage("SI2", [tr.with_channels(p3=p3)], supply, theta)
