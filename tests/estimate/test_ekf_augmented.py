"""Tests of the state-augmented EKF and its parallel configuration (Fossen et al. 1996, Table 1, eqs. 15–25)."""

from __future__ import annotations

import numpy as np
import pytest

from shipid.errors import ConvergenceError
from shipid.estimate.ekf_augmented import (AugmentedModel, augmented_ekf, numerical_jacobian,
                                           parallel_augmented_ekf, rk4_map)
from shipid.numerics.integrate import rk4_step


def _linear_system(seed=0, n=200):
    rng = np.random.default_rng(seed)
    A = np.array([[1.0, 0.1], [-0.05, 0.95]])
    B = np.array([[0.0], [0.1]])
    C = np.array([[1.0, 0.0]])
    Qx = np.diag([1e-4, 4e-4])
    R = np.array([[0.01]])
    u = rng.normal(size=(n, 1))
    x = np.zeros(2)
    Z = np.empty((n, 1))
    for k in range(n):
        Z[k] = C @ x + rng.normal(scale=0.1, size=1)
        x = A @ x + B @ u[k] + rng.multivariate_normal(np.zeros(2), Qx)
    return A, B, C, Qx, R, u, Z


def _kalman_filter(A, B, C, Q, R, x0, P0, Z, U):
    """Textbook linear KF (independent reference: (I-KH)P form, explicit inverse)."""
    x, P = x0.copy(), P0.copy()
    xs, ll = [], 0.0
    for k in range(Z.shape[0]):
        S = C @ P @ C.T + R
        K = P @ C.T @ np.linalg.inv(S)
        nu = Z[k] - C @ x
        x = x + K @ nu
        P = (np.eye(len(x)) - K @ C) @ P
        ll += -0.5 * (nu @ np.linalg.inv(S) @ nu + np.log(np.linalg.det(2 * np.pi * S)))
        xs.append(x.copy())
        x = A @ x + B @ U[k]
        P = A @ P @ A.T + Q
    return np.array(xs), ll


def test_ekf_on_linear_model_equals_kalman_filter():
    A, B, C, Qx, R, u, Z = _linear_system()
    model = AugmentedModel(f=lambda k, x, uu, th: A @ x + B @ uu, h=lambda k, x, th: C @ x, nx=2, ntheta=0,
                           f_jac=lambda k, x, uu, th: (A, np.zeros((2, 0))),
                           h_jac=lambda k, x, th: (C, np.zeros((1, 0))))
    x0, P0 = np.array([0.5, 0.0]), np.eye(2)
    res = augmented_ekf(model, x0, np.zeros(0), P0, Qx, R, Z, u)
    ref, ll = _kalman_filter(A, B, C, Qx, R, x0, P0, Z, u)
    np.testing.assert_allclose(res.x, ref, rtol=1e-9, atol=1e-12)
    assert res.loglik == pytest.approx(ll, rel=1e-10)
    # numerical Jacobians reproduce the analytic ones on a linear model
    num = augmented_ekf(AugmentedModel(f=model.f, h=model.h, nx=2, ntheta=0), x0, np.zeros(0), P0, Qx, R, Z, u)
    np.testing.assert_allclose(num.x, ref, rtol=1e-6, atol=1e-9)


def _param_model():
    """x(k+1) = [x1 + dt x2, x2 + dt(θ1 x2 + θ2 u)], z = x1: a first-order ship-like system."""
    dt = 0.5

    def f(k, x, u, th):
        return np.array([x[0] + dt * x[1], x[1] + dt * (th[0] * x[1] + th[1] * u[0])])

    def fj(k, x, u, th):
        return (np.array([[1.0, dt], [0.0, 1.0 + dt * th[0]]]),
                np.array([[0.0, 0.0], [dt * x[1], dt * u[0]]]))

    return AugmentedModel(f=f, h=lambda k, x, th: x[:1], nx=2, ntheta=2, f_jac=fj,
                          h_jac=lambda k, x, th: (np.array([[1.0, 0.0]]), np.zeros((1, 2))))


