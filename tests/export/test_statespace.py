"""State-space export: the DP control model of Fossen, Sagatun & Sørensen (1996) eqs. 50–52, and manoeuvring
models linearised about a straight run."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lsim

from known.fossen1996 import A_EQ51, A_H_EQ48, B_EQ52, K_EQ49, T_EQ29
from shipid.export import load, state_space
from shipid.export.statespace import accelerations, trim
from shipid.models import abkowitz as ab
from shipid.numerics.integrate import simulate

#: Eq. (30): the a-priori inertia matrix M'' of the supply vessel (bis), as the paper prints it.
M_EQ30 = np.array([[1.1274, 0.0, 0.0], [0.0, 1.8902, -0.0744], [0.0, -0.0744, 0.1278]])


def test_dp_export_equals_eqs_50_to_52():
    """A'' = M''^-1 A_h M'' and B'' = M''^-1 T'' K'' (eq. 50, ERRATA 001 reading of B'') written out here from
    eqs. 29, 30, 48 and 49; the export equals them to round-off, and the matrices the paper prints (eqs. 51-52)
    to their printed precision."""
    ss = state_space("supply")
    Minv = np.linalg.inv(M_EQ30)
    A_ref = Minv @ A_H_EQ48 @ M_EQ30
    B_ref = Minv @ T_EQ29 @ np.diag(K_EQ49)
    assert ss.states == ("u", "v", "r") and ss.inputs == ("u1", "u2", "u3", "u4", "u5", "u6")
    np.testing.assert_allclose(ss.A, A_ref, rtol=0, atol=1e-15)
    np.testing.assert_allclose(ss.B, B_ref, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(ss.C, np.eye(3))
    np.testing.assert_array_equal(ss.D, np.zeros((3, 6)))
    # eq. 51 is printed to 1e-4 and computed from A_h before eq. 48 rounded it to 1e-4: half a unit of the
    # last digit of eq. 51 plus half a unit of each free entry of eq. 48 (eq. 46), propagated through M^-1 . M
    E = 0.5e-4 * (A_H_EQ48 != 0)
    tol_a = 0.5e-4 + np.abs(Minv) @ E @ np.abs(M_EQ30)
    assert np.all(np.abs(ss.A - A_EQ51) <= tol_a + 1e-12)
    # eq. 52 is printed to 1e-4 from K'' printed to 0.1e-3 (eq. 49): half a unit of each, propagated
    tol = 0.5e-4 + np.abs(Minv @ T_EQ29) * 0.05e-3
    assert np.all(np.abs(ss.B - B_EQ52) <= tol + 1e-12)


def test_dp_si_form_is_the_bis_form_in_si_units():
    """The SI matrices are the bis ones scaled by eqs. 26-28 (A = S A'' S^-1 / Th)."""
    src = load("supply")
    bis, si = state_space(src), state_space(src, units="si")
    b = src.model.bis
    np.testing.assert_allclose(si.A, b.A_from_bis(bis.A), rtol=1e-10, atol=1e-14)
    assert si.units["u"] == "m/s" and bis.units["u"] == "- (bis)"


def test_dp_kinematics_adds_positions():
    ss = state_space("supply", kinematics=True)
    assert ss.states == ("x", "y", "psi", "u", "v", "r")
    np.testing.assert_array_equal(ss.A[:3, 3:], np.eye(3))


def test_frame_and_dict_carry_names_and_units():
    ss = state_space("supply")
    f = ss.to_frame()
    assert list(f.index) == ["du/dt", "dv/dt", "dr/dt", "out u", "out v", "out r"]
    assert f.columns[0] == "u [- (bis)]" and f.shape == (6, 9)
    assert f.iloc[0, 0] == ss.A[0, 0]
    d = ss.to_dict()
    assert np.array_equal(np.array(d["B"]), ss.B) and d["inputs"][0] == "u1"
    assert "eqs. 50-52" in repr(ss) and len(repr(ss)) < 300


def test_python_control_statespace():
    control = pytest.importorskip("control")
    ss = state_space("supply")
    sys = ss.to_control()
    assert isinstance(sys, control.StateSpace)
    np.testing.assert_array_equal(sys.A, ss.A)
    np.testing.assert_array_equal(sys.B, ss.B)
    assert list(sys.input_labels) == list(ss.inputs) and list(sys.state_labels) == list(ss.states)


def test_abkowitz_trim_holds_the_straight_run():
    """Yoon & Rhee's Table 3 has Y_0, N_0 != 0: the straight run needs a small rudder and drift, found by the trim."""
    src = load("esso-osaka")
    tr = trim(src)
    acc = accelerations(src, (tr.speed, tr.v, 0.0), tr.delta, tr.rps)
    L, U = src.length, tr.speed
    assert np.all(np.abs(acc * np.array([L, L, L * L]) / U ** 2) < 1e-9)
    assert tr.delta != 0.0 and abs(np.degrees(tr.delta)) < 0.1


def test_linearisation_predicts_a_small_rudder_step():
    """The exported (A, B) of the packaged Esso Osaka model predict its sway and yaw rate after a 0.5 deg rudder
    step from the trimmed straight run: over 120 s the nonlinear model (RK4) and the linear one (scipy lsim)
    differ by less than 1 % of the largest yaw rate."""
    src = load("esso-osaka")
    ss = state_space(src)
    op = ss.operating_point
    p = src.model
    t = np.arange(0.0, 120.0 + 1e-9, 0.5)
    d0, dd = np.deg2rad(op["delta_deg"]), np.deg2rad(0.5)
    u_in = np.column_stack([np.full(t.size, d0 + dd), np.full(t.size, op["rps"])])
    x0 = np.array([op["speed"], op["v"], 0.0, 0.0, 0.0, 0.0])
    sim = simulate(ab.dynamics, t, x0, u_in, p)
    r_nl = sim.x[:, 2]
    _, y, _ = lsim((ss.A, ss.B, ss.C, ss.D), np.column_stack([np.full(t.size, dd), np.zeros(t.size)]), t)
    assert np.max(np.abs(y[:, 2] - r_nl)) < 0.01 * np.max(np.abs(r_nl))
    assert np.max(np.abs(y[:, 1] - (sim.x[:, 1] - op["v"]))) < 0.01 * np.max(np.abs(sim.x[:, 1] - op["v"]))


def test_dp_speed_is_refused():
    from shipid.errors import InputError
    with pytest.raises(InputError, match="at rest"):
        state_space("supply", speed=3.0)
