"""The regressors (37) of Algorithm 1 (shipid.methods.masscm.data)."""

import numpy as np

from shipid.methods.masscm.data import diff2, regressors


def test_regressors_in_place_equal_the_stacked_form():
    """The regressors (37) written column by column equal the stacked form, signs of zeros included."""
    rng = np.random.default_rng(37)
    y, a, r, d = (rng.standard_normal(500) for _ in range(4))
    y[7] = 0.0
    stacked = np.column_stack([-np.concatenate([[0.0], y[:-1]]), -np.concatenate([[0.0, 0.0], y[:-2]]),
                               diff2(a), diff2(r), diff2(d)])
    got = regressors(y, a, r, d)
    assert got.flags.c_contiguous
    assert np.array_equal(got, stacked) and np.array_equal(np.signbit(got), np.signbit(stacked))

