"""Yaw-balance CV of the KVLCC2 (methods.mmg.propeller_side, issue 19): the decision rule, the training score
and the Nomoto check of the neutral rudder angle on synthetic records with a known answer."""

import numpy as np
import pytest

from shipid.io.trial import Trial
from shipid.methods.mmg import propeller_side as PS


def nomoto_trial(delta_n, K=0.3, T=8.0, seed=7):
    """A zig-zag-like record of ``T ṙ + r = K (δ − δ_n)`` (Euler, 20 Hz) with a square-wave rudder."""
    rng = np.random.default_rng(seed)
    h = 0.05
    t = np.arange(0.0, 200.0, h)
    delta = np.where(t < 2.0, 0.0, np.deg2rad(15.0) * np.sign(np.sin(2 * np.pi * (t - 2.0) / 40.0) + 1e-12))
    r = np.zeros_like(t)
    for k in range(t.size - 1):
        r[k + 1] = r[k] + h * (K * (delta[k] - delta_n) - r[k]) / T
    r = r + 1e-5 * rng.standard_normal(t.size)
    psi = np.cumsum(r) * h
    ch = {"x": t, "y": 0 * t, "psi": psi, "u": 1.0 + 0 * t, "v": 0 * t, "r": r, "delta": delta, "n": 10.0 + 0 * t}
    return Trial(t, ch, {}, {})


@pytest.mark.parametrize("dn_deg", [-0.5, 0.0, 0.8])
def test_yaw_balance_recovers_the_neutral_angle_of_a_nomoto_ship(dn_deg):
    y = PS.yaw_balance(nomoto_trial(np.deg2rad(dn_deg)))
    assert y["delta_n_deg"] == pytest.approx(dn_deg, abs=0.05)
    assert 0.0 < y["delta_n_se_deg"] < 0.05


def folds(scores):
    return {f: {c: {"score": v[i]} for c, v in scores.items()} for i, f in enumerate(("a", "b", "c"))}


def test_decision_rule_keeps_the_current_choice_unless_a_new_candidate_wins_in_two_folds():
    cur = PS.CURRENT
    names = ["default", cur, "neutral-angle"]
    # lowest mean but better than the current choice in one fold only: the current choice stays
    d = PS.decide(folds({"default": [20, 20, 20], cur: [10, 10, 10], "neutral-angle": [2, 11, 11]}), names)
    assert d["best_mean"] == "neutral-angle" and d["chosen"] == cur
    assert d["folds_better_than_current"]["neutral-angle"] == 1
    # lower mean and better in two folds: it replaces the current choice
    d = PS.decide(folds({"default": [20, 20, 20], cur: [10, 10, 10], "neutral-angle": [9, 9, 11]}), names)
    assert d["chosen"] == "neutral-angle"
    assert d["fold_spread"]["neutral-angle"] == pytest.approx(np.std([9, 9, 11], ddof=1))
    # the default never replaces the current choice
    d = PS.decide(folds({"default": [1, 1, 1], cur: [10, 10, 10], "neutral-angle": [12, 12, 12]}), names)
    assert d["best_mean"] == "default" and d["chosen"] == cur


def test_training_score_is_peak_rms_of_used_runs_plus_heading_rms_of_all():
    rep = [{"r_peak_stbd_err_pct": 3.0, "r_peak_port_err_pct": -4.0, "psi_rms": 1.0},
           {"r_peak_stbd_err_pct": 100.0, "r_peak_port_err_pct": 100.0, "psi_rms": 7.0}]
    got = PS.training_score(rep, [True, False])
    assert got == pytest.approx(np.sqrt((9 + 16) / 2) + np.sqrt((1 + 49) / 2))
    rep[1]["psi_rms"] = float("inf")
    assert PS.training_score(rep, [True, False]) == float("inf")


def test_candidates_add_one_term_each_to_the_two_references():
    c = PS.candidates()
    assert set(c) == {"default", PS.CURRENT, "neutral-angle", PS.CURRENT + "/neutral-angle", "prop-side",
                      PS.CURRENT + "/prop-side"}
    for name, cand in c.items():
        assert cand.get(PS.SECOND) in (None, *PS.GRIDS)
    assert min(PS.PROP_SIDE_GRID) == 0.0                 # the right-handed rotation fixes the sign


