"""Identifiability of (30) from the three datasets (issue 3; ERRATA 000 on (23)–(26))."""

import numpy as np
import pytest
from known.linder2015 import TABLE3_TRUE

from shipid.methods.masscm.identifiability import (dm_dzf, exact_fit_family, jacobian_rank, m_of_zf, report,
                                                    rho)
from shipid.models.roll_reduced import THETA_NAMES, KnownParams, discrete_coeffs

TRUE = TABLE3_TRUE
CONDS = ["nominal", "calibration", "loaded"]


@pytest.fixture(scope="module")
def kn():
    return KnownParams.from_vessel("fishing-vessel")


def test_jacobian_rank_is_one_short(kn):
    r = jacobian_rank(TRUE, kn)
    assert r["n_params"] == 9 and r["rank"] == 8
    s = np.array(r["singular_values"])
    assert s[-1] < 1e-10 * s[0] and s[-2] > 1e-6 * s[0]       # a clean gap, not ill-conditioning
    nd = r["null_direction"]
    assert abs(nd["zm_bar"]) < 1e-8                              # zm_bar does not move along the null direction
    assert np.isclose(nd["m"], dm_dzf(TRUE, kn), rtol=1e-6)      # m moves with slope dm/dz_f


@pytest.mark.parametrize("zf_new", [-0.3, -0.1, 0.0, 0.05])
def test_exact_fit_family_reproduces_all_transfer_functions(kn, zf_new):
    th2 = exact_fit_family(TRUE, kn, zf_new)
    g1 = discrete_coeffs(TRUE, kn, CONDS, 0.02)
    g2 = discrete_coeffs(th2, kn, CONDS, 0.02)
    assert np.allclose(g1, g2, rtol=1e-11, atol=1e-14)
    assert th2[THETA_NAMES.index("zm_bar")] == TRUE[8]
    assert np.isclose(rho(th2, kn), rho(TRUE, kn), rtol=1e-12)
    assert np.isclose(th2[7], m_of_zf(rho(TRUE, kn), TRUE[8], zf_new, kn), rtol=1e-12)
    assert not np.isclose(th2[7], 0.4)                           # m really changes


def test_slope_predicts_table3_spread_of_m(kn):
    # Table 3: std(z_f) = 0.0225 m, std(m) = 0.0018 kg; the family slope links them
    slope = dm_dzf(TRUE, kn)
    assert np.isclose(slope, 2.1 * 0.2 * (-0.01) / 0.21**2, rtol=1e-9)   # rho = 2.1, hand value
    assert 0.0012 < abs(slope) * 0.0225 < 0.0030


def test_report_statement(kn):
    r = report(TRUE, kn)
    assert r["not_identifiable"] == ["z_f"] and set(r["identifiable"]) == {"zm_bar", "rho"}
