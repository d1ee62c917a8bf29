"""MMG model (issue 6): closed-form cross-flow integrals, equations of motion, published sets.

The published Esso Osaka set is read at run time from ``data_root()/params`` (never
copied); those tests skip cleanly when the folder is absent.
"""

import numpy as np
import pytest
from scipy import integrate

from shipid.io import data_root
from shipid.models import mmg

ROOT = data_root()


def need_params():
    if ROOT is None or not (ROOT / "params").is_dir():
        pytest.skip("shared data (params/) not found (set SHIPID_DATA)")


@pytest.mark.parametrize("v,r", [(0.1, 0.05), (0.01, 0.2), (-0.05, -0.3), (0.2, 0.0), (0.0, 0.1),
                                 (0.0, 0.0), (-0.3, 0.02)])
def test_crossflow_closed_form_matches_quadrature(v, r):
    L, CY, CN = 3.0, 2.217, 0.8097
    x = np.linspace(-L / 2, L / 2, 4001)
    sy = v + CY * r * x
    sn = v + CN * r * x
    iy_ref = integrate.simpson(np.abs(sy) * sy, x=x) / L
    in_ref = integrate.simpson(np.abs(sn) * sn * x, x=x) / L ** 2
    iy, i_n = mmg.crossflow_integrals(np.array(v), np.array(r), L, CY, CN)
    assert iy == pytest.approx(iy_ref, abs=1e-9)
    assert i_n == pytest.approx(in_ref, abs=1e-9)


def test_apparent_wind_head_wind_and_beam_wind():
    # ship heading 0 (along x0) at 1 m/s, wind from 0 rad (blowing towards -x0) at 2 m/s -> 3 m/s from the bow
    UA, gA = mmg.apparent_wind(np.array(2.0), np.array(0.0), np.array(0.0), np.array(1.0), np.array(0.0))
    assert UA == pytest.approx(3.0) and gA == pytest.approx(0.0, abs=1e-12)
    # ship at rest heading east (psi = pi/2), wind from north (0): from the port side, 270 deg clockwise
    UA, gA = mmg.apparent_wind(np.array(1.0), np.array(0.0), np.array(np.pi / 2), np.array(0.0), np.array(0.0))
    assert UA == pytest.approx(1.0) and gA == pytest.approx(1.5 * np.pi)


def _toy_model():
    need_params()
    return mmg.load_published("esso_osaka_3m")


def test_rigid_body_forces_invert_accelerations():
    m = _toy_model()
    rng = np.random.default_rng(6)
    u, v, r, X, Y, N = rng.normal(size=(6, 50)) * np.array([[0.5], [0.1], [0.1], [5], [5], [5]])
    du, dv, dr = mmg.accelerations(m, u, v, r, X, Y, N)
    X2, Y2, N2 = mmg.rigid_body_forces(m, u, v, r, du, dv, dr)
    np.testing.assert_allclose([X2, Y2, N2], [X, Y, N], rtol=1e-12, atol=1e-12)


def test_esso_published_particulars_match_readme():
    # shared/data/README.md: m 244.6 kg, x_G 0.094 m, L 3.0 m
    m = _toy_model()
    assert m.particulars["m"] == pytest.approx(244.6, abs=0.2)
    assert m.particulars["x_G"] == pytest.approx(0.094, abs=0.001)
    assert m.particulars["L"] == 3.0


def _reference_hull(u, v, r, p, c):
    """mmg-1p1r-simulator hullForceYoshimuraSimpson written out directly (Simpson, 100 points)."""
    L, d, rho = p["L"], p["d"], p["rho"]
    U = np.hypot(u, v)
    beta = np.arctan2(v, u)
    x = np.linspace(-L / 2, L / 2, 100)
    yc = integrate.simpson(np.abs(v + p["C_rY"] * r * x) * (v + p["C_rY"] * r * x), x=x) / L * c["CD_Y"]
    nc = integrate.simpson(np.abs(v + p["C_rN"] * r * x) * (v + p["C_rN"] * r * x) * x, x=x) / L ** 2 * c["CD_N"]
    q = 0.5 * rho * L * d
    XH = q * ((c["X_0F"] + (c["X_0A"] - c["X_0F"]) * abs(beta) / np.pi) * u * U + c["X_vr"] * v * r * L)
    YH = q * (c["Y_v"] * v * abs(u) + c["Y_r"] * r * L * u - yc)
    NH = q * L * (c["N_v"] * v * u + c["N_r"] * r * L * abs(u) - nc)
    return XH, YH, NH


