"""Standard manoeuvres of identified MMG models: conditions, the batched simulator, ``shipid simulate MODEL.json``."""

import json

import numpy as np
import pytest

from shipid.cli import main
from shipid.io import data_root, read_trial
from shipid.io.trial import Trial
from shipid.errors import InputError
from shipid.methods.mmg import manoeuvres as MM
from shipid.models import mmg
from shipid.simulate.manoeuvres import run_manoeuvre
from shipid.simulate.metrics import turning_metrics, zigzag_metrics

ROOT = data_root()


def need_params():
    if ROOT is None or not (ROOT / "params").is_dir():
        pytest.skip("shared data (params/) not found (set SHIPID_DATA)")


@pytest.fixture(scope="module")
def kv():
    need_params()
    return mmg.load_published("kvlcc2_hsva")


def test_equilibrium_speed_and_rps_are_inverse_and_hold_the_speed(kv):
    u = MM.equilibrium_speed(kv, 10.23)
    assert 0.8 < u < 1.6                                   # the HSVA tests ran 1.179 m/s at 10.23 rev/s
    assert MM.equilibrium_rps(kv, u) == pytest.approx(10.23, rel=1e-8)
    assert abs(MM.straight_du(kv, u, 10.23)) < 1e-9


def test_training_conditions_from_constructed_runs():
    t = np.arange(0.0, 20.0, 0.1)
    d = np.deg2rad(10.0) * np.clip((t - 5.0) / 2.0, 0.0, 1.0)      # 5 deg/s ramp
    n1 = np.where(t < 10, 8.0, -4.0)
    runs = [Trial(t, {"delta": d, "n": n1, "u": np.full(t.size, 0.4)}, {}, {}),
            Trial(t, {"delta": -d, "n": np.full(t.size, 12.0), "u": np.full(t.size, 0.6)}, {}, {})]
    tc = MM.training_conditions(runs)
    assert tc["rps_ahead"] == pytest.approx(np.median(np.r_[n1[n1 > 0], np.full(t.size, 12.0)]))
    assert tc["rps_astern"] == -4.0
    assert np.degrees(tc["rudder_rate"]) == pytest.approx(5.0, rel=1e-9)    # two 10-deg moves in 2 s
    assert tc["rps_rate"] is None                                    # one jump: fewer than 5 moving samples
    assert tc["runs"] == 2
    assert tc["water_depth"] is None and tc["water_depth_runs"] == 0
    runs[0].meta["water_depth"] = 6.0
    tc = MM.training_conditions(runs)
    assert tc["water_depth"] == 6.0 and tc["water_depth_runs"] == 1


def test_depth_classes_and_the_depth_check():
    """PIANC / ITTC classes by h/T; a prediction outside the training runs' class is one warning line."""
    assert [MM.depth_class(x) for x in (13.2, 3.01, 3.0, 1.6, 1.5, 1.3, 1.2, 1.1)] == \
        ["deep", "deep", "medium deep", "medium deep", "shallow", "shallow", "very shallow", "very shallow"]
    T = 0.455
    notes, warns = MM.depth_check(T, 6.0, None)                        # at the training depth
    assert warns == [] and notes == ["water depth 6 m (h/T 13.2, deep water; training runs 6 m)"]
    notes, warns = MM.depth_check(T, 6.0, 2.0)                         # another deep-water depth: same class
    assert warns == [] and "h/T 4.4" in notes[0]
    notes, warns = MM.depth_check(T, 6.0, 0.6)
    assert notes == [] and len(warns) == 1 and "h/T 1.32, shallow water" in warns[0] and "deep)" in warns[0]
    notes, warns = MM.depth_check(T, None, 0.8)                        # training depth unknown, not deep
    assert len(warns) == 1 and "not recorded" in warns[0] and "medium deep" in warns[0]
    notes, warns = MM.depth_check(T, None, 5.0)
    assert warns == [] and "deep water" in notes[0]
    assert MM.depth_check(T, None, None) == ([], [])
    with pytest.raises(InputError, match="must exceed the model's draught"):
        MM.depth_check(T, 6.0, 0.4)


