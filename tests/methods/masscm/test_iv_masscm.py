"""IV building blocks (estimate.iv) and Hannan–Rissanen ARMA (estimate.arma) used by Algorithm 1."""

import numpy as np
from scipy.signal import lfilter

from shipid.estimate.arma import hannan_rissanen
from shipid.estimate.iv import arx_fit, arx_simulate, iv_compress, lag_matrix


def test_lag_matrix():
    x = np.arange(10.0)
    L = lag_matrix(x, 3, 4)
    assert L.shape == (6, 3)
    assert np.array_equal(L[0], [4, 3, 2]) and np.array_equal(L[-1], [9, 8, 7])


def test_arx_recovers_noise_free_system():
    rng = np.random.default_rng(0)
    u = rng.standard_normal(2000)
    b_true, a_true = np.array([0.0, 0.5, -0.2]), np.array([1.0, -1.5, 0.7])
    y = lfilter(b_true, a_true, u)
    b, a = arx_fit(y, u, na=2, nb=3)
    assert np.allclose(a, a_true, atol=1e-10) and np.allclose(b, b_true, atol=1e-10)
    assert np.allclose(arx_simulate(b, a, u), y, atol=1e-8)


def test_iv_compress_equals_two_stage_least_squares():
    rng = np.random.default_rng(1)
    n = 3000
    z = rng.standard_normal((n, 6))
    x = z @ rng.standard_normal((6, 3)) + 0.5 * rng.standard_normal((n, 3))
    y = x @ np.array([1.0, -2.0, 0.5]) + rng.standard_normal(n)
    mo = iv_compress(z, y, x)
    g_iv = np.linalg.solve(mo.R, mo.r)
    P = z @ np.linalg.solve(z.T @ z, z.T)                 # textbook 2SLS with Q = (Z'Z)^-1
    g_2sls = np.linalg.solve(x.T @ P @ x, x.T @ P @ y)
    assert np.allclose(g_iv, g_2sls, rtol=1e-9)
    # criterion value: ||Qz'(y - X g)||^2 = ||R g - r||^2 + rss0
    g = np.array([0.3, 0.1, -0.4])
    e = y - x @ g
    assert np.isclose(e @ P @ e, np.sum((mo.R @ g - mo.r) ** 2) + mo.rss0, rtol=1e-9)


def test_hannan_rissanen_recovers_arma21():
    rng = np.random.default_rng(2)
    a_true, c_true = np.array([1.0, -1.2, 0.5]), np.array([1.0, 0.4])
    e = rng.standard_normal(40000) * 0.3
    x = lfilter(c_true, a_true, e)
    m = hannan_rissanen(x, na=2, nc=1)
    assert np.allclose(m.a, a_true, atol=0.03) and np.allclose(m.c, c_true, atol=0.03)
    assert np.isclose(m.lam, 0.09, rtol=0.05)
    w = m.prefilter(x)[100:]                                # the prefilter (43) whitens
    ac = np.array([np.dot(w[:-k], w[k:]) for k in range(1, 11)]) / np.dot(w, w)
    assert np.max(np.abs(ac)) < 4 / np.sqrt(w.size)


def test_hannan_rissanen_stabilises():
    rng = np.random.default_rng(3)
    x = np.cumsum(rng.standard_normal(3000))               # a random walk: the AR part must be made stable
    m = hannan_rissanen(x, na=2, nc=2)
    assert np.all(np.abs(np.roots(m.a)) < 1) and np.all(np.abs(np.roots(m.c)) < 1)


def test_pure_ar_fit():
    rng = np.random.default_rng(4)
    a_true = np.array([1.0, -1.6, 0.8])
    x = lfilter([1.0], a_true, rng.standard_normal(30000))
    m = hannan_rissanen(x, na=2, nc=0)
    assert np.allclose(m.a, a_true, atol=0.02) and m.c.size == 1 and np.isclose(m.lam, 1.0, rtol=0.05)


def test_lag_gram_equals_explicit_products():
    """The O(n p) Gram of the AR regression equals X^T X, X^T x built from the explicit lag matrix."""
    from shipid.estimate.arma import ar_gram, lagged_columns
    x = np.cumsum(np.random.default_rng(11).standard_normal(700))
    for p in (1, 3, 40):
        X = np.ascontiguousarray(lagged_columns(x, p, p))
        G, g = ar_gram(x, p)
        assert np.allclose(G, X.T @ X, rtol=1e-12, atol=1e-12 * np.abs(G).max())
        assert np.allclose(g, X.T @ x[p:], rtol=1e-12, atol=1e-12 * np.abs(g).max())


def test_lag_gram_equals_explicit_instrument_gram():
    """Z^T Z of a lag-structured instrument matrix (45) from the lag-0 rows and edge corrections."""
    from shipid.estimate.iv import lag_gram
    rng = np.random.default_rng(12)
    n, s, nls = 400, 17, (16, 5, 1, 2)
    F = np.cumsum(rng.standard_normal((len(nls), n)), axis=1)
    Z = np.column_stack([lag_matrix(F[k], nl, s) for k, nl in enumerate(nls)])
    h = np.concatenate([F[k, s - 1 - np.arange(nl)] for k, nl in enumerate(nls)])
    G = lag_gram(np.ascontiguousarray(Z.T), h, nls)
    assert np.allclose(G, Z.T @ Z, rtol=1e-12, atol=1e-13 * np.abs(G).max())
