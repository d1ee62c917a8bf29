"""The compiled fixed-θ likelihood filters of the DP models against the reference augmented EKF (seed 001)."""

from __future__ import annotations

import numpy as np
import pytest

from shipid.methods.dp import estimator as m
from shipid.methods.dp.stage_models import prepare
from shipid.methods.dp.pem import StageLikelihood
from shipid.methods.dp.trials import simulate_dp_trial
from shipid.models.dp import dp_vessel
from shipid.vessels import load_vessel


@pytest.fixture(scope="module")
def supply():
    return dp_vessel(load_vessel("supply"))


@pytest.mark.parametrize("name,kind,free", [("SI1", "surge", (0,)), ("SI2", "sway-yaw", (1,)),
                                            ("SI3", "azimuth", (8,))])
def test_loglik_equals_augmented_ekf_with_fixed_theta(supply, name, kind, free):
    """ℓ of the compiled filter = ℓ of Table 1's filter run with a (numerically) zero θ covariance.

    Two 200-s trials with a gap in the fixes; θ off the truth (so the data do not fit exactly).
    """
    trials = [simulate_dp_trial(supply, kind, 200.0, 40 + j) for j in range(2)]
    x = trials[0]["x"].copy()
    x[30:35] = np.nan
    trials[0] = trials[0].with_channels(x=x)
    theta = supply.theta * np.array([1.1, 0.9, 1.0, 1.2, 0.95, 1.05, 0.9, 1.1, 1.05])
    opt = m.DPOptions(passes=1, covariance="ekf", theta0_std=tuple([1e-12] * 9))
    ref = m.run_stage(name, trials, supply, theta, opt, free=free)
    data = [prepare(t, supply, kind) for t in trials]
    lik = StageLikelihood(kind, data, supply, m.DPOptions())
    a = np.zeros(len(lik.noise_names))
    assert -lik.nll(theta, a) == pytest.approx(ref.ekf.loglik, rel=1e-9)
    # the noise scales enter as intensities × e^{2a} and std × e^{a}
    a2 = np.full(len(a), 0.3)
    o = m.DPOptions()
    scaled = m.DPOptions(passes=1, covariance="ekf", theta0_std=tuple([1e-12] * 9), q_h=o.q_h * np.exp(0.6),
                         q_b=o.q_b * np.exp(0.6), sigma_pos=o.sigma_pos * np.exp(0.3),
                         sigma_psi=o.sigma_psi * np.exp(0.3) if kind != "surge" else o.sigma_psi)
    if kind == "surge":
        a2 = a2[:3]
    ref2 = m.run_stage(name, trials, supply, theta, scaled, free=free)
    assert -lik.nll(theta, a2) == pytest.approx(ref2.ekf.loglik, rel=1e-9)
