"""Optional angle-dependent rudder terms of the Yasukawa 2015 structure (models.mmg_forces, issue 19).

Off by default (absent or 0: forces bit-identical to the standard method); the stall part is odd,
monotone and saturating; each per-side term changes only its side. The KVLCC2 L7 set is read at run
time from ``data_root()/params`` (never copied); those tests skip when the folder is absent.
"""

import numpy as np
import pytest

from shipid.models import mmg
from shipid.models import mmg_forces as F

SEED = 20261202                       # the states of these tests (fixture mmg_states, conftest)
GRID = np.deg2rad(np.linspace(-40.0, 40.0, 33))


def test_terms_at_zero_leave_the_forces_unchanged_bit_for_bit(kvlcc2_l7, mmg_states, with_part):
    m = kvlcc2_l7
    args = mmg_states(SEED)
    ref = mmg.forces(m, *args)
    off = with_part(m, **{k: 0.0 for k in F.RUDDER_LARGE_ANGLE})
    got = mmg.forces(off, *args)
    for a, b in zip(ref, got):
        assert np.array_equal(a, b)


def test_stalled_sine_is_odd_monotone_saturating_and_linear_at_small_angles():
    a = np.deg2rad(np.linspace(-89.0, 89.0, 357))
    sa = np.sin(a)
    alpha_s = np.deg2rad(20.0)
    g = F.stalled_sine(sa, alpha_s)
    assert np.all(np.diff(g) > 0)                                   # monotone
    assert np.all(np.abs(g) < np.sin(alpha_s))                      # never above the ceiling
    np.testing.assert_allclose(g, -F.stalled_sine(-sa, alpha_s), rtol=0, atol=1e-15)   # odd
    small = np.abs(a) < np.deg2rad(2.0)
    np.testing.assert_allclose(g[small], sa[small], rtol=2e-3)      # slope unchanged at small angles
    assert abs(g[-1]) > 0.95 * np.sin(alpha_s)                      # saturates towards the ceiling
    np.testing.assert_array_equal(F.stalled_sine(sa, 0.0), sa)      # alpha_s <= 0: off
    assert np.all(np.abs(F.stalled_sine(sa, np.deg2rad(10.0))) <= np.abs(g) + 1e-15)  # earlier stall, less lift


def _rudder_moment(m, delta):
    k = delta.size
    u, n = np.full(k, 1.179), np.full(k, 10.23)
    z = np.zeros(k)
    return mmg.forces(m, u, z, z, delta, n)[2] - mmg.forces(m, u, z, z, z, n)[2]


def test_stall_per_side_changes_only_its_side_and_keeps_the_normal_force_monotone(kvlcc2_l7, with_part):
    """Straight ahead (alpha_R = delta) the rudder's yaw moment is -(x_R + a_H x_H) F_N cos(delta), so
    N / cos(delta) is proportional to the normal force."""
    m = kvlcc2_l7
    N0 = _rudder_moment(m, GRID)
    N1 = _rudder_moment(with_part(m, rudder_stall_plus=np.deg2rad(15.0)), GRID)
    pos, neg = GRID > 0, GRID < 0
    np.testing.assert_array_equal(N1[neg], N0[neg])
    assert np.all(np.abs(N1[pos]) < np.abs(N0[pos]))
    F0, F1 = N0 / np.cos(GRID), N1 / np.cos(GRID)
    assert np.all(np.diff(F1) > 0)
    big = GRID > np.deg2rad(30.0)
    assert np.ptp(F1[big]) < 0.2 * np.ptp(F0[big])                  # flat past stall


def test_crossflow_side_and_side_slope_strengthen_the_chosen_side_more_at_larger_angles(kvlcc2_l7, with_part):
    m = with_part(kvlcc2_l7, rudder_crossflow=1.0)
    N0 = _rudder_moment(m, GRID)
    for kw in ({"rudder_crossflow_side": -0.5}, {"rudder_side_slope": -0.3}):
        N1 = _rudder_moment(with_part(m, **kw), GRID)
        pos, neg = GRID > 0, GRID < 0
        assert np.all(np.abs(N1[neg]) > np.abs(N0[neg])) and np.all(np.abs(N1[pos]) < np.abs(N0[pos])), kw
        rel = np.abs(N1[neg] / N0[neg] - 1.0)                       # grows with |delta|
        assert np.all(np.diff(rel[::-1]) > 0), kw


def test_side_slope_factor_is_one_plus_k_delta():
    FN = np.ones(3)
    d = np.array([-0.5, 0.0, 0.5])
    np.testing.assert_allclose(F.rudder_side_slope({"rudder_side_slope": -0.2}, FN, d), [1.1, 1.0, 0.9])
    np.testing.assert_array_equal(F.rudder_side_slope({}, FN, d), FN)
