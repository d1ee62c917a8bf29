"""Observed information of the DP prediction-error stage with noise levels the data do not determine.

:func:`shipid.methods.dp.pem.pem_stage` on quadratic stand-ins for −ℓ (known optimum and
Hessian), and the rule :func:`shipid.methods.dp.pem.undetermined_noise` that picks the noise
log-scales held at their optimum when the observed information is formed.
"""

from __future__ import annotations

import numpy as np

from shipid.methods.dp.pem import A_BOUND, undetermined_noise, pem_stage


class _Quadratic:
    """−ℓ = ½ dᵀ A d + extra(a), d = (θ_f − θ*, a − a*); ``extra`` may be flat or concave in a₀."""

    noise_names = ("q_h", "q_b", "sigma_pos")

    def __init__(self, A, theta_star, a_star, free, extra=None):
        self.A, self.ts, self.as_, self.free, self.extra = A, theta_star, a_star, free, extra
        self.n_eval = 0

    def nll(self, theta_full, a):
        self.n_eval += 1
        d = np.concatenate([theta_full[self.free] - self.ts, a - self.as_])
        return 0.5 * d @ self.A @ d + (self.extra(a) if self.extra else 0.0)


def _spd(n, rng):
    Q = rng.standard_normal((n, n))
    return Q @ Q.T + n * np.eye(n)


def test_positive_definite_hessian_holds_nothing():
    rng = np.random.default_rng(11)
    H = _spd(5, rng)
    assert undetermined_noise(H, np.zeros(5), 2) == []


def test_flat_or_concave_noise_direction_is_held_theta_never():
    rng = np.random.default_rng(12)
    H = _spd(5, rng)
    H[3, :] = H[:, 3] = 0.0
    H[3, 3] = -1.0  # noise coordinate 1 (index 3) concave
    assert undetermined_noise(H, np.zeros(5), 2) == [3]
    # indefinite through the coupling only (every diagonal positive): the coupled noise coordinate goes
    H2 = np.diag([4.0, 4.0, 1.0, 1.0, 1.0])
    H2[1, 4] = H2[4, 1] = 3.0
    held = undetermined_noise(H2, np.zeros(5), 2)
    assert held == [4]
    keep = [0, 1, 2, 3]
    np.linalg.cholesky(H2[np.ix_(keep, keep)])
    # an indefinite theta block cannot be repaired by holding noise: every noise held, still not PD
    H3 = np.diag([1.0, -1.0, 1.0, 1.0, 1.0])
    assert undetermined_noise(H3, np.zeros(5), 2) == [2, 3, 4]


def test_noise_next_to_bound_is_held():
    H = np.eye(4)
    y = np.array([0.0, 0.0, A_BOUND - 0.1, 0.5])
    assert undetermined_noise(H, y, 2) == [2]


def test_pem_stage_flat_noise_direction_settles_with_theta_block_covariance():
    """A likelihood flat in a₀ (q_h) and independent of it: θ's covariance is [A⁻¹] of the rest."""
    rng = np.random.default_rng(13)
    free = [1, 4]
    A = _spd(5, rng)
    A[2, :] = A[:, 2] = 0.0  # a₀ (φ index 2) does not enter the likelihood
    ts, a_star = np.array([0.3, -1.2]), np.array([0.0, 0.4, -0.3])
    lik = _Quadratic(A, ts, a_star, free)
    theta_full = np.zeros(9)
    theta_full[free] = ts + np.array([0.05, -0.04])
    res = pem_stage(lik, theta_full, free, np.array([0.1, 0.1]), [], np.zeros((9, 9)), np.array([0.5, 0.0, 0.0]))
    keep = [0, 1, 3, 4]
    C = np.linalg.inv(A[np.ix_(keep, keep)])
    assert res.settled
    assert res.diagnostics["noise_at_bound"] == ["q_h"] and res.diagnostics["noise_held"] == ["q_h"]
    np.testing.assert_allclose(res.theta, ts, atol=1e-6)
    np.testing.assert_allclose(res.cov_free, C[:2, :2], rtol=1e-4)
    assert np.isnan(res.log_scales_std[0]) and np.all(np.isfinite(res.log_scales_std[1:]))


def test_pem_stage_concave_noise_direction_runs_to_bound_and_theta_keeps_std():
    rng = np.random.default_rng(14)
    free = [0, 2]
    A = _spd(5, rng)
    A[2, :] = A[:, 2] = 0.0
    ts, a_star = np.array([1.0, 2.0]), np.array([0.0, 0.0, 0.0])
    lik = _Quadratic(A, ts, a_star, free, extra=lambda a: -0.01 * a[0] ** 2)
    theta_full = np.zeros(9)
    theta_full[free] = ts
    res = pem_stage(lik, theta_full, free, np.array([0.1, 0.1]), [], np.zeros((9, 9)), np.array([-0.5, 0.1, 0.1]))
    assert res.diagnostics["noise_at_bound"] == ["q_h"]
    assert abs(res.log_scales[0]) > A_BOUND - 0.25
    assert res.settled and np.all(np.isfinite(res.cov_free))
    keep = [0, 1, 3, 4]
    np.testing.assert_allclose(res.cov_free, np.linalg.inv(A[np.ix_(keep, keep)])[:2, :2], rtol=1e-4)
