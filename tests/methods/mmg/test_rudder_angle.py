"""Angle-dependent rudder terms at large angles (mmg.rudder_angle): folds that only extrapolate in angle,
the decision rule, batched replays with the new per-row particulars, calibration of a new term."""

import numpy as np
import pytest

from shipid.io import data_root
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import rudder_angle as RA
from shipid.methods.mmg import side_calibration as S
from shipid.methods.mmg import turning_selection as T
from shipid.methods.mmg.candidates import apply_candidate
from shipid.methods.mmg.extrapolation import replay
from shipid.models import mmg

ROOT = data_root()
FREE = {"X": ("R_0", "XP_gain", "XR_gain"), "Y": ("Y_v", "Y_r", "YR_gain"), "N": ("N_v", "N_r", "NR_arm")}


def test_every_fold_trains_below_and_scores_above_its_angle():
    sets = RA.fold_sets(RA.RUNS)
    ang = RA.rudder_angles(RA.RUNS)
    assert [f for f, _, _ in sets] == [f for f, _ in RA.FOLDS]
    for (_, top), (_, tr, te) in zip(RA.FOLDS, sets):
        assert tr and te and set(tr).isdisjoint(te) and len(tr) + len(te) == len(RA.RUNS)
        assert max(ang[i] for i in tr) <= top < min(ang[i] for i in te)
    assert sorted(round(ang[i]) for i in sets[0][1]) == [10, 10, 10, 10, 15, 15]
    assert "HSVA_CPMC_KVLCC2_Z_05_01.dat" not in RA.RUNS


def test_candidates_differ_from_the_default_only_in_the_rudder():
    C = RA.candidates()
    d = C["default"]
    assert not d.get(T.CALIBRATE) and "rudder_crossflow" not in (d.get("particulars") or {})
    for name, c in C.items():
        assert all(tuple(c[m]) == tuple(d[m]) for m in mmg.MODES), name
        par = c.get(T.CALIBRATE)
        assert par is None or par in RA.GRIDS, name


def _fold(scores):
    return {c: {"score": s} for c, s in scores.items()}


def test_decision_needs_the_lowest_mean_and_enough_folds_better_than_the_default():
    names = ["default", "a", "b"]
    folds = {"1": _fold({"default": 10, "a": 5, "b": 9.5}), "2": _fold({"default": 10, "a": 12, "b": 9.5}),
             "3": _fold({"default": 10, "a": 11, "b": 9.6})}
    d = RA.decide(folds, names)            # a: lowest mean (9.33) but better in 1 fold only
    assert d["best_mean"] == "a" and d["folds_better_than_default"]["a"] == 1 and d["chosen"] == "default"
    folds["3"]["a"]["score"] = 8.0         # now better in 2 of 3
    assert RA.decide(folds, names)["chosen"] == "a"
    folds = {k: _fold({"default": 1, "a": 2, "b": 3}) for k in "123"}
    assert RA.decide(folds, names)["chosen"] == "default"


@pytest.fixture(scope="module")
def setup(own_run):
    if ROOT is None or not (ROOT / "params").exists():
        pytest.skip("shared data not found (set SHIPID_DATA)")
    prior = mmg.load_published("kvlcc2_hsva")
    truth, _ = apply_candidate(prior, {m: () for m in mmg.MODES}
                               | {"particulars": {"gamma_R": "symmetric", "rudder_crossflow": 1.0,
                                                  "rudder_side_slope": -0.2}})
    spec = ((15.0, 40.0, "own_Z_15_05.dat"), (20.0, 50.0, "own_Z_20_05.dat"), (10.0, 36.0, "own_Z_10_05.dat"))
    trials = [own_run(truth, 90.0, rudder_deg=d, period=p, source=n) for d, p, n in spec]
    return prior, trials, [R.smooth_run(t) for t in trials]


def test_batch_replay_with_large_angle_terms_per_row_matches_each_replay(setup):
    prior, trials, runs = setup
    base = dict(FREE, particulars={"rudder_crossflow": 1.0})
    ms = [S.fit_candidate(runs, prior, S.with_asymmetry(base, v, p)) for p, v in
          (("rudder_side_slope", -0.2), ("rudder_stall_plus", np.deg2rad(15.0)), ("rudder_crossflow_side", -0.5))]
    ms.append(S.fit_candidate(runs, prior, base))
    rows = [(ms[0], 0), (ms[1], 1), (ms[2], 0), (ms[3], 2), (ms[1], 0)]
    got = T.batch_replay(rows, [T.replay_data(t) for t in trials])
    for (m, i), g in zip(rows, got):
        ref = replay(m, trials[i])
        for k, v in g.items():
            np.testing.assert_allclose(v, ref[k], rtol=1e-9, atol=1e-9)


