"""Compiled FIR / lag-product kernels (shipid.estimate.fir_kernels) against the straightforward computations."""

import numpy as np
import pytest

from shipid.estimate.arma import ar_gram, ar_solve_normal, fit_ar, hannan_rissanen
from shipid.estimate.fir_kernels import ar_normal_equations, fir_filter, lag_moments, ridge_cholesky_solve
from shipid.estimate.iv import lag_matrix


def test_fir_filter_equals_convolution():
    rng = np.random.default_rng(0)
    X = np.cumsum(rng.standard_normal((3, 500)), axis=1)
    for p1 in (1, 3, 8, 9, 41):                         # fewer, exactly and more than the 8-tap block
        a = rng.standard_normal(p1)
        Y = fir_filter(a, X)
        ref = np.array([np.convolve(a, x)[:X.shape[1]] for x in X])
        assert np.allclose(Y, ref, rtol=0, atol=1e-13 * np.abs(ref).max())


@pytest.mark.parametrize("nls", [(16, 16, 16, 2), (5, 0, 3, 1), (1, 1, 1, 1), (7, 2, 0, 16)])
def test_lag_moments_equal_explicit_instrument_products(nls):
    """Z^T Z and Z^T T of the lag instruments (45) without forming Z, against the explicit products."""
    rng = np.random.default_rng(sum(nls))
    n, s = 600, 17
    F = np.cumsum(rng.standard_normal((len(nls), n)), axis=1)
    T = np.cumsum(rng.standard_normal((6, n)), axis=1)
    Z = np.column_stack([lag_matrix(F[k], nl, s) for k, nl in enumerate(nls) if nl])
    G, ZtT = lag_moments(F, np.array(nls, dtype=np.int64), T, s)
    assert G.shape == (sum(nls), sum(nls)) and ZtT.shape == (sum(nls), 6)
    assert np.allclose(G, Z.T @ Z, rtol=0, atol=1e-13 * np.abs(G).max())
    assert np.allclose(ZtT, Z.T @ T[:, s:].T, rtol=0, atol=1e-13 * np.abs(ZtT).max())


def test_ar_normal_equations_equal_reference_gram():
    x = np.cumsum(np.random.default_rng(3).standard_normal(900))
    for p in (1, 2, 40):
        G, g, xx = ar_normal_equations(x, p)
        Gr, gr = ar_gram(x, p)
        assert np.allclose(G, Gr, rtol=0, atol=1e-13 * np.abs(Gr).max())
        assert np.allclose(g, gr, rtol=0, atol=1e-13 * np.abs(gr).max())
        assert np.isclose(xx, x[p:] @ x[p:], rtol=1e-13)


def test_ridge_cholesky_solve_equals_reference():
    rng = np.random.default_rng(4)
    A = rng.standard_normal((200, 12))
    G, g = A.T @ A, A.T @ rng.standard_normal(200)
    ok, th = ridge_cholesky_solve(G, g)
    assert ok and np.allclose(th, ar_solve_normal(G, g, None, 12), rtol=1e-11)
    ok, _ = ridge_cholesky_solve(-G, g)                  # not positive definite: reported, not solved
    assert not ok


@pytest.mark.parametrize("seed", [5, 6])
def test_fit_ar_equals_hannan_rissanen_pure_ar(seed):
    """The compiled AR(40) fit of the prefilters (43) is the same estimator as hannan_rissanen(x, p, 0)."""
    from scipy.signal import lfilter
    rng = np.random.default_rng(seed)
    x = lfilter([1.0], [1.0, -1.5, 0.7], rng.standard_normal(3000)) + 0.3
    a, b = fit_ar(x, 40), hannan_rissanen(x, 40, 0, n_long=40)
    assert np.allclose(a.a, b.a, rtol=0, atol=1e-10) and a.c.size == b.c.size == 1
    assert np.isclose(a.lam, b.lam, rtol=1e-12)
    # degenerate inputs take the reference path
    assert fit_ar(np.ones(100), 4).lam == 0.0


@pytest.mark.parametrize("rank_deficient", [False, True])
def test_compiled_projection_qr_equals_iv_compress_products(rank_deficient):
    from shipid.estimate.iv import iv_compress_products, iv_compress_products_compiled
    rng = np.random.default_rng(7)
    Z = rng.standard_normal((800, 20))
    if rank_deficient:                                   # exact collinearity: directions dropped by the rank rule
        Z[:, 5] = Z[:, 3] - 2 * Z[:, 4]
    P = np.column_stack([Z @ rng.standard_normal((20, 5)) + rng.standard_normal((800, 5)), rng.standard_normal(800)])
    a = iv_compress_products_compiled(Z.T @ Z, Z.T @ P, 800)
    b = iv_compress_products(Z.T @ Z, Z.T @ P, 800)
    assert a.rank_ok == b.rank_ok and a.n == b.n
    assert np.allclose(a.R.T @ a.R, b.R.T @ b.R, rtol=1e-11, atol=1e-13 * np.abs(b.R).max() ** 2)
    assert np.allclose(a.R.T @ a.r, b.R.T @ b.r, rtol=1e-11, atol=1e-13 * np.abs(b.R.T @ b.r).max())
    assert np.isclose(a.rss0, b.rss0, rtol=1e-10)
    assert np.allclose(np.abs(np.diag(a.R)), np.abs(np.diag(b.R)), rtol=1e-11)


def test_fewer_instrument_directions_than_regressors_pad_the_factor_with_zero_rows():
    """Three instruments for five regressors: both paths return the (5, 5) factor of the same criterion,
    rows beyond the rank zero, and ``rank_ok`` False (the reference path returned a (3, 5) factor, which
    the stacking of the datasets' moments in masscm.criterion could not take)."""
    from shipid.estimate.iv import iv_compress_products, iv_compress_products_compiled
    rng = np.random.default_rng(11)
    Z = rng.standard_normal((500, 3))
    P = rng.standard_normal((500, 6))
    a = iv_compress_products_compiled(Z.T @ Z, Z.T @ P, 500)
    b = iv_compress_products(Z.T @ Z, Z.T @ P, 500)
    for mo in (a, b):
        assert mo.R.shape == (5, 5) and mo.r.shape == (5,) and not mo.rank_ok
        assert np.all(mo.R[3:] == 0.0) and np.all(mo.r[3:] == 0.0)
    assert np.allclose(a.R.T @ a.R, b.R.T @ b.R, rtol=1e-11, atol=1e-13)
    assert np.allclose(a.R.T @ a.r, b.R.T @ b.r, rtol=1e-11, atol=1e-13)
