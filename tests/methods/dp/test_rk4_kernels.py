"""The compiled RK4 steps of the DP likelihood against the one Python source (Fossen et al. 1996, seed 001).

The models are written once, as continuous ``f(t, x, u, θ)`` in :mod:`shipid.methods.dp.stage_models`
(eqs. 31–32 and 35–38); their discrete map (eq. 15) and Φ (Table 1) are the package's one RK4
(:func:`shipid.estimate.ekf_augmented.rk4_map`, i.e. :func:`shipid.numerics.integrate.rk4_step_jacobians`).
The numba kernels of :mod:`shipid.methods.dp.loglik` must reproduce that map and its Jacobian to
rounding (rtol 1e-12: the compiled right-hand sides sum the same terms in another order).
"""

from __future__ import annotations

import numpy as np
import pytest

from shipid.methods.dp import loglik
from shipid.methods.dp.pem import thrust_force
from shipid.methods.dp.stage_models import momentum_model, surge_model
from shipid.models import dp
from shipid.vessels import load_vessel

RTOL = 1e-12


@pytest.fixture(scope="module")
def supply():
    return dp.dp_vessel(load_vessel("supply"))


def _theta(v, rng):
    """θ off the packaged values (a point the filter visits while it searches)."""
    return v.theta * (1.0 + 0.3 * rng.standard_normal(9))


def _input(rng):
    """u = [u1 … u6, α6] of eq. 5 (control vector and azimuth angle)."""
    return np.concatenate([rng.uniform(-1.0, 1.0, 6), [rng.uniform(0.0, np.pi)]])


@pytest.mark.parametrize("seed", range(5))
def test_momentum_step_equals_rk4_map(supply, seed):
    rng = np.random.default_rng(seed)
    th = _theta(supply, rng)
    t = np.array([0.0, 0.3, 0.9])                       # bis sample times; uneven steps
    model = momentum_model(supply, th, tuple(range(9)), t, current=False)
    x = np.concatenate([0.05 * rng.standard_normal(3), rng.standard_normal(2), [rng.uniform(-np.pi, np.pi)],
                        1e-3 * rng.standard_normal(3)])
    u = _input(rng)
    A_h, _K = dp.matrices_from_theta(th)
    tau = thrust_force(u[None, :], th, supply.arms)[0]
    for k in range(2):
        want_x = model.f(k, x, u, th)
        want_phi = model.f_jac(k, x, u, th)[0]
        Phi = np.empty((9, 9))
        got_x = loglik._mom_rk4(x, tau, supply.M, supply.Minv, A_h, t[k + 1] - t[k], Phi)
        np.testing.assert_allclose(got_x, want_x, rtol=RTOL, atol=RTOL * np.abs(want_x).max())
        np.testing.assert_allclose(Phi, want_phi, rtol=RTOL, atol=RTOL * np.abs(want_phi).max())
        assert not np.allclose(want_x, x)                # the step moves the state


@pytest.mark.parametrize("seed", range(5))
def test_surge_step_equals_rk4_map(supply, seed):
    rng = np.random.default_rng(seed)
    th = _theta(supply, rng)
    t = np.array([0.0, 0.25, 0.85])
    model = surge_model(supply, th, tuple(range(9)), t)
    x = np.array([0.05 * rng.standard_normal(), rng.standard_normal(), 1e-3 * rng.standard_normal()])
    u = _input(rng)
    tau = thrust_force(u[None, :], th, supply.arms)[0, 0]
    Ac = np.zeros((3, 3))
    Ac[0, 0], Ac[0, 2], Ac[1, 0] = th[0], 1.0, 1.0 / supply.M[0, 0]
    for k in range(2):
        want_x = model.f(k, x, u, th)
        want_phi = model.f_jac(k, x, u, th)[0]
        got_x, Phi = loglik._surge_rk4(x, tau, Ac, t[k + 1] - t[k])
        np.testing.assert_allclose(got_x, want_x, rtol=RTOL, atol=RTOL * np.abs(want_x).max())
        np.testing.assert_allclose(Phi, want_phi, rtol=RTOL, atol=RTOL * np.abs(want_phi).max())
