"""Angle-dependent rudder terms at large angles (mmg.rudder_angle, ``identify mmg --selection rudder-angle``):
the candidates, batched replays with the new per-row particulars, calibration of the chosen candidate."""

import numpy as np
import pytest

from shipid.io import data_root
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import rudder_angle as RA
from shipid.methods.mmg import turning_selection as T
from shipid.methods.mmg.candidates import apply_candidate
from shipid.models import mmg

ROOT = data_root()
FREE = {"X": ("R_0", "XP_gain", "XR_gain"), "Y": ("Y_v", "Y_r", "YR_gain"), "N": ("N_v", "N_r", "NR_arm")}


def test_candidates_differ_from_the_default_only_in_the_rudder():
    C = RA.candidates()
    d = C["default"]
    assert not d.get(T.CALIBRATE) and "rudder_crossflow" not in (d.get("particulars") or {})
    for name, c in C.items():
        assert all(tuple(c[m]) == tuple(d[m]) for m in mmg.MODES), name
        par = c.get(T.CALIBRATE)
        assert par is None or par in RA.GRIDS, name


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


def test_batch_replay_with_large_angle_terms_per_row_matches_each_replay(setup, replay_ref):
    prior, trials, runs = setup
    base = dict(FREE, particulars={"rudder_crossflow": 1.0})
    ms = [T.fit_candidate(runs, prior, T.with_asymmetry(base, v, p)) for p, v in
          (("rudder_side_slope", -0.2), ("rudder_stall_plus", np.deg2rad(15.0)), ("rudder_crossflow_side", -0.5))]
    ms.append(T.fit_candidate(runs, prior, base))
    rows = [(ms[0], 0), (ms[1], 1), (ms[2], 0), (ms[3], 2), (ms[1], 0)]
    got = T.batch_replay(rows, [T.replay_data(t) for t in trials])
    for (m, i), g in zip(rows, got):
        ref = replay_ref(m, trials[i])
        for k, v in g.items():
            np.testing.assert_allclose(v, ref[k], rtol=1e-9, atol=1e-9)


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


# ----------------------------------------------------------------------------- selection for manoeuvres
@pytest.fixture(scope="module")
def ladder(own_run):
    """Five noise-free zig-zags of a truth with an angle-dependent side term, named as HSVA runs: 10°/1°
    (switch under 5°: trains, never scored) and 10°, 15°, 20°, 25° with switch 5°."""
    if ROOT is None or not (ROOT / "params").exists():
        pytest.skip("shared data not found (set SHIPID_DATA)")
    prior = mmg.load_published("kvlcc2_hsva")
    truth, _ = apply_candidate(prior, {m: () for m in mmg.MODES}
                               | {"particulars": {"gamma_R": "symmetric", "rudder_crossflow": 1.0,
                                                  "rudder_side_slope": -0.2}})
    spec = ((10.0, 20.0, "own_Z_10_01.dat"), (10.0, 36.0, "own_Z_10_05.dat"), (15.0, 40.0, "own_Z_15_05.dat"),
            (20.0, 50.0, "own_Z_20_05.dat"), (25.0, 56.0, "own_Z_25_05.dat"))
    trials = [own_run(truth, 80.0, rudder_deg=d, period=p, source=n) for d, p, n in spec]
    return prior, trials, [R.smooth_run(t) for t in trials]


def test_run_angles_from_the_name_else_from_the_largest_rudder(ladder):
    from dataclasses import replace as _r

    _, trials, _ = ladder
    assert RA.run_angles(trials[:2]) == [(10.0, 1.0), (10.0, 5.0)]
    anon = _r(trials[4], meta={"source": "run.csv"})
    assert RA.run_angles([anon]) == [(25.0, None)]


def test_forward_folds_cut_at_the_largest_angles_with_two_below(ladder):
    _, trials, _ = ladder
    folds, why = RA.forward_folds(trials)
    # scored angles 10, 15, 20, 25: cuts with >= 2 scored angles below are 20 and 25
    assert [(a, tr, sc) for a, tr, sc in folds] == [(20.0, [0, 1, 2], [3, 4]), (25.0, [0, 1, 2, 3], [4])]
    assert "4 rudder angle(s)" in why
    few, why = RA.forward_folds(trials[:3])          # 10 and 15 only: the guard fails
    assert few == [] and "needs 3" in why