def synthetic_replays(centres, grid=(-2.0, -1.0, 0.0, 1.0, 2.0)):
    """Per grid value, one replay per run whose heading RMS is smallest at that run's centre."""
    return {a: [{"r_peak_stbd_err_pct": 0.0, "r_peak_port_err_pct": 0.0, "psi_rms": 1.0 + (a - c) ** 2}
                for c in centres] for a in grid}


def test_bootstrap_se_is_zero_when_every_run_agrees_and_grows_with_their_disagreement():
    use = [True] * 8
    assert PS.bootstrap_se(synthetic_replays([0.3] * 8), use, resamples=50) == 0.0
    narrow = PS.bootstrap_se(synthetic_replays(0.3 + 0.1 * np.linspace(-1, 1, 8)), use, resamples=200)
    wide = PS.bootstrap_se(synthetic_replays(0.3 + 0.6 * np.linspace(-1, 1, 8)), use, resamples=200)
    assert 0.0 < narrow < wide
    again = PS.bootstrap_se(synthetic_replays(0.3 + 0.6 * np.linspace(-1, 1, 8)), use, resamples=200)
    assert again == wide                                  # seeded: same draws, same SE


def test_hsva_neutral_angle_is_small_up_to_25_deg_and_moves_to_starboard_at_30_and_35():
    from shipid.io import data_root
    from shipid.io.basins import read_kvlcc2
    from shipid.methods.mmg.rudder_angle import RUNS, rudder_angles

    root = data_root()
    if root is None or not (root / "kvlcc2_hsva").is_dir():
        pytest.skip("shared data (kvlcc2_hsva/) not found (set SHIPID_DATA)")
    bal = {n: PS.yaw_balance(read_kvlcc2(n)) for n in RUNS}
    for n, a in zip(RUNS, rudder_angles(RUNS)):
        y = bal[n]
        assert np.isfinite(y["delta_n_se_deg"]) and y["delta_n_se_deg"] < 0.2
        if a <= 25.0:
            assert abs(y["delta_n_deg"]) < 0.7
        else:
            assert y["delta_n_deg"] > 0.5


@pytest.mark.slow
def test_resolve_sets_both_calibrated_particulars_on_the_given_runs():
    from shipid.io import data_root
    from shipid.io.basins import read_kvlcc2
    from shipid.methods.mmg import estimator as R
    from shipid.models import mmg

    root = data_root()
    if root is None or not (root / "kvlcc2_hsva").is_dir():
        pytest.skip("shared data (kvlcc2_hsva/) not found (set SHIPID_DATA)")
    names = ["HSVA_CPMC_KVLCC2_Z_10_01.dat", "HSVA_CPMC_KVLCC2_Z_10_05.dat", "HSVA_CPMC_KVLCC2_Z_15_05.dat",
             "HSVA_CPMC_KVLCC2_Z_20_05.dat"]
    trials = [read_kvlcc2(n) for n in names]
    runs = [R.smooth_run(tr) for tr in trials]
    cand = PS.candidates()[PS.CURRENT + "/neutral-angle"]
    c, info = PS.resolve(trials, runs, mmg.load_published("kvlcc2_hsva"), cand)
    part = c["particulars"]
    assert part["rudder_crossflow_side"] == info["value"]
    sec = info["second"]
    assert sec["parameter"] == "rudder_neutral_angle" and part["rudder_neutral_angle"] == sec["value"]
    assert min(PS.NEUTRAL_GRID) <= sec["value"] <= max(PS.NEUTRAL_GRID)
    assert sec["status"] in ("calibrated", "not determined") and np.isfinite(sec["se"]) and sec["se"] >= 0
    assert PS.SECOND not in c and "calibrate" not in c
    assert min(sec["training_score"].values()) == pytest.approx(
        sec["training_score"][f"{sec['value']:.6g}"])
