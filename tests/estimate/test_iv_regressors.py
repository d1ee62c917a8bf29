"""The ARX regressors of shipid.estimate.iv (the black-box instruments of Algorithm 1, the monitor's yaw model)."""

import numpy as np

from shipid.estimate.iv import arx_regressors, lag_matrix


def test_arx_regressors_equal_the_stacked_lag_matrices():
    """The ARX fit's regressors, written column by column in Fortran order, equal the stacked lag matrices (and so
    give the same triangular factor)."""
    rng = np.random.default_rng(44)
    for n, na, nb in ((1000, 4, 5), (300, 2, 3), (400, 3, 1)):
        y, u = rng.standard_normal(n), rng.standard_normal(n)
        y[9] = 0.0
        s = max(na, nb - 1)
        stacked = np.column_stack([-lag_matrix(y, na + 1, s)[:, 1:], lag_matrix(u, nb, s), y[s:]])
        got = arx_regressors(y, u, na, nb, s)
        assert got.flags.f_contiguous
        assert np.array_equal(got, stacked) and np.array_equal(np.signbit(got), np.signbit(stacked))
        assert np.array_equal(np.linalg.qr(got, mode="r"), np.linalg.qr(stacked, mode="r"))
