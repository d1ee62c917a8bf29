"""Tests of unit-length scaling and ridge regression (seed 002 eqs. 16–18)."""

import warnings

import numpy as np
import pytest

from shipid.estimate.ridge import hoerl_kennard_k, ols, ridge, unit_length_scale


def _collinear(n=400, seed=0, noise=0.05):
    rng = np.random.default_rng(seed)
    a = rng.normal(size=n)
    H = np.column_stack([a, a + 0.05 * rng.normal(size=n), rng.normal(size=n) * 3.0, a ** 3])
    theta = np.array([1.0, -0.5, 0.02, 0.3])
    y = H @ theta + noise * rng.normal(size=n)
    return H, y, theta


def test_unit_length_scaling_gives_correlation_matrix():
    H, y, _ = _collinear()
    sc = unit_length_scale(H, y)
    C = sc.correlation
    np.testing.assert_allclose(np.diag(C), 1.0)
    # uncentred correlation: cosine between columns
    c01 = H[:, 0] @ H[:, 1] / np.linalg.norm(H[:, 0]) / np.linalg.norm(H[:, 1])
    assert C[0, 1] == pytest.approx(c01)
    assert sc.y @ sc.y == pytest.approx(1.0)


def test_ridge_with_k_to_zero_is_ols():
    """DESIGN practice 8: ridge with k → 0 equals OLS."""
    H, y, _ = _collinear()
    ref = ols(H, y)
    np.testing.assert_allclose(ridge(H, y, 0.0).theta, ref, rtol=1e-9)
    np.testing.assert_allclose(ridge(H, y, 1e-13).theta, ref, rtol=1e-6)
    f = ridge(H, y, 0.0)
    assert f.Cp == pytest.approx(f.p)  # Mallows' Cp of the full OLS model is p


def test_ols_standard_errors_match_statsmodels():
    sm = pytest.importorskip("statsmodels.api")
    H, y, _ = _collinear(noise=0.3)
    f = ridge(H, y, 0.0)
    r = sm.OLS(y, H).fit()
    np.testing.assert_allclose(f.theta, r.params, rtol=1e-9)
    np.testing.assert_allclose(f.se, r.bse, rtol=1e-8)
    assert f.R2_uncentred == pytest.approx(r.rsquared, rel=1e-10)  # statsmodels: uncentred without constant


def test_back_transformation_recovers_exact_coefficients():
    H, _, theta = _collinear()
    y = H @ theta
    y = y + 1e-9 * np.random.default_rng(1).normal(size=y.size)
    f = ridge(H, y)
    np.testing.assert_allclose(f.theta, theta, rtol=1e-5)
    assert f.R2 == pytest.approx(1.0, abs=1e-12)


def test_hoerl_kennard_fixed_point_and_shrinkage():
    H, y, _ = _collinear(noise=0.5)
    f = ridge(H, y)
    assert f.converged and f.k > 0
    b = f.b
    # fixed point of k = p sigma^2 / b'b
    assert f.k == pytest.approx(f.p * f.sigma2 / (b @ b), rel=1e-5)
    # ridge shrinks the scaled coefficient vector
    assert b @ b < ridge(H, y, 0.0).b @ ridge(H, y, 0.0).b
    assert f.kappa > 100  # columns 0, 1 nearly collinear


def test_non_convergence_is_reported():
    H, y, _ = _collinear(noise=0.5)
    sc = unit_length_scale(H, y)
    C, g = sc.W.T @ sc.W, sc.W.T @ sc.y
    k, it, conv = hoerl_kennard_k(C, g, 0.01, tol=0.0, max_iter=3)
    assert not conv and it == 3
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        f = ridge(H, y, tol=0.0, max_iter=2)
    assert not f.converged and any("did not converge" in str(x.message) for x in w)


def test_zero_column_is_an_error():
    H, y, _ = _collinear()
    H[:, 2] = 0.0
    with pytest.raises(ValueError, match="identically zero"):
        ridge(H, y)


def test_runaway_hoerl_kennard_falls_back_to_one_step_k():
    """On a response unrelated to the regressors the k iteration runs away (k grows, b
    shrinks, until bᵀb underflows); the fit must say so and use the one-step
    Hoerl–Kennard–Baldwin k = p σ̂² / b_OLSᵀ b_OLS, not raise or return k = inf."""
    import warnings

    from shipid.estimate.ridge import ridge, unit_length_scale

    rng = np.random.default_rng(0)
    H = rng.normal(size=(50, 3))
    y = rng.normal(size=50)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fit = ridge(H, y)
    assert not fit.converged
    assert any("did not converge" in str(w.message) for w in caught)
    sc = unit_length_scale(H, y)
    b_ols = np.linalg.solve(sc.W.T @ sc.W, sc.W.T @ sc.y)
    sigma2 = float(np.sum((sc.y - sc.W @ b_ols) ** 2)) / (50 - 3)
    assert fit.k == pytest.approx(3 * sigma2 / float(b_ols @ b_ols), rel=1e-12)
    assert np.all(np.isfinite(fit.theta)) and np.all(np.isfinite(fit.se))


def test_hac_ols_matches_statsmodels_newey_west():
    """cov="hac" with k = 0 is the Newey–West OLS covariance (Bartlett kernel, small-sample factor
    n/(n − p)); reference: statsmodels OLS cov_type="HAC" with use_correction=True."""
    sm = pytest.importorskip("statsmodels.api")
    rng = np.random.default_rng(5)
    n = 500
    e = np.zeros(n)
    for i in range(1, n):  # AR(1) errors: serially correlated residuals
        e[i] = 0.8 * e[i - 1] + rng.normal()
    H = np.column_stack([np.ones(n), rng.normal(size=n).cumsum() / 10, np.sin(np.arange(n) / 20.0)])
    y = H @ np.array([1.0, 0.5, -2.0]) + 0.1 * e
    f = ridge(H, y, 0.0, cov="hac", bandwidth=12)
    ref = sm.OLS(y, H).fit(cov_type="HAC", cov_kwds={"maxlags": 12, "use_correction": True})
    np.testing.assert_allclose(f.theta, ref.params, rtol=1e-9)
    np.testing.assert_allclose(f.se, ref.bse, rtol=1e-8)
    # serial correlation: the iid formula is optimistic here
    assert np.all(f.se_iid < f.se)


def test_hac_segments_do_not_pair_rows_across_trials():
    from shipid.estimate.ridge import newey_west

    g = np.arange(12, dtype=float).reshape(6, 2)
    seg = np.array([0, 0, 0, 1, 1, 1])
    S = newey_west(g, 2, seg)
    ref = newey_west(g[:3], 2) + newey_west(g[3:], 2)
    np.testing.assert_allclose(S, ref)


def test_ridge_bias_enters_hac_std():
    H, y, _ = _collinear(noise=0.2)
    f = ridge(H, y, 0.05, cov="hac", bandwidth=3)
    np.testing.assert_allclose(f.se, np.sqrt(f.se_sampling ** 2 + f.bias ** 2))
    assert np.any(np.abs(f.bias) > 0)
