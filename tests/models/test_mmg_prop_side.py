"""Optional asymmetry terms of the Yasukawa 2015 structure (models.mmg_prop_side, issue 19).

Off by default (absent or 0: forces bit-identical); the neutral rudder angle shifts the rudder inflow angle
and nothing else; the propeller side force is c T at the propeller's position, to port in yaw for c > 0. The
KVLCC2 L7 set is read at run time from ``data_root()/params`` (never copied); skipped when absent.
"""

import numpy as np
import pytest

from shipid.models import mmg
from shipid.models import mmg_forces as F
from shipid.models.mmg_prop_side import PROP_SIDE_TERMS

SEED = 20261203                       # the states of these tests (fixture mmg_states, conftest)


def test_terms_at_zero_leave_the_forces_unchanged_bit_for_bit(kvlcc2_l7, mmg_states, with_part):
    m = kvlcc2_l7
    args = mmg_states(SEED)
    ref = mmg.forces(m, *args)
    got = mmg.forces(with_part(m, **{k: 0.0 for k in PROP_SIDE_TERMS}), *args)
    for a, b in zip(ref, got):
        assert np.array_equal(a, b)
    assert set(PROP_SIDE_TERMS) <= set(F.RUDDER_LARGE_ANGLE)        # may differ per row of a replay batch


def test_neutral_angle_shifts_the_rudder_inflow_angle_only(kvlcc2_l7, mmg_states, with_part):
    m = kvlcc2_l7
    u, v, r, delta, n = mmg_states(SEED)
    d0 = np.deg2rad(1.5)
    a = F.basis_yasukawa(with_part(m, rudder_neutral_angle=d0).particulars, u, v, r, delta, n)["aux"]
    b = F.basis_yasukawa(m.particulars, u, v, r, delta, n)["aux"]
    np.testing.assert_allclose(a["alpha_R"], b["alpha_R"] - d0, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(a["U_R"], b["U_R"])
    np.testing.assert_array_equal(a["T"], b["T"])
    # straight ahead with the rudder amidships: d0 > 0 turns the ship to port (N < 0), as a right-handed
    # propeller's swirl does
    one = [np.array([x]) for x in (1.179, 0.0, 0.0, 0.0, 10.23)]
    assert mmg.forces(with_part(m, rudder_neutral_angle=d0), *one)[2][0] < 0.0
    assert mmg.forces(m, *one)[2][0] == pytest.approx(0.0, abs=1e-9)


def test_propeller_side_force_is_c_times_thrust_at_the_propeller(kvlcc2_l7, mmg_states, with_part):
    m = kvlcc2_l7
    args = mmg_states(SEED)
    c = 0.05
    X0, Y0, N0 = mmg.forces(m, *args)
    X1, Y1, N1 = mmg.forces(with_part(m, prop_side_thrust=c), *args)
    T = F.basis_yasukawa(m.particulars, *args)["aux"]["T"]
    p = m.particulars
    np.testing.assert_array_equal(X1, X0)
    np.testing.assert_allclose(Y1 - Y0, c * T, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(N1 - N0, p["x_P"] * p["L"] * c * T, rtol=1e-12, atol=1e-9)
    assert np.all(N1 - N0 < 0)                       # stern to starboard: bow to port (x_P < 0, T > 0)


def test_per_row_values_act_per_row(kvlcc2_l7, mmg_states, with_part):
    m = kvlcc2_l7
    u, v, r, delta, n = (a[:3] for a in mmg_states(SEED))
    vals = np.array([0.0, 0.02, 0.04])
    _, _, Nrow = mmg.forces(with_part(m, rudder_neutral_angle=vals), u, v, r, delta, n)
    for i, x in enumerate(vals):
        _, _, Ni = mmg.forces(with_part(m, rudder_neutral_angle=float(x)), u[i:i + 1], v[i:i + 1], r[i:i + 1],
                              delta[i:i + 1], n[i:i + 1])
        assert Nrow[i] == pytest.approx(Ni[0], rel=1e-12)