@pytest.mark.slow
def test_calibration_of_a_new_term_is_that_of_side_calibration(setup):
    """The batched per-fold calibration gives the value of the reference (unbatched) calibration."""
    prior, trials, runs = setup
    names = [t.meta["source"] for t in trials]
    cand = dict(FREE, particulars={"gamma_R": "symmetric", "rudder_crossflow": 1.0}, calibrate="rudder_side_slope")
    data = [T.replay_data(t) for t in trials]
    c, a = RA.calibrated(cand, runs, data, T.peak_runs(trials), prior, [0, 1, 2])
    plain = {k: v for k, v in cand.items() if k != T.CALIBRATE}
    ref, table = S.calibrate(runs, trials, names, prior, plain, RA.SLOPE_GRID, parameter="rudder_side_slope")
    assert a == pytest.approx(ref, abs=1e-12) and np.isfinite(table[ref])
    assert c["particulars"]["rudder_side_slope"] == a and T.CALIBRATE not in c


def test_identify_with_the_chosen_candidate_calibrates_its_side_parameter_on_its_grid(setup):
    from shipid.methods.mmg import pipeline as P

    prior, trials, runs = setup
    cand = RA.candidates()[RA.CHOSEN]
    par = cand[T.CALIBRATE]
    res = P.identify(trials, prior, structure="c", candidates={"c": cand}, resolve=RA.resolve, refine="none")
    cal = res.diagnostics["calibration"]
    plain = {k: v for k, v in cand.items() if k != T.CALIBRATE}
    (a, table), = T.calibrate_folds(runs, [T.replay_data(t) for t in trials], T.peak_runs(trials), prior, plain,
                                    [[0, 1, 2]], grid=RA.GRIDS[par], parameter=par)
    assert cal["parameter"] == par and cal["value"] == a
    assert all(f"{g:g}" in cal["training_peak_score"] for g in RA.GRIDS[par])
    assert res.model["particulars"][par] == a and res.model["particulars"]["rudder_crossflow"] == 1.0


def test_cli_rudder_angle_selection_refuses_another_structure(capsys):
    """--selection rudder-angle with the Esso prior: one line naming the structure, exit 2, no traceback."""
    from shipid.cli import main

    rel = "esso_osaka_3m/data/zigzag/zigzag_31-Jul-2020_13_04_24.csv"
    if ROOT is None or not (ROOT / rel).exists():
        pytest.skip("shared data not found (set SHIPID_DATA)")
    rc = main(["identify", "mmg", "--trial", str(ROOT / rel), "--prior", "esso_osaka_3m",
               "--selection", "rudder-angle", "--json"])
    err = capsys.readouterr().err
    assert rc == 2 and "rudder-angle: for the structure 'yasukawa2015' only (not 'esso-lowspeed')" in err
    assert "Traceback" not in err


def test_study_command_prints_the_table_and_the_decision(monkeypatch, capsys):
    """``shipid study kvlcc2-rudder-angle`` formats what cross_validate returns (here a small stand-in)."""
    import json

    from shipid.cli import main

    rep = {"psi_rms": 2.0, "r_peak_stbd_err_pct": 1.0, "r_peak_port_err_pct": -3.0}
    row = {"calibrated": None, **RA.score_rows([rep]), "runs": {"HSVA_CPMC_KVLCC2_Z_35_05.dat": rep}}
    folds = {f: {"train": [], "scored": [], "default": dict(row), "cf": dict(row, score=1.0)} for f, _ in RA.FOLDS}
    fake = {"folds": folds, "decision": RA.decide(folds, ["default", "cf"])}
    monkeypatch.setattr(RA, "cross_validate", lambda progress=None: fake)
    assert main(["study", "kvlcc2-rudder-angle"]) == 0
    out = capsys.readouterr().out
    assert "chosen 'cf'" in out and "35_05 +1.0/-3.0 2.0" in out
    assert main(["study", "kvlcc2-rudder-angle", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["decision"]["chosen"] == "cf"


def test_heading_drift_is_zero_for_the_model_that_made_the_run(setup):
    prior, trials, _ = setup
    truth, _ = apply_candidate(prior, {m: () for m in mmg.MODES}
                               | {"particulars": {"gamma_R": "symmetric", "rudder_crossflow": 1.0,
                                                  "rudder_side_slope": -0.2}})
    d = RA.heading_drift(truth, trials[0])
    assert abs(d["r_mean_err_deg_s"]) < 1e-6 and abs(d["psi_end_err_deg"]) < 1e-4
