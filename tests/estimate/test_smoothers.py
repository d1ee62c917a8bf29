"""Tests of the modified Bryson–Frazier and RTS fixed-interval smoothers (seed 002 eq. 10)."""

import numpy as np
import pytest

from shipid.estimate.cd_ekf import cd_ekf
from shipid.estimate.smoothers import mbf_smoother, rts_smoother


def _linear_problem(n=300, seed=1):
    """A 3-state linear model (damped oscillator + bias), two measurements."""
    F = np.array([[0.0, 1.0, 0.0], [-0.2, -0.1, 1.0], [0.0, 0.0, -0.05]])
    Q = np.diag([0.0, 0.02, 0.01])
    H = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    R = np.diag([0.2, 0.5]) ** 2
    h = 0.5
    from shipid.estimate.cd_ekf import van_loan
    Phi, Qd = van_loan(F, Q, h)
    rng = np.random.default_rng(seed)
    x = np.array([1.0, 0.0, 0.3])
    X = np.empty((n, 3)); Z = np.empty((n, 2))
    for k in range(n):
        if k > 0:
            x = Phi @ x + rng.multivariate_normal(np.zeros(3), Qd)
        X[k] = x
        Z[k] = H @ x + rng.multivariate_normal(np.zeros(2), R)
    t = np.arange(n) * h
    fr = cd_ekf(lambda t, x, u, th: F @ x, lambda t, x, u, th: F, lambda t, x: H @ x, lambda t, x: H, Q, R, t, Z,
                np.zeros(3), np.eye(3))
    return fr, X


def test_mbf_equals_rts_on_linear_model():
    fr, _ = _linear_problem()
    a, b = mbf_smoother(fr), rts_smoother(fr)
    np.testing.assert_allclose(a.x, b.x, rtol=1e-8, atol=1e-9)
    np.testing.assert_allclose(a.P, b.P, rtol=1e-7, atol=1e-10)


def test_last_smoothed_state_is_the_filtered_one():
    fr, _ = _linear_problem()
    for sm in (mbf_smoother(fr), rts_smoother(fr)):
        np.testing.assert_array_equal(sm.x[-1], fr.x_filt[-1])
        np.testing.assert_allclose(sm.P[-1], fr.P_filt[-1])


def test_smoother_improves_on_filter_and_is_consistent():
    fr, X = _linear_problem(n=1500, seed=4)
    sm = mbf_smoother(fr)
    ef = fr.x_filt - X
    es = sm.x - X
    assert np.sqrt(np.mean(es[:, 2] ** 2)) < np.sqrt(np.mean(ef[:, 2] ** 2))
    # smoothed covariance never exceeds the filtered one
    assert np.all(np.einsum("kii->ki", sm.P) <= np.einsum("kii->ki", fr.P_filt) + 1e-12)
    # and it describes the smoothed error: mean NEES ~ 3 (the smoothed errors are
    # serially correlated, so allow 15 %)
    nees = np.einsum("ki,kij,kj->k", es, np.linalg.inv(sm.P), es)
    assert np.mean(nees) == pytest.approx(3.0, rel=0.15)
