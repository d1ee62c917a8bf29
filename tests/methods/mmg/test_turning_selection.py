"""KVLCC2 selection on what a turning circle measures: candidates, batched replays, per-fold calibration,
zig-zag names and the calibration helpers (shipid.methods.mmg.turning_selection)."""

import numpy as np
import pytest

from shipid.io import data_root
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import turning_selection as T
from shipid.methods.mmg.candidates import CANDIDATES, apply_candidate
from shipid.models import mmg

ROOT = data_root()
FREE = {"X": ("R_0", "XP_gain", "XR_gain"), "Y": ("Y_v", "Y_r", "YR_gain"), "N": ("N_v", "N_r", "NR_arm")}
CAL = dict(FREE, particulars={"rudder_crossflow": 1.0}, calibrate="rudder_side_gain")


@pytest.fixture(scope="module")
def setup(own_run):
    if ROOT is None or not (ROOT / "params").exists():
        pytest.skip("shared data not found (set SHIPID_DATA)")
    prior = mmg.load_published("kvlcc2_hsva")
    truth, _ = apply_candidate(prior, {m: () for m in mmg.MODES}
                               | {"particulars": {"gamma_R": "symmetric", "rudder_crossflow": 1.0,
                                                  "rudder_side_gain": 0.05}})
    spec = ((15.0, 40.0, "own_Z_15_05.dat"), (20.0, 50.0, "own_Z_20_05.dat"), (10.0, 36.0, "own_Z_10_05.dat"),
            (10.0, 30.0, "own_Z_10_01.dat"))
    trials = [own_run(truth, 90.0, rudder_deg=d, period=p, source=n) for d, p, n in spec]
    runs = [R.smooth_run(t) for t in trials]
    return prior, trials, runs


def test_turning_list_extends_the_candidate_list():
    C = T.TURNING_CANDIDATES["yasukawa2015"]
    assert list(C)[:6] == list(CANDIDATES["yasukawa2015"]) and len(C) == 15
    cal = [c for c in C if C[c].get(T.CALIBRATE)]
    assert len(cal) == 3 and all(C[c]["particulars"]["rudder_crossflow"] == 1.0 for c in cal)
    assert all(C[c]["particulars"]["gamma_R"] == "symmetric" for c in cal)


def test_zigzag_angles_from_names():
    assert np.degrees(T.zigzag_angles("HSVA_CPMC_KVLCC2_Z_20_10_P.dat")) == pytest.approx((20, 10))
    assert np.degrees(T.zigzag_angles("HSVA_CPMC_KVLCC2_Z_35_05.dat")) == pytest.approx((35, 5))
    with pytest.raises(Exception, match="cannot read the zig-zag angles"):
        T.zigzag_angles("turn.csv")


def test_refine_minimum_is_the_vertex_of_the_parabola_clipped_to_the_span():
    assert T.refine_minimum([0.0, 1.0, 2.0], [(x - 1.3) ** 2 for x in (0.0, 1.0, 2.0)]) == pytest.approx(1.3)
    assert T.refine_minimum([0.0, 1.0, 2.0], [1.0, 1.0, 1.0]) == 1.0          # flat: the middle point
    assert T.refine_minimum([0.0, 1.0, 2.0], [(x - 5.0) ** 2 for x in (0.0, 1.0, 2.0)]) == 2.0


def test_batch_replay_matches_the_replay_of_each_row(setup, replay_ref):
    prior, trials, runs = setup
    m1 = T.fit_candidate(runs, prior, T.with_asymmetry(CAL, -0.05, "rudder_side_gain"))
    m2 = T.fit_candidate(runs, prior, T.with_asymmetry(CAL, 0.1, "rudder_side_gain"))
    m3 = T.fit_candidate(runs, prior, dict(FREE))
    rows = [(m1, 0), (m2, 1), (m3, 1), (m1, 2)]
    got = T.batch_replay(rows, [T.replay_data(t) for t in trials])
    for (m, i), g in zip(rows, got):
        ref = replay_ref(m, trials[i])
        for k, v in g.items():
            np.testing.assert_allclose(v, ref[k], rtol=1e-9, atol=1e-9)


def _calibrate_ref(runs, trials, prior, cand, grid, parameter, replay_ref):
    """The reference calibration: each value's model fitted and every run with switch >= 5 deg replayed one at
    a time; the grid's best, then the parabola's vertex through it and its neighbours, kept if lower."""
    use = T.peak_runs(trials)

    def score(a):
        m = T.fit_candidate(runs, prior, T.with_asymmetry(cand, a, parameter))
        e = np.array([replay_ref(m, tr)[f"r_peak_{s}_err_pct"] for tr, u in zip(trials, use) if u
                      for s in ("stbd", "port")], float)
        return float(np.sqrt(np.mean(e ** 2)))

    table = {float(a): score(a) for a in grid}
    best = min(table, key=lambda a: table[a])
    g = sorted(table)
    i = g.index(best)
    if 0 < i < len(g) - 1:
        a = T.refine_minimum(g[i - 1:i + 2], [table[g[j]] ** 2 for j in (i - 1, i, i + 1)])
        table[a] = score(a)
        best = a if table[a] < table[best] else best
    return best, table