def test_imo_and_simulate_say_when_the_depth_is_outside_the_training_runs(tmp_path, kv, capsys):
    from shipid.methods.mmg import imo as I

    model = {"method": "mmg-ebm", "model": dict(kv.to_dict(), training_conditions={
        "rps_ahead": 10.23, "rudder_rate": float(np.deg2rad(15.0)), "runs": 13, "rps_astern": None,
        "water_depth": 6.0, "water_depth_runs": 13})}
    rep = I.assess(model, samples=0)
    assert rep["warnings"] == [] and rep["conditions"]["water_depth"] == 6.0
    rep = I.assess(model, samples=0, water_depth=0.6)
    assert rep["conditions"]["water_depth"] == 0.6
    assert sum("not the depth class of the training runs" in w for w in rep["warnings"]) == 1
    mj = tmp_path / "MODEL.json"
    mj.write_text(json.dumps(model))
    out = tmp_path / "t.csv"
    capsys.readouterr()
    assert main(["simulate", str(mj), "turning-35", "--out", str(out), "--duration", "60", "--water-depth", "0.6"]) == 0
    assert capsys.readouterr().err.count("not the depth class of the training runs") == 1
    assert main(["--strict", "simulate", str(mj), "turning-35", "--out", str(out), "--force", "--duration", "60",
                 "--water-depth", "0.6"]) == 3
    assert main(["simulate", "esso-osaka", "zigzag-20", "--out", str(tmp_path / "z.csv"), "--water-depth", "3"]) == 2
    # imo: its warnings are 'shipid: warning:' lines counted by shipid --strict
    capsys.readouterr()
    assert main(["--strict", "imo", str(mj), "--samples", "0", "--water-depth", "0.6"]) == 3
    assert capsys.readouterr().err.count("shipid: warning: water depth 0.6 m") == 1
    assert main(["imo", str(mj), "--samples", "0"]) == 0
    assert main(["identify", "mmg", "--trial", str(out), "--water-depth", "-1"]) == 2
    assert "water depth must be positive" in capsys.readouterr().err
    # validate: a run that records its depth is checked against the model's training depth
    from shipid.io import write_trial

    tr = read_trial(out)
    for depth, lines in ((6.0, 0), (0.6, 1)):
        tr.meta["water_depth"] = depth
        pq = tmp_path / f"run_{depth:g}.parquet"
        write_trial(tr, pq)
        capsys.readouterr()
        assert main(["validate", str(mj), "--trial", str(pq)]) == 0
        assert capsys.readouterr().err.count("not the depth class of the training runs") == lines


def test_rudder_move_rates_ignore_quantisation_and_drift():
    t = np.arange(0.0, 30.0, 0.1)
    q = np.deg2rad(0.56)
    d = q * np.round(np.deg2rad(2.0) * np.sin(t) / q)          # a quantised 2-deg wobble: no large move
    d[150:] += np.deg2rad(20.0) * np.clip((t[150:] - 15.0) / 1.0, 0, 1)     # one 20-deg move at 20 deg/s
    r = MM.rudder_move_rates(d, t)
    assert r.size == 1 and np.degrees(r[0]) == pytest.approx(20.0, rel=0.15)


def test_conditions_need_speed_or_rps_without_training_data(kv):
    with pytest.raises(InputError, match="--speed or --rps"):
        MM.resolve_conditions(kv, {"model": kv.to_dict()})
    c = MM.resolve_conditions(kv, {"model": kv.to_dict()}, rps=10.23, rudder_rate_deg_s=15.0)
    assert c.speed == pytest.approx(MM.equilibrium_speed(kv, 10.23))
    assert np.degrees(c.rudder_rate) == pytest.approx(15.0)
    d = {"model": dict(kv.to_dict(), training_conditions={"rps_ahead": 9.0, "rudder_rate": 0.2, "runs": 3})}
    c = MM.resolve_conditions(kv, d)
    assert c.rps == 9.0 and c.rudder_rate == 0.2 and "median ahead rate of the 3 training runs" in c.notes[0]


