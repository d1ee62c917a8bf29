"""Rudder yaw-inflow, propeller-walk and wind-arm terms (esso-lowspeed-ext2; shipid.methods.mmg.candidates_ext2)."""

import numpy as np
import pytest

from shipid.methods.mmg import candidates as C
from shipid.methods.mmg import candidates_ext2 as E2
from shipid.models import mmg
from shipid.models.mmg_esso_ext2 import EXT2_COEFS
from shipid.models.mmg_forces import fujii_f_alpha


def _ext2(prior, terms, **coef):
    m, free = C.apply_candidate(prior, E2.ext2_variant(E2.base_candidate(), E2.combine(*terms)))
    return m.with_coef(coef), free


def _winds(seed, k):
    g = np.random.default_rng(seed)
    return g.uniform(0.0, 5.0, k), g.uniform(-np.pi, np.pi, k)


def test_zero_extra_terms_give_the_ext_model(esso_published, esso_states):
    """With the EXT2_COEFS at zero the forces are those of esso-lowspeed-ext (and of the published model)."""
    m, _ = _ext2(esso_published, tuple(E2.EXT2_TERMS))
    assert m.structure == E2.STRUCTURE
    base, _ = C.apply_candidate(esso_published, E2.base_candidate())
    assert base.structure == "esso-lowspeed-ext"
    s = esso_states(5, 300, 16.0)
    UA, gA = _winds(5, 300)
    for a, b, c in zip(mmg.forces(m, *s, UA, gA), mmg.forces(base, *s, UA, gA),
                       mmg.forces(esso_published, *s, UA, gA)):
        np.testing.assert_array_equal(a, b)
        np.testing.assert_allclose(a, c, rtol=1e-12, atol=1e-12)


def test_yaw_inflow_is_the_normal_force_slope_times_rL_over_UR(esso_published, esso_states):
    """YR_r = c adds c * dF_N/d(alpha) * (r L / U_R) * (-cos delta) to Y, NR_r = k adds k L times the same to N;
    nothing at zero yaw rate."""
    p = esso_published.particulars
    m, _ = _ext2(esso_published, ("rudder-yaw-inflow",), YR_r=0.3, NR_r=-0.4)
    u, v, r, d, n = esso_states(6, 300, 16.0)
    F1, F0 = mmg.forces(m, u, v, r, d, n), mmg.forces(esso_published, u, v, r, d, n)
    a = mmg.basis(esso_published, u, v, r, d, n)["aux"]
    slope = 0.5 * p["rho"] * p["A_R"] * a["U_R"] ** 2 * fujii_f_alpha(p["lambda_R"]) * np.cos(a["alpha_R"])
    ok = a["U_R"] > 1e-3
    col = -slope[ok] * (r[ok] * p["L"] / a["U_R"][ok]) * np.cos(d[ok])
    np.testing.assert_allclose((F1[1] - F0[1])[ok], 0.3 * col, rtol=1e-9, atol=1e-14)
    np.testing.assert_allclose((F1[2] - F0[2])[ok], -0.4 * p["L"] * col, rtol=1e-9, atol=1e-14)
    np.testing.assert_allclose(F1[0], F0[0], rtol=1e-12, atol=1e-12)
    z = 0 * r
    G1, G0 = mmg.forces(m, u, v, z, d, n), mmg.forces(esso_published, u, v, z, d, n)
    np.testing.assert_allclose(G1[1], G0[1], rtol=0, atol=1e-15)


def test_prop_walk_grows_with_the_advance_ratio_ahead_only(esso_published, esso_states):
    p = esso_published.particulars
    m, _ = _ext2(esso_published, ("prop-walk-J",), YP_J=0.02, NP_J=-0.01)
    u, v, r, d, n = esso_states(7, 300, 16.0)
    F1, F0 = mmg.forces(m, u, v, r, d, n), mmg.forces(esso_published, u, v, r, d, n)
    J = mmg.basis(esso_published, u, v, r, d, n)["aux"]["J"]
    T = (n > 0) * p["rho"] * p["D_p"] ** 4 * n * n * J
    np.testing.assert_allclose(F1[1] - F0[1], 0.02 * T, rtol=1e-9, atol=1e-14)
    np.testing.assert_allclose(F1[2] - F0[2], -0.01 * T * p["L"], rtol=1e-9, atol=1e-14)
    assert np.all((F1[1] - F0[1])[n <= 0] == 0)


def test_wind_arm_moves_the_air_side_force(esso_published, esso_states):
    p = esso_published.particulars
    m, _ = _ext2(esso_published, ("wind-arm",), NW_y=0.1)
    s = esso_states(8, 300, 16.0)
    UA, gA = _winds(8, 300)
    F1, F0 = mmg.forces(m, *s, UA, gA), mmg.forces(esso_published, *s, UA, gA)
    YA = mmg.wind_forces(p, UA, gA)[1]
    np.testing.assert_allclose(F1[2] - F0[2], 0.1 * p["L"] * YA, rtol=1e-9, atol=1e-13)
    np.testing.assert_allclose(F1[1], F0[1], rtol=1e-12, atol=1e-12)


def test_variants_extend_the_heldout9_choice():
    v = E2.ext2_variants()
    assert set(v) == {f"{E2.BASE_NAME}+{t}" for t in E2.EXT2_TERMS}
    base = E2.base_candidate()
    assert base["structure"] == "esso-lowspeed-ext" and {"NP_n", "NW_g"} <= set(base["N"])
    w = v[f"{E2.BASE_NAME}+rudder-yaw-inflow"]
    assert w["structure"] == E2.STRUCTURE and w["weighting"] == "nondimensional"
    assert w["Y"][-1] == "YR_r" and w["N"][-1] == "NR_r" and w["X"] == base["X"]
    assert set(sum(E2.combine(*E2.EXT2_TERMS).values(), ())) == set(sum(EXT2_COEFS.values(), ()))
    with pytest.raises(ValueError):
        E2.ext2_variant(C.CANDIDATES["esso-lowspeed"]["hull+rudder+thrust"], E2.EXT2_TERMS["wind-arm"])
