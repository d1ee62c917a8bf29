"""Small dense linear algebra as numba kernels, shared by the compiled filters and smoothers.

The compiled EBM loops (:mod:`shipid.methods.ebm.kernels`) and the compiled MMG step 1
(:mod:`shipid.methods.mmg.kernels`) call these without allocating: the Cholesky factor of
a leading block, the Cholesky solve and the symmetrisation that the batch EKF update of
Yoon & Rhee 2003 (eq. 9) and the RTS gain need. float64, no ``fastmath``; a
matrix that is not positive definite (or holds NaN) is reported by a False return, never
factored.

Cache. numba keys the on-disk cache of a compiled function on the file that defines it
only, not on the compiled functions it calls from other files. A compiled caller in
another module therefore carries :func:`source_key` of this file as a constant and
compiles without the disk cache when the constant does not match the file found at
import (see :data:`shipid.methods.ebm.kernels.NUMBA_LINALG_KEY`); an edit here must
update those constants (their tests say so).
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
from numba import njit

_JIT = dict(cache=True, nogil=True, error_model="numpy")  # no ZeroDivisionError checks in loops


def source_key(module) -> str | None:
    """First 16 hex digits of the SHA-256 of ``module``'s source file; None if it cannot be read.

    The key with which a numba caller checks that a compiled callee of another file is the
    one its on-disk cache was built against (see the module docstring).
    """
    try:
        return hashlib.sha256(Path(module.__file__).read_bytes()).hexdigest()[:16]
    except (OSError, TypeError):
        return None


@njit(**_JIT)
def cholesky_into(A, n, L):
    """Lower Cholesky factor of the leading n × n block of ``A`` into ``L``; False if not PD."""
    for j in range(n):
        s = A[j, j]
        for k in range(j):
            s -= L[j, k] * L[j, k]
        if not (s > 0.0):  # also catches NaN
            return False
        d = np.sqrt(s)
        L[j, j] = d
        for i in range(j + 1, n):
            s = A[i, j]
            for k in range(j):
                s -= L[i, k] * L[j, k]
            L[i, j] = s / d
        for i in range(j):
            L[i, j] = 0.0
    return True


@njit(**_JIT)
def cho_solve_inplace(L, n, B):
    """Solve (L Lᵀ) X = B in place for the leading n rows of B (n × ncol), L from :func:`cholesky_into`."""
    ncol = B.shape[1]
    for i in range(n):  # forward: L Y = B
        d = L[i, i]
        for k in range(i):
            lik = L[i, k]
            for c in range(ncol):
                B[i, c] -= lik * B[k, c]
        for c in range(ncol):
            B[i, c] /= d
    for i in range(n - 1, -1, -1):  # backward: Lᵀ X = Y
        d = L[i, i]
        for k in range(i + 1, n):
            lki = L[k, i]
            for c in range(ncol):
                B[i, c] -= lki * B[k, c]
        for c in range(ncol):
            B[i, c] /= d


@njit(**_JIT)
def symmetrise_inplace(A, n):
    """Replace the leading n × n block of ``A`` by its symmetric part ``(A + Aᵀ)/2``, in place."""
    for i in range(n):
        for j in range(i + 1, n):
            s = 0.5 * (A[i, j] + A[j, i])
            A[i, j] = s
            A[j, i] = s


__all__ = ["source_key", "cholesky_into", "cho_solve_inplace", "symmetrise_inplace"]
