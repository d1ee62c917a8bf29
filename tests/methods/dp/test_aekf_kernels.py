"""The compiled parallel augmented EKF of the DP schemes equals the Python filter (Fossen et al. 1996, Table 1)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from shipid.methods.dp.aekf_kernels import MOMENTUM, SURGE, rk4_aug
from shipid.methods.dp.estimator import DPOptions, run_stage
from shipid.methods.dp.stage_models import momentum_model, surge_model
from shipid.methods.dp.trials import simulate_dp_trial
from shipid.models.dp import dp_vessel
from shipid.numerics.integrate import rk4_step_jacobians
from shipid.vessels import load_vessel

V = dp_vessel(load_vessel("supply"))


def _rel(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


@pytest.mark.parametrize("kind", ["surge", "momentum"])
def test_rk4_aug_is_the_one_rk4(kind):
    """rk4_aug: the state step and both Jacobians of rk4_step_jacobians on the stage model (1e-12)."""
    rng = np.random.default_rng(3)
    th = V.theta * (1 + 0.1 * rng.standard_normal(9))
    u = np.concatenate([rng.uniform(-0.5, 0.5, 6), [0.7]])
    t = np.array([0.0, 0.3])
    if kind == "surge":
        est = [0, 5, 8]
        model = surge_model(V, th, tuple(est), t)
        x = np.array([0.01, 0.2, 1e-4])
        code = SURGE
    else:
        est = [1, 2, 3, 4, 6, 7]
        model = momentum_model(V, th, tuple(est), t, current=False)
        x = np.array([0.01, -0.02, 0.003, 0.5, -0.3, 2.0, 1e-4, -2e-4, 1e-5])
        code = MOMENTUM
    xn_py = model.f(0, x, u, th[est])
    Fx_py, Ft_py = model.f_jac(0, x, u, th[est])
    Fx = np.empty((x.size, x.size))
    Ft = np.empty((x.size, len(est)))
    xn = rk4_aug(code, x, u, th, np.array(est), V.M, V.Minv, np.asarray(V.arms, float), 0.3, Fx, Ft)
    assert _rel(xn, xn_py) < 1e-13
    assert _rel(Fx, Fx_py) < 1e-12
    assert _rel(Ft, Ft_py) < 1e-12


@pytest.mark.parametrize("name,kind", [("SI1", "surge"), ("SI2", "sway-yaw"), ("SI3", "azimuth")])
def test_compiled_stage_equals_python(name, kind):
    """Every θ history, its covariance and the log-likelihood agree to 1e-12 (two passes, considered θ)."""
    trials = [simulate_dp_trial(V, kind, 300.0, 40 + j, dt=1.0) for j in range(2)]
    th = V.theta.copy()
    cov = np.zeros((9, 9))
    if name != "SI1":  # earlier schemes' parameters are considered (Schmidt-Kalman)
        done = [0, 5] if name == "SI2" else [0, 1, 2, 3, 4, 5, 6, 7]
        cov[done, done] = (0.01 * np.abs(th[done])) ** 2
    opt = DPOptions(covariance="ekf")
    fast = run_stage(name, trials, V, th, opt, theta_cov=cov)
    slow = run_stage(name, trials, V, th, replace(opt, compiled=False), theta_cov=cov)
    assert _rel(fast.ekf.theta, slow.ekf.theta) < 1e-12
    assert _rel(fast.ekf.theta_cov, slow.ekf.theta_cov) < 1e-12
    assert abs(fast.ekf.loglik - slow.ekf.loglik) < 1e-12 * abs(slow.ekf.loglik)
    for a, b in zip(fast.ekf.nis, slow.ekf.nis):
        assert _rel(a[np.isfinite(b)], b[np.isfinite(b)]) < 1e-10
    for a, b in zip(fast.ekf.x, slow.ekf.x):
        assert _rel(a, b) < 1e-12
