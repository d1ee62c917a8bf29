"""An MMG model exported to shipmmg (PyPI; optional extra ``shipmmg``): the KVLCC2 35 deg turning circle."""

from __future__ import annotations

import numpy as np
import pytest

from shipid.errors import InputError
from shipid.export import load, to_shipmmg
from shipid.export.source import from_model
from shipid.io.paths import data_root
from shipid.io.trial import Trial
from shipid.methods.mmg import manoeuvres as MM
from shipid.models import mmg
from shipid.simulate.manoeuvres import run_manoeuvre
from shipid.simulate.metrics import turning_metrics

U0 = 1.179                      # HSVA KVLCC2 approach speed, m/s (shared data README)
RUDDER_RATE = np.deg2rad(15.8)  # 2.33 deg/s at full scale (L 320 m) on the 7 m model: 2.33 sqrt(320/7)


def _kvlcc2():
    root = data_root()
    if root is None or not (root / "params" / "kvlcc2_L7_mmg_shipmmg.yml").is_file():
        pytest.skip("KVLCC2 parameters not found (set SHIPID_DATA)")
    return mmg.load_published("kvlcc2_L7")


def test_mapping_reproduces_shipids_rudder_and_propeller_gains():
    model = _kvlcc2()
    ex = to_shipmmg("published:kvlcc2_L7")
    c, p = model.coef, model.particulars
    assert ex.basic["t_P"] == pytest.approx(1 - c["XP_gain"]) and ex.basic["a_H"] == pytest.approx(c["YR_gain"] - 1)
    assert ex.basic["x_R"] + ex.basic["a_H"] * ex.basic["x_H"] == pytest.approx(c["NR_arm"])
    assert ex.maneuvering["N_rrr_dash"] == c["N_rrr"] and ex.basic["L_pp"] == p["L"]
    assert ex.rho == p["rho"]


def test_other_structures_are_refused():
    with pytest.raises(InputError, match="no shipmmg form|family"):
        to_shipmmg("esso-osaka")


def _turn(model, ex):
    """35 deg starboard turn: shipid's (RK4, input held) and shipmmg's (solve_ivp) from the same rudder history."""
    cond = MM.Conditions(speed=U0, rps=MM.equilibrium_rps(model, U0), rudder_rate=RUDDER_RATE)
    tr = run_manoeuvre(MM.ship_model(model, cond), "turning-35", duration=150.0, dt=0.1, speed=U0)
    X = ex.simulate(tr.t, tr["delta"], tr["n"], U0)
    other = Trial(tr.t, {"x": X[:, 0], "y": X[:, 1], "psi": X[:, 2], "u": X[:, 3], "v": X[:, 4], "r": X[:, 5],
                         "delta_cmd": tr["delta_cmd"]}, {}, {})
    a, b = turning_metrics(tr), turning_metrics(other)
    return (b.advance / a.advance - 1, b.tactical_diameter / a.tactical_diameter - 1)


def test_kvlcc2_turning_circle_in_shipmmg():
    """The KVLCC2 L7 MMG set (Yasukawa & Yoshimura 2015 Table 3, the set shipmmg's own tests use; identifying
    one from the HSVA runs takes minutes) exported to shipmmg turns within 1 % of shipid (advance, tactical diameter), or the
    export names the terms that differ and, with those terms set equal in both codes (w_P0 = 0 with C_2 = 1,
    x_G = 0), the two agree within 1 %.

    Measured (shipmmg 0.0.11, 0.1 s grid): advance +0.27 %, tactical diameter -2.10 % as exported; the export
    names the wake fraction in a turn (Yasukawa & Yoshimura eq. 15 against shipmmg's w_P0 exp(-4 beta_P^2)) and
    the drift angle taken from v - x_G r; with both made equal -0.34 % and -0.00 % (the rest: shipmmg's spline
    of the rudder ramp against shipid's input held over each step).
    """
    pytest.importorskip("shipmmg")
    model = _kvlcc2()
    ex = to_shipmmg("published:kvlcc2_L7")
    d_adv, d_td = _turn(model, ex)
    if max(abs(d_adv), abs(d_td)) > 0.01:
        assert any(d.startswith("wake fraction in a turn") for d in ex.differences)
        assert any(d.startswith("drift angle") for d in ex.differences)
    p = dict(model.particulars)
    p.update(w_P0=0.0, C_2_plus=1.0, C_2_minus=1.0, x_G=0.0)
    same = mmg.MmgModel(model.structure, p, model.coef, name="kvlcc2-named-terms-equal")
    ex_same = to_shipmmg(from_model("mmg", same, origin="test"))
    assert ex_same.differences == ()
    d_adv, d_td = _turn(same, ex_same)
    assert abs(d_adv) < 0.01 and abs(d_td) < 0.01


def _measured():  # pragma: no cover - prints the figures quoted above: python tests/export/test_shipmmg.py
    model = _kvlcc2()
    print("as exported: advance %+.3f %%, tactical diameter %+.3f %%" % tuple(100 * x for x in _turn(model, to_shipmmg("published:kvlcc2_L7"))))
    p = dict(model.particulars)
    p.update(w_P0=0.0, C_2_plus=1.0, C_2_minus=1.0, x_G=0.0)
    same = mmg.MmgModel(model.structure, p, model.coef)
    print("named terms equal: advance %+.3f %%, tactical diameter %+.3f %%" % tuple(100 * x for x in _turn(same, to_shipmmg(from_model("mmg", same, origin="test")))))


if __name__ == "__main__":  # pragma: no cover
    _measured()


@pytest.mark.slow
@pytest.mark.realdata
def test_kvlcc2_identified_from_hsva_runs_in_shipmmg(tmp_path):
    """The target as stated: a KVLCC2 model identified from four HSVA zig-zags (10/10 and 20/10, both sides;
    candidate linear-hull+rudder, about 3 min) exported to shipmmg. Measured: advance +0.33 %, tactical
    diameter -2.33 % as exported, with the wake and drift-angle terms named; with those terms made equal in
    both codes -0.33 % and -0.00 %."""
    pytest.importorskip("shipmmg")
    from shipid.cli import main

    root = data_root()
    if root is None or not (root / "kvlcc2_hsva").is_dir():
        pytest.skip("HSVA KVLCC2 runs not found (set SHIPID_DATA)")
    runs = ["Z_10_10_S", "Z_20_10_P", "Z_10_10_P", "Z_20_10_S"]
    args = ["identify", "mmg", "--structure", "linear-hull+rudder", "-o", str(tmp_path / "MODEL.json")]
    for r in runs:
        args += ["--trial", str(root / "kvlcc2_hsva" / f"HSVA_CPMC_KVLCC2_{r}.dat")]
    assert main(args) == 0
    ex = to_shipmmg(str(tmp_path / "MODEL.json"))
    model = load(str(tmp_path / "MODEL.json")).model
    d_adv, d_td = _turn(model, ex)
    if max(abs(d_adv), abs(d_td)) > 0.01:
        assert any(d.startswith("wake fraction in a turn") for d in ex.differences)
    p = dict(model.particulars)
    p.update(w_P0=0.0, C_2_plus=1.0, C_2_minus=1.0, x_G=0.0)
    same = mmg.MmgModel(model.structure, p, model.coef)
    ex_same = to_shipmmg(from_model("mmg", same, origin="test"))
    assert ex_same.differences == ()
    d_adv, d_td = _turn(same, ex_same)
    assert abs(d_adv) < 0.01 and abs(d_td) < 0.01
