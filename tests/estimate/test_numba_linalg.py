"""The shared numba Cholesky kernels (shipid.estimate.numba_linalg) against numpy."""

from types import SimpleNamespace

import numpy as np

from shipid.estimate import numba_linalg as nl


def _spd(rng, n):
    a = rng.standard_normal((n, n))
    return a @ a.T + n * np.eye(n)


def test_cholesky_into_equals_numpy_on_a_leading_block():
    rng = np.random.default_rng(11)
    A = np.full((7, 7), np.nan)
    A[:5, :5] = _spd(rng, 5)
    L = np.full((7, 7), 99.0)
    assert nl.cholesky_into(A, 5, L)
    np.testing.assert_allclose(L[:5, :5], np.linalg.cholesky(A[:5, :5]), rtol=1e-13, atol=1e-13)
    assert np.all(L[5:, :] == 99.0) and np.all(L[:, 5:] == 99.0)  # outside the block untouched


def test_cholesky_into_refuses_indefinite_and_nan():
    L = np.empty((3, 3))
    assert not nl.cholesky_into(np.diag([1.0, -1.0, 1.0]), 3, L)
    assert not nl.cholesky_into(np.array([[1.0, 0, 0], [0, np.nan, 0], [0, 0, 1.0]]), 3, L)


def test_cho_solve_inplace_equals_solve():
    rng = np.random.default_rng(12)
    A = _spd(rng, 6)
    B = rng.standard_normal((6, 4))
    L = np.empty((6, 6))
    assert nl.cholesky_into(A, 6, L)
    X = B.copy()
    nl.cho_solve_inplace(L, 6, X)
    np.testing.assert_allclose(X, np.linalg.solve(A, B), rtol=1e-11, atol=1e-12)


def test_source_key_is_a_hash_of_the_file_and_none_without_one():
    key = nl.source_key(nl)
    assert isinstance(key, str) and len(key) == 16
    assert nl.source_key(SimpleNamespace(__file__=None)) is None          # built-in module
    assert nl.source_key(SimpleNamespace(__file__="/nonexistent/x.py")) is None


def test_symmetrise_inplace_touches_the_leading_block_only():
    rng = np.random.default_rng(13)
    A = rng.standard_normal((5, 5))
    want = A.copy()
    want[:3, :3] = 0.5 * (A[:3, :3] + A[:3, :3].T)
    nl.symmetrise_inplace(A, 3)
    np.testing.assert_array_equal(A, want)
