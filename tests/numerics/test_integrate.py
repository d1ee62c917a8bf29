"""Integrators: RK4 convergence order, adaptive solvers against the exact solution, closed-loop inputs.

Reference solutions are exact: a forced linear system written as an autonomous linear
system (the forcing cos ωt, sin ωt appended to the state), solved by the matrix exponential.
"""

import numpy as np
import pytest
from scipy.linalg import expm

from shipid.numerics.integrate import simulate

# Damped oscillator (ω_n = 1.3 rad/s, ζ = 0.2) driven by b·cos(ω t) plus a constant input b·u.
A = np.array([[0.0, 1.0], [-1.69, -0.52]])
b = np.array([0.0, 1.0])
W = 0.7


def f_forced(t, x, u, theta):
    return A @ x + b * (np.cos(W * t) + u[0])


def exact_forced(t, x0, u0):
    """x(t) of f_forced from the augmented autonomous system z = [x, cos ωt, sin ωt, u]."""
    Z = np.zeros((5, 5))
    Z[:2, :2] = A
    Z[:2, 2] = b            # + b cos ωt
    Z[:2, 4] = b            # + b u (u constant)
    Z[2, 3] = -W            # d/dt cos = -ω sin
    Z[3, 2] = W             # d/dt sin =  ω cos
    z0 = np.r_[x0, 1.0, 0.0, u0]
    return np.array([expm(Z * tk) @ z0 for tk in np.atleast_1d(t)])[:, :2]


def test_rk4_is_fourth_order():
    x0 = np.array([1.0, -0.5])
    T = 8.0
    exact = exact_forced(T, x0, 0.3)[0]
    hs, errs = [], []
    for n in (20, 40, 80, 160, 320):
        t = np.linspace(0.0, T, n + 1)
        sim = simulate(f_forced, t, x0, np.full(n + 1, 0.3), method="rk4")
        hs.append(T / n)
        errs.append(np.linalg.norm(sim.x[-1] - exact))
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert abs(slope - 4.0) < 0.2, (slope, errs)
    assert 1e-12 < errs[-1] < 1e-7   # small, yet far above round-off, so the slope is the truncation order


def test_rk4_substeps_equal_finer_grid():
    x0 = np.array([1.0, 0.0])
    t = np.linspace(0, 4, 41)
    coarse = simulate(f_forced, t, x0, np.zeros(41), method="rk4", substeps=4)
    fine_t = np.linspace(0, 4, 161)
    fine = simulate(f_forced, fine_t, x0, np.zeros(161), method="rk4")
    np.testing.assert_allclose(coarse.x, fine.x[::4], rtol=0, atol=1e-13)


@pytest.mark.parametrize("method", ["RK45", "DOP853", "LSODA"])
def test_adaptive_solvers_match_exact(method):
    x0 = np.array([0.2, 1.0])
    t = np.linspace(0.0, 10.0, 51)
    sim = simulate(f_forced, t, x0, np.full(51, -0.4), method=method, rtol=1e-10, atol=1e-12)
    ref = exact_forced(t, x0, -0.4)
    np.testing.assert_allclose(sim.x, ref, rtol=0, atol=1e-7)


def test_closed_loop_callback_is_held_and_recorded():
    # dx/dt = u with u = -k x evaluated at each sample and held: the exact discrete
    # solution is x_{k+1} = (1 - k h) x_k (RK4 is exact for a constant derivative).
    k, h = 0.5, 0.1
    t = np.arange(0, 5.0 + h / 2, h)
    calls = []

    def law(tt, x):
        calls.append(tt)
        return np.array([-k * x[0]])

    sim = simulate(lambda tt, x, u, th: u.copy(), t, np.array([2.0]), law)
    np.testing.assert_allclose(sim.x[:, 0], 2.0 * (1 - k * h) ** np.arange(t.size), rtol=1e-12)
    np.testing.assert_allclose(sim.u[:, 0], -k * sim.x[:, 0], rtol=1e-12)
    np.testing.assert_array_equal(calls, t)     # once per sample, in order


def test_input_length_mismatch_is_an_error():
    with pytest.raises(ValueError, match="samples"):
        simulate(f_forced, np.linspace(0, 1, 11), np.zeros(2), np.zeros(10))