def test_calibrate_folds_is_the_reference_calibration(setup, replay_ref):
    prior, trials, runs = setup
    idx = [0, 1, 3]
    a_ref, tab_ref = _calibrate_ref([runs[i] for i in idx], [trials[i] for i in idx], prior, CAL,
                                    T.SIDE_GAIN_GRID, "rudder_side_gain", replay_ref)
    (a, tab), = T.calibrate_folds(runs, [T.replay_data(t) for t in trials], T.peak_runs(trials), prior, CAL, [idx])
    assert a == pytest.approx(a_ref, abs=1e-9)
    # the grid points are the same numbers; the parabola's vertex (a key computed from the scores) agrees to
    # round-off only, as the scores do (the two paths sum the same terms in a different order)
    ka, kb = sorted(tab), sorted(tab_ref)
    assert len(ka) == len(kb) and ka == pytest.approx(kb, abs=1e-12)
    for k, kr in zip(ka, kb):
        assert tab[k] == pytest.approx(tab_ref[kr], rel=1e-9)
    assert T.peak_runs(trials) == [True, True, True, False]


def test_selection_and_calibration_read_only_training_runs(setup, monkeypatch):
    """Spy: every model is fitted on a fold's training runs; a calibration replays only the runs its models
    were fitted on; a left-out run is replayed only by models fitted without it, whose side gain is the one
    calibrated on that fold's training runs."""
    prior, trials, runs = setup
    fitted, replayed, calibrated = {}, [], []
    fit0, rep0, cal0 = T._fit, T.batch_replay, T.calibrate_folds

    def spy_fit(rs, *a, **k):
        m = fit0(rs, *a, **k)
        fitted[id(m)] = (m, frozenset(next(i for i, r in enumerate(runs) if r is x) for x in rs))
        return m

    def spy_rep(rows, data):
        replayed.extend((id(m), i) for m, i in rows)
        return rep0(rows, data)

    def spy_cal(rs, data, use, pr, cand, sets, **k):
        out = cal0(rs, data, use, pr, cand, sets, **k)
        calibrated.extend(zip(map(frozenset, sets), (o[0] for o in out)))
        return out

    monkeypatch.setattr(T, "_fit", spy_fit)
    monkeypatch.setattr(T, "batch_replay", spy_rep)
    monkeypatch.setattr(T, "calibrate_folds", spy_cal)
    cands = {"plain": dict(FREE), "calibrated": CAL}
    best, table, _ = T.select_for_turning(trials, runs, prior, cands, folds=None)
    n = len(runs)
    folds = {frozenset(set(range(n)) - {i}) for i in range(n)}
    assert {fs for _, fs in fitted.values()} <= folds
    assert {fs for fs, _ in calibrated} == folds
    gain = dict(calibrated)
    tests = 0
    for mid, i in replayed:
        m, fs = fitted[mid]
        if i in fs:
            continue                                   # a calibration replay: a run the model was fitted on
        tests += 1
        assert fs == frozenset(set(range(n)) - {i})    # the left-out run, by the fold's own model
        if "rudder_side_gain" in m.particulars:
            assert m.particulars["rudder_side_gain"] == gain[fs]
    assert tests == 2 * sum(T.peak_runs(trials))
    assert best in cands and np.isfinite(table[best]["score"])
    assert len(table["calibrated"]["calibrated_per_fold"]["rudder_side_gain"]) == n


def test_identify_fits_a_calibrated_candidate_with_the_gain_calibrated_on_its_runs(setup):
    from shipid.methods.mmg import pipeline as P

    prior, trials, runs = setup
    res = P.identify(trials[:3], prior, structure="cal", candidates={"cal": CAL}, resolve=T.resolve, refine="none")
    cal = res.diagnostics["calibration"]
    (a, _), = T.calibrate_folds(runs[:3], [T.replay_data(t) for t in trials[:3]], T.peak_runs(trials[:3]), prior,
                                CAL, [[0, 1, 2]])
    assert cal["parameter"] == "rudder_side_gain" and cal["value"] == a
    assert res.model["particulars"]["rudder_side_gain"] == a
    assert res.model["particular_overrides"]["rudder_side_gain"] == a
    assert res.model["particulars"]["rudder_crossflow"] == 1.0


@pytest.mark.parametrize("selection", ["turning", "turning-auto"])
def test_cli_turning_selection_refuses_a_structure_without_turning_candidates(selection, capsys):
    """--selection turning / turning-auto with the Esso prior: one line naming the structure, exit 2, no traceback."""
    from shipid.cli import main

    rel = "esso_osaka_3m/data/zigzag/zigzag_31-Jul-2020_13_04_24.csv"
    if ROOT is None or not (ROOT / rel).exists():
        pytest.skip("shared data not found (set SHIPID_DATA)")
    rc = main(["identify", "mmg", "--trial", str(ROOT / rel), "--trial", str(ROOT / rel), "--prior", "esso_osaka_3m",
               "--selection", selection, "--json"])
    err = capsys.readouterr().err
    assert rc == 2 and f"{selection}: no turning candidates for the structure 'esso-lowspeed'" in err
    assert "Traceback" not in err


def test_criteria_scores(setup):
    """'peak': the pooled peak-yaw-rate RMS; 'peak+heading': that plus the pooled heading RMS; same table else."""
    prior, trials, runs = setup
    cands = {"plain": dict(FREE), "sym": dict(FREE, particulars={"gamma_R": "symmetric"})}
    _, a, m1 = T.select_for_turning(trials, runs, prior, cands)
    _, b, m2 = T.select_for_turning(trials, runs, prior, cands, criterion="peak+heading")
    for c in cands:
        assert a[c]["score"] == a[c]["r_peak_rms"] and b[c]["score"] == b[c]["r_peak_rms"] + b[c]["psi_rms"]
        assert a[c]["psi_rms"] == b[c]["psi_rms"] > 0
    assert "heading" not in m1 and "heading RMS" in m2
    with pytest.raises(Exception, match="unknown selection criterion"):
        T.select_for_turning(trials, runs, prior, cands, criterion="psi")
