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