def test_select_manoeuvres_applies_its_rule_to_its_fold_table(ladder):
    prior, trials, runs = ladder
    cands = RA.manoeuvre_candidates()
    chosen, table, method, rec = RA.select_manoeuvres(trials, runs, prior, cands)
    h = rec["horizon_choice"]
    from shipid.methods.mmg.candidates import CANDIDATES
    from shipid.methods.mmg.pipeline import select_structure

    assert h == select_structure(trials, runs, prior, CANDIDATES["yasukawa2015"])[0]
    assert set(table) == {h, h + RA.INTEGRAL, RA.RA_NAME, RA.RA_NAME + RA.INTEGRAL}
    assert [f["cut_deg"] for f in rec["folds"]] == [20.0, 25.0] and "2 folds" in method
    for c, row in table.items():
        fs = [f["rows"][c]["score"] for f in rec["folds"]]
        assert row["fold_scores"] == fs and row["score"] == pytest.approx(np.mean(fs))
        assert row["folds_better_than_H"] == sum(f["rows"][c]["score"] < f["rows"][h]["score"] for f in rec["folds"])
    assert all("calibrated" in f["rows"][RA.RA_NAME] for f in rec["folds"])
    best = min(table, key=lambda c: table[c]["score"])
    want = best if table[best]["folds_better_than_H"] >= 2 else h       # ceil(2 x 2 / 3) = 2
    assert chosen == want and rec["criterion"] == RA.CRITERION and rec["why"]


def test_select_manoeuvres_below_three_angles_is_the_horizon_selection(ladder):
    from shipid.methods.mmg.pipeline import select_structure
    from shipid.methods.mmg.candidates import CANDIDATES

    prior, trials, runs = ladder
    chosen, table, _, rec = RA.select_manoeuvres(trials[:3], runs[:3], prior, RA.manoeuvre_candidates())
    h, htable = select_structure(trials[:3], runs[:3], prior, CANDIDATES["yasukawa2015"])
    assert chosen == h and table == htable and "not run" in rec["note"]


def test_auto_is_manoeuvres_for_yasukawa_only_and_manoeuvres_refuses_another_structure(esso_published):
    from shipid.errors import InputError
    from shipid.methods.mmg import entry as E

    assert E.default_selection(mmg.load_published("kvlcc2_hsva")) == "manoeuvres"
    assert E.default_selection(esso_published) == "horizons"
    with pytest.raises(InputError, match="manoeuvres: for the structure 'yasukawa2015' only"):
        E._selection_kw("manoeuvres", esso_published, None)
    assert "H" not in RA.manoeuvre_candidates(equation_given=True)
    assert not any(k.endswith(RA.INTEGRAL) for k in RA.manoeuvre_candidates(equation_given=True))


@pytest.mark.slow
def test_default_identify_on_the_hsva_runs_records_the_forward_cv():
    """The 13 HSVA zig-zags through ``shipid.identify`` defaults: the forward CV ran (three cuts), its choice
    follows its rule, and the chosen row's calibrated parameter is recorded (about a minute)."""
    import shipid

    d = None if ROOT is None else ROOT / "kvlcc2_hsva"
    if d is None or not d.is_dir():
        pytest.skip("shared data (kvlcc2_hsva/) not found (set SHIPID_DATA)")
    res = shipid.identify("mmg", sorted(str(p) for p in d.glob("*.dat")))
    sel = res.diagnostics["structure_selection"]
    assert sel["criterion"] == RA.CRITERION and [f["cut_deg"] for f in sel["folds"]] == [25.0, 30.0, 35.0]
    t, h = sel["table"], sel["horizon_choice"]
    best = min(t, key=lambda c: t[c]["score"])
    assert sel["chosen"] == (best if t[best]["folds_better_than_H"] >= 2 else h)
    assert res.model["structure_candidate"] == sel["chosen"]