def _simulate_param(model, theta, n, seed, q=1e-4, r=0.05):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.choice([-1.0, 1.0], size=n // 20 + 1), 20)[:n, None]
    x = np.zeros(2)
    Z = np.empty((n, 1))
    for k in range(n):
        Z[k] = x[0] + rng.normal(scale=r)
        x = model.f(k, x, u[k], theta) + np.array([0.0, rng.normal(scale=np.sqrt(q))])
    return u, Z


def test_parallel_with_one_trial_equals_plain_augmented_ekf():
    model = _param_model()
    theta = np.array([-0.3, 0.8])
    u, Z = _simulate_param(model, theta, 300, seed=4)
    th0 = np.array([-0.1, 0.3])
    P0x, P0t = np.diag([0.1, 0.1]), np.diag([0.1, 0.5])
    Qx, Qt, R = np.diag([0.0, 1e-4]), np.diag([1e-8, 1e-8]), np.array([[0.0025]])
    from scipy.linalg import block_diag
    plain = augmented_ekf(model, np.zeros(2), th0, block_diag(P0x, P0t), block_diag(Qx, Qt), R, Z, u)
    par = parallel_augmented_ekf(model, [np.zeros(2)], th0, P0x, P0t, Qx, Qt, R, [Z], [u])
    np.testing.assert_array_equal(par.theta, plain.theta)
    np.testing.assert_array_equal(par.x[0], plain.x)
    np.testing.assert_array_equal(par.theta_cov, plain.theta_cov)
    assert par.loglik == plain.loglik
    np.testing.assert_allclose(par.nis[0], plain.nis, rtol=1e-12)
    # and the estimate is consistent with the truth
    err = plain.theta_final - theta
    assert np.all(np.abs(err) < 3 * plain.theta_std[-1])


def test_parallel_two_trials_and_unequal_lengths():
    model = _param_model()
    theta = np.array([-0.3, 0.8])
    u1, Z1 = _simulate_param(model, theta, 300, seed=5)
    u2, Z2 = _simulate_param(model, theta, 200, seed=6)
    args = dict(theta0=np.array([-0.1, 0.3]), P0x=np.diag([0.1, 0.1]), P0theta=np.diag([0.1, 0.5]),
                Qx=np.diag([0.0, 1e-4]), Qtheta=np.zeros((2, 2)), R=np.array([[0.0025]]))
    res = parallel_augmented_ekf(model, [np.zeros(2), np.zeros(2)], measurements=[Z1, Z2], inputs=[u1, u2], **args)
    assert res.x[0].shape == (300, 2) and res.x[1].shape == (200, 2) and res.theta.shape == (300, 2)
    # the shorter trial is frozen after its end (no propagation, no process noise): its state
    # variances can only shrink afterwards (through the correlation with θ), never grow
    assert np.all(res.combined.P_diag[-1, 2:4] <= res.combined.P_diag[199, 2:4] * (1 + 1e-12))
    err = res.theta_final - theta
    assert np.all(np.abs(err) < 3 * res.theta_std[-1])
    # two trials carry more information than the first one alone
    one = parallel_augmented_ekf(model, [np.zeros(2)], measurements=[Z1], inputs=[u1], **args)
    assert np.all(res.theta_std[-1] < one.theta_std[-1])


def test_missing_measurements_are_skipped():
    A, B, C, Qx, R, u, Z = _linear_system(seed=2, n=50)
    Z = Z.copy()
    Z[10:20] = np.nan
    model = AugmentedModel(f=lambda k, x, uu, th: A @ x + B @ uu, h=lambda k, x, th: C @ x, nx=2, ntheta=0)
    res = augmented_ekf(model, np.zeros(2), np.zeros(0), np.eye(2), Qx, R, Z, u)
    assert np.all(np.isnan(res.nis[10:20])) and np.all(np.isfinite(res.nis[:10]))
    assert np.all(res.nis_dof[10:20] == 0)
    # variance grows while blind
    assert res.P_diag[19, 0] > res.P_diag[10, 0]


def test_divergence_is_reported():
    model = AugmentedModel(f=lambda k, x, u, th: x * 1e200, h=lambda k, x, th: x, nx=1, ntheta=0)
    with pytest.raises(ConvergenceError, match="diverged"), np.errstate(over="ignore", invalid="ignore"):
        augmented_ekf(model, np.ones(1), np.zeros(0), np.eye(1), np.eye(1), np.eye(1), np.ones((10, 1)))


def _pendulum():
    """A forced damped pendulum ``f(t, x, u, θ)`` (time enters through the forcing) and its Jacobians."""
    def f(t, x, u, th):
        return np.array([x[1], -th[0] * np.sin(x[0]) - th[1] * x[1] + u[0] * np.cos(t)])

    def jac(t, x, u, th):
        return (np.array([[0.0, 1.0], [-th[0] * np.cos(x[0]), -th[1]]]),
                np.array([[0.0, 0.0], [-np.sin(x[0]), -x[1]]]))
    return f, jac


def test_rk4_map_jacobian_is_exact_derivative():
    f, jac = _pendulum()
    t, x, u, th, dt = 0.7, np.array([0.4, -0.2]), np.array([0.3]), np.array([2.0, 0.5]), 0.3
    xn, Px, Pt = rk4_map(f, jac, t, x, u, th, dt)
    Jx = numerical_jacobian(lambda s: rk4_map(f, jac, t, s, u, th, dt)[0], x, 1e-6)
    Jt = numerical_jacobian(lambda s: rk4_map(f, jac, t, x, u, s, dt)[0], th, 1e-6)
    np.testing.assert_allclose(Px, Jx, atol=1e-8)
    np.testing.assert_allclose(Pt, Jt, atol=1e-8)


def test_rk4_map_state_is_the_one_rk4():
    """The discrete map of eq. 15 is the simulators' RK4 step, to the last bit; t is threaded through."""
    f, jac = _pendulum()
    t, x, u, th, dt = 0.7, np.array([0.4, -0.2]), np.array([0.3]), np.array([2.0, 0.5]), 0.3
    xn, _, _ = rk4_map(f, jac, t, x, u, th, dt)
    np.testing.assert_array_equal(xn, rk4_step(f, t, x, u, th, dt))
    assert not np.allclose(xn, rk4_map(f, jac, t + 1.0, x, u, th, dt)[0])
    _, Px, Pt = rk4_map(lambda tt, s, uu, p: f(tt, s, uu, th), lambda tt, s, uu, p: (jac(tt, s, uu, th)[0],
                                                                                       np.zeros((2, 0))),
                        t, x, u, np.zeros(0), dt)
    assert Px.shape == (2, 2) and Pt.shape == (2, 0)


def test_consider_states_keep_their_estimate_and_inflate_the_others():
    """Schmidt–Kalman consider parameter: its estimate is not updated, its uncertainty is carried."""
    model = _param_model()
    theta = np.array([-0.3, 0.8])
    u, Z = _simulate_param(model, theta, 300, seed=7)
    from scipy.linalg import block_diag
    P0x, Qx, R = np.diag([0.1, 0.1]), np.diag([0.0, 1e-4]), np.array([[0.0025]])
    th0 = np.array([-0.1, 0.8])  # θ2 "frozen" at its value from an earlier identification
    P_known = block_diag(P0x, np.diag([0.1, 1e-12]))
    P_uncertain = block_diag(P0x, np.diag([0.1, 0.05 ** 2]))
    Q = block_diag(Qx, np.zeros((2, 2)))
    fixed = augmented_ekf(model, np.zeros(2), th0, P_known, Q, R, Z, u, consider=[3])
    cons = augmented_ekf(model, np.zeros(2), th0, P_uncertain, Q, R, Z, u, consider=[3])
    assert np.all(cons.theta[:, 1] == 0.8)                     # not estimated
    assert cons.theta_cov[-1, 1, 1] == pytest.approx(0.05 ** 2)  # its variance is untouched
    assert cons.theta_std[-1, 0] > 1.2 * fixed.theta_std[-1, 0]  # θ1 carries θ2's uncertainty
    # and a free θ2 would have been moved by the data
    free = augmented_ekf(model, np.zeros(2), th0, P_uncertain, Q, R, Z, u)
    assert free.theta[-1, 1] != 0.8
