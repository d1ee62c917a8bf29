"""The shared numba Cholesky kernels (shipid.numerics.numba_linalg) against numpy."""

import importlib
import re
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import shipid
from shipid.numerics import numba_linalg as nl


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


def _callers() -> list[str]:
    """The modules that carry a ``NUMBA_LINALG_KEY`` (the compiled callers of these kernels)."""
    root = Path(shipid.__file__).parent
    return sorted(".".join(("shipid", *f.relative_to(root).with_suffix("").parts)) for f in root.rglob("*.py")
                  if re.search(r"^NUMBA_LINALG_KEY = ", f.read_text(encoding="utf-8"), re.M))


def test_the_callers_are_found():
    assert {"shipid.methods.ebm.kernels", "shipid.methods.mmg.kernels", "shipid.methods.dp.loglik",
            "shipid.methods.masscm.search"} <= set(_callers())


@pytest.mark.parametrize("name", _callers())
def test_every_caller_cache_key_is_current(name):
    """A compiled caller in another file keys its disk cache on this file (numba does not see the dependency).

    If this fails, numba_linalg.py was edited: set ``NUMBA_LINALG_KEY`` in the module named to the value
    printed, which also refreshes that module's cache.
    """
    mod = importlib.import_module(name)
    key = nl.source_key(nl)
    assert mod.NUMBA_LINALG_KEY == key, f"set NUMBA_LINALG_KEY = {key!r} in {name}"
    assert mod.CACHE_VALID