@pytest.mark.parametrize("u,v,r", [(0.5, 0.05, 0.02), (-0.2, 0.1, -0.05), (0.05, -0.1, 0.1)])
def test_esso_hull_basis_equals_reference_formula(u, v, r):
    m = _toy_model()
    b = mmg.basis(m, u, v, r, 0.0, 0.0)
    got = []
    for mode, first in (("X", 3), ("Y", 3), ("N", 3)):
        H, _ = b[mode]
        got.append(float(H[..., :first] @ m.theta(mode)[:first]))
    ref = _reference_hull(u, v, r, m.particulars, m.coef)
    np.testing.assert_allclose(got, ref, rtol=2e-3, atol=1e-6)   # Simpson on 100 points vs exact


def test_starboard_rudder_turns_to_starboard_both_sets():
    """Positive δ gives a positive yaw moment and negative sway force (MMG sign convention)."""
    need_params()
    for name, n, u in (("esso_osaka_3m", 10.0, 0.4), ("kvlcc2_L7", 10.23, 1.179)):
        m = mmg.load_published(name)
        X, Y, N = mmg.forces(m, u, 0.0, 0.0, np.deg2rad(20), n)
        X0, Y0, N0 = mmg.forces(m, u, 0.0, 0.0, 0.0, n)
        assert N - N0 > 0 and Y - Y0 < 0 and X - X0 < 0, name


def test_kvlcc2_L7_published_values():
    need_params()
    m = mmg.load_published("kvlcc2_L7")
    # Yasukawa & Yoshimura 2015 Table 3 (KVLCC2): Y'_v = -0.315, N'_r = -0.049; rho*nabla = 1025*3.27
    assert m.coef["Y_v"] == -0.315 and m.coef["N_r"] == -0.049
    assert m.particulars["m"] == pytest.approx(1025 * 3.27)


def test_batch_simulation_equals_single_runs():
    m = _toy_model()
    t = np.arange(0, 5.0, 0.1)
    x0 = np.array([[0, 0, 0, 0.3, 0.0, 0.0], [1, 2, 0.5, 0.1, 0.02, -0.01]])
    U = np.zeros((2, t.size, 4))
    U[:, :, 0] = np.deg2rad(10)
    U[:, :, 1] = 8.0
    U[1, :, 2], U[1, :, 3] = 1.5, 2.0
    both = mmg.simulate_batch(m, t, x0, U)
    for i in range(2):
        one = mmg.simulate_batch(m, t, x0[i][None], U[i])[0]
        np.testing.assert_allclose(both[i], one, rtol=1e-12, atol=1e-12)
    from shipid.numerics.integrate import simulate
    ref = simulate(mmg.dynamics, t, x0[1], U[1], m)
    np.testing.assert_allclose(both[1], ref.x, rtol=1e-10, atol=1e-12)


def test_cubic_hull_structure_uses_the_standard_mmg_hull():
    """esso-cubic-hull: hull columns of Yasukawa & Yoshimura (2015) eq. 8, Esso propeller/rudder columns."""
    m = _toy_model()
    coef = {c: 0.1 for md in mmg.MODES for c in mmg.COEFS["esso-cubic-hull"][md]}
    cm = mmg.MmgModel("esso-cubic-hull", m.particulars, coef)
    u, v, r = np.array([0.4, 0.1]), np.array([0.05, -0.08]), np.array([0.02, 0.1])
    b = mmg.basis(cm, u, v, r, 0.1, 8.0)
    be = mmg.basis(m, u, v, r, 0.1, 8.0)
    U = np.hypot(u, v)
    q = 0.5 * m.particulars["rho"] * m.particulars["L"] * m.particulars["d"] * U ** 2
    np.testing.assert_allclose(b["Y"][0][:, 0], q * v / U)                      # Y'_v v'
    np.testing.assert_allclose(b["N"][0][:, 1], q * m.particulars["L"] * r * m.particulars["L"] / U)  # N'_r r'
    np.testing.assert_allclose(b["X"][0][:, 0], -q)                             # -R'_0
    np.testing.assert_allclose(b["Y"][0][:, 6:], be["Y"][0][:, 3:])             # propeller/rudder unchanged