def test_theta_rows_sets_only_the_named_coefficients(kv):
    Th = MM.theta_rows(kv, ["N_r", "Y_v"], np.array([[1.0, 2.0], [3.0, 4.0]]))
    iN = mmg.COEFS[kv.structure]["N"].index("N_r")
    iY = mmg.COEFS[kv.structure]["Y"].index("Y_v")
    np.testing.assert_array_equal(Th["N"][:, iN], [1.0, 3.0])
    np.testing.assert_array_equal(Th["Y"][:, iY], [2.0, 4.0])
    np.testing.assert_array_equal(np.delete(Th["N"][1], iN), np.delete(kv.theta("N"), iN))
    np.testing.assert_array_equal(Th["X"][0], kv.theta("X"))


def test_batched_simulator_agrees_with_run_manoeuvre(kv):
    """One row of the batch is the generic simulator's turning circle / zig-zag, to round-off, and
    a batch of two different coefficient vectors equals the two simulated alone."""
    cond = MM.Conditions(speed=MM.equilibrium_speed(kv, 10.23), rps=10.23, rudder_rate=np.deg2rad(15.0))
    sm = MM.ship_model(kv, cond)
    dur = 120.0
    for name, order, psw, side in (("turning-35-port", 35.0, np.inf, -1), ("zigzag-10", 10.0, 10.0, 1)):
        ref = run_manoeuvre(sm, name, duration=dur, dt=0.1, speed=cond.speed)
        rec = MM.simulate_rudder_batch(kv, MM.theta_rows(kv), [np.deg2rad(order)], [np.deg2rad(psw)], [side],
                                       cond, dt=0.1, t_max=dur, until_heading=np.inf, until_reversals=99)
        assert rec.t.size == ref.t.size
        for j, c in enumerate(mmg.STATE_NAMES):
            np.testing.assert_allclose(rec.x[0, :, j], ref[c], rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(rec.delta[0], ref["delta"], atol=1e-12)
        np.testing.assert_allclose(rec.delta_cmd[0], ref["delta_cmd"], atol=1e-12)
    other = kv.with_coef({"N_r": 1.3 * kv.coef["N_r"]})
    names = ["N_r"]
    rec2 = MM.simulate_rudder_batch(kv, MM.theta_rows(kv, names, [[kv.coef["N_r"]], [other.coef["N_r"]]]),
                                    np.deg2rad([20, 20]), np.deg2rad([20, 20]), [1, 1], cond, t_max=80.0,
                                    until_reversals=99)
    alone = MM.simulate_rudder_batch(other, MM.theta_rows(other), np.deg2rad([20]), np.deg2rad([20]), [1], cond,
                                     t_max=80.0, until_reversals=99)
    np.testing.assert_allclose(rec2.x[1], alone.x[0], rtol=1e-12, atol=1e-12)
    assert np.abs(rec2.x[0, :, 2] - rec2.x[1, :, 2]).max() > np.deg2rad(1.0)


def test_batch_stops_when_every_row_has_its_measures(kv):
    cond = MM.Conditions(speed=MM.equilibrium_speed(kv, 10.23), rps=10.23, rudder_rate=np.deg2rad(15.0))
    rec = MM.simulate_rudder_batch(kv, MM.theta_rows(kv, ["N_r"], [[kv.coef["N_r"]]] * 2),
                                   np.deg2rad([35, 10]), [np.inf, np.deg2rad(10)], [1, -1], cond)
    assert rec.t[-1] < MM.T_APPROACH + 100 * kv.particulars["L"] / cond.speed
    tm = turning_metrics(rec.trial(0))
    assert np.isfinite(tm.tactical_diameter) and tm.side == 1
    zm = zigzag_metrics(rec.trial(1), np.deg2rad(10))
    assert len(zm.overshoots) >= 2 and all(o > 0 for o in zm.overshoots)


def test_cli_simulate_model_json(tmp_path, kv, capsys):
    """An MMG MODEL.json through a turning circle at the training data's propeller rate."""
    model = {"method": "mmg-ebm", "model": dict(kv.to_dict(), training_conditions={
        "rps_ahead": 10.23, "rudder_rate": float(np.deg2rad(15.0)), "runs": 13, "rps_astern": None})}
    mj = tmp_path / "MODEL.json"
    mj.write_text(json.dumps(model))
    out = tmp_path / "t.csv"
    assert main(["simulate", str(mj), "turning-35", "--out", str(out), "--duration", "150"]) == 0
    text = capsys.readouterr().out
    assert "10.23 rev/s" in text and "equilibrium" in text
    tr = read_trial(out)
    assert tr.duration == pytest.approx(150.0)
    np.testing.assert_allclose(tr["n"], 10.23)
    tm = turning_metrics(tr)
    assert tm.side == 1 and 2.0 < tm.advance / kv.particulars["L"] < 5.0
    assert main(["simulate", str(mj), "turning-35", "--out", str(out)]) == 2          # no clobbering
    assert main(["simulate", str(mj), "dp-surge", "--out", str(tmp_path / "d.csv")]) == 2
    assert main(["simulate", "published:kvlcc2_hsva", "zigzag-10", "--out", str(tmp_path / "z.csv")]) == 2


def test_batched_simulator_agrees_with_run_manoeuvre_with_air_drag():
    """The Esso set has wind geometry: in still air the ship meets its own apparent wind in both paths."""
    need_params()
    es = mmg.load_published("esso_osaka_3m")
    cond = MM.Conditions(speed=MM.equilibrium_speed(es, 10.0), rps=10.0, rudder_rate=np.deg2rad(30.0))
    assert abs(mmg.dynamics(0.0, np.array([0, 0, 0, cond.speed, 0, 0.0]), np.array([0, 10.0, 0, 0]), es)[3]) < 1e-9
    ref = run_manoeuvre(MM.ship_model(es, cond), "zigzag-20", duration=60.0, dt=0.1, speed=cond.speed)
    rec = MM.simulate_rudder_batch(es, MM.theta_rows(es), [np.deg2rad(20)], [np.deg2rad(20)], [1], cond,
                                   t_max=60.0, until_reversals=99)
    for j, c in enumerate(mmg.STATE_NAMES):
        np.testing.assert_allclose(rec.x[0, :, j], ref[c], rtol=1e-10, atol=1e-10)


def test_conditions_of_an_older_model_file_come_from_its_training_runs(tmp_path, kv):
    """A MODEL.json without training_conditions: they are computed from the training run files it names."""
    from shipid.io import write_trial

    t = np.arange(0.0, 30.0, 0.1)
    d = np.deg2rad(10.0) * np.clip((t - 5.0) / 1.0, 0.0, 1.0)
    ch = {"x": 0 * t, "y": 0 * t, "psi": 0 * t, "u": np.full(t.size, 1.0), "v": 0 * t, "r": 0 * t,
          "delta": d, "n": np.full(t.size, 9.5)}
    run = tmp_path / "run.csv"
    write_trial(Trial(t, ch, {}, {}), run)
    res = {"model": kv.to_dict(), "provenance": {"training_runs": [{"file": str(run)}], "rudder_sign": -1}}
    c = MM.resolve_conditions(kv, res)
    assert c.rps == 9.5 and np.degrees(c.rudder_rate) == pytest.approx(10.0, rel=1e-9)
    res["provenance"]["training_runs"].append({"file": str(tmp_path / "gone.csv")})
    with pytest.raises(InputError, match="--speed or --rps"):
        MM.resolve_conditions(kv, res)


def test_rows_equilibrium_is_each_rows_scalar_equilibrium():
    need_params()
    es = mmg.load_published("esso_osaka_3m")
    scales = [1.0, 0.8, 1.3]
    Th = MM.theta_rows(es, ["X_0F", "N_r"], [[es.coef["X_0F"] * s, es.coef["N_r"]] for s in scales])
    speeds = MM.rows_equilibrium(es, Th, rps=10.0)
    rates = MM.rows_equilibrium(es, Th, speed=0.4)
    for s, u, n in zip(scales, speeds, rates):
        m = es.with_coef({"X_0F": es.coef["X_0F"] * s})
        assert u == pytest.approx(MM.equilibrium_speed(m, 10.0), rel=1e-9)
        assert n == pytest.approx(MM.equilibrium_rps(m, 0.4), rel=1e-9)
    # a row whose hull pushes it ahead at every speed has none
    Th = MM.theta_rows(es, ["X_0F"], [[-50.0 * es.coef["X_0F"]]])
    assert np.isnan(MM.rows_equilibrium(es, Th, rps=10.0)[0])
    with pytest.raises(ValueError):
        MM.rows_equilibrium(es, Th)
