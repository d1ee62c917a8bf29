"""Tests of the continuous–discrete EKF (seed 002 §3.1, eq. 9)."""

import numpy as np
import pytest

from shipid.estimate.cd_ekf import cd_ekf, taylor_discretise, van_loan
from shipid.numerics.integrate import rk4_step


def _double_integrator(q=0.5, r=0.3, h=0.5, n=200, seed=0):
    """Linear test model: position/velocity, ẍ = w, z = position + noise."""
    F = np.array([[0.0, 1.0], [0.0, 0.0]])
    Q = np.diag([0.0, q])
    Hm = np.array([[1.0, 0.0]])
    R = np.array([[r ** 2]])
    Phi = np.array([[1.0, h], [0.0, 1.0]])
    Qd = q * np.array([[h ** 3 / 3, h ** 2 / 2], [h ** 2 / 2, h]])  # exact (Van Loan by hand)
    rng = np.random.default_rng(seed)
    x = np.array([0.0, 1.0])
    X = np.empty((n, 2)); Z = np.empty((n, 1))
    for k in range(n):
        if k > 0:
            x = Phi @ x + rng.multivariate_normal(np.zeros(2), Qd)
        X[k] = x
        Z[k] = Hm @ x + rng.normal(0, r)
    t = np.arange(n) * h
    return dict(F=F, Q=Q, H=Hm, R=R, Phi=Phi, Qd=Qd, X=X, Z=Z, t=t)


def _run(m, x0, P0):
    return cd_ekf(lambda t, x, u, th: m["F"] @ x, lambda t, x, u, th: m["F"], lambda t, x: m["H"] @ x,
                  lambda t, x: m["H"], m["Q"], m["R"], m["t"], m["Z"], x0, P0)


def test_prediction_is_the_one_rk4_with_held_input_and_parameters():
    """f(t, x, u, θ): between t_k and t_{k+1} the state follows rk4_step with u[k] held and θ passed."""
    m = _double_integrator(n=30)
    n = m["t"].size
    u = np.column_stack([np.sin(0.3 * m["t"])])

    def f(t, x, uk, th):
        return np.array([x[1], -th[0] * np.sin(x[0]) + th[1] * uk[0] + 0.1 * np.cos(t)])

    def F(t, x, uk, th):
        return np.array([[0.0, 1.0], [-th[0] * np.cos(x[0]), 0.0]])

    th = np.array([0.8, 2.0])
    fr = cd_ekf(f, F, lambda t, x: m["H"] @ x, lambda t, x: m["H"], m["Q"], m["R"], m["t"], m["Z"],
                np.zeros(2), np.eye(2), u=u, theta=th, substeps=2)
    for k in range(1, n):
        h = m["t"][k] - m["t"][k - 1]
        x = rk4_step(f, m["t"][k - 1], fr.x_filt[k - 1], u[k - 1], th, 0.5 * h)
        x = rk4_step(f, m["t"][k - 1] + 0.5 * h, x, u[k - 1], th, 0.5 * h)
        np.testing.assert_array_equal(fr.x_pred[k], x)


def test_discretisation_matches_closed_form():
    m = _double_integrator()
    for fn in (van_loan, taylor_discretise):
        Phi, Qd = fn(m["F"], m["Q"], 0.5)
        np.testing.assert_allclose(Phi, m["Phi"], atol=1e-14)
        np.testing.assert_allclose(Qd, m["Qd"], rtol=1e-12, atol=1e-15)


def test_taylor_equals_van_loan_on_random_model():
    rng = np.random.default_rng(3)
    F = rng.normal(size=(6, 6)) * 0.4
    B = rng.normal(size=(6, 6))
    Q = B @ B.T
    a, b = van_loan(F, Q, 0.8), taylor_discretise(F, Q, 0.8)
    np.testing.assert_allclose(a[0], b[0], atol=1e-13)
    np.testing.assert_allclose(a[1], b[1], atol=1e-12)


def test_linear_model_equals_textbook_kalman_filter():
    """DESIGN practice 8: on a linear model the EKF is the Kalman filter."""
    m = _double_integrator()
    x0 = np.array([0.0, 0.0]); P0 = np.eye(2) * 4.0
    fr = _run(m, x0, P0)
    x, P = x0.copy(), P0.copy()
    for k in range(len(m["t"])):
        if k > 0:
            x = m["Phi"] @ x
            P = m["Phi"] @ P @ m["Phi"].T + m["Qd"]
        np.testing.assert_allclose(fr.x_pred[k], x, rtol=1e-10, atol=1e-10)
        S = m["H"] @ P @ m["H"].T + m["R"]
        K = P @ m["H"].T @ np.linalg.inv(S)
        x = x + K @ (m["Z"][k] - m["H"] @ x)
        P = (np.eye(2) - K @ m["H"]) @ P
        np.testing.assert_allclose(fr.x_filt[k], x, rtol=1e-9, atol=1e-10)
        np.testing.assert_allclose(fr.P_filt[k], P, rtol=1e-9, atol=1e-12)


def test_innovations_are_consistent():
    m = _double_integrator(n=2000, seed=7)
    fr = _run(m, m["X"][0], np.eye(2) * 1e-6)
    # E[NIS] = number of measurements (1); 2000 samples: sd of the mean ~ sqrt(2/2000) = 0.03
    assert np.nanmean(fr.nis) == pytest.approx(1.0, abs=0.1)
    # filtered error within its covariance
    e = fr.x_filt - m["X"]
    nees = np.einsum("ki,kij,kj->k", e, np.linalg.inv(fr.P_filt), e)
    assert np.mean(nees) == pytest.approx(2.0, abs=0.2)


def test_missing_measurement_skips_update():
    m = _double_integrator(n=20)
    m["Z"] = m["Z"].copy()
    m["Z"][5] = np.nan
    fr = _run(m, np.zeros(2), np.eye(2))
    np.testing.assert_array_equal(fr.x_filt[5], fr.x_pred[5])
    assert np.isnan(fr.nis[5]) and np.isfinite(fr.nis[6])
