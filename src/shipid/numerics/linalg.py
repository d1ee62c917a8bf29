"""Numerically careful linear-algebra pieces shared by every estimator.

Why these forms (DESIGN.md practice 6):

* covariance updates use the Joseph form ``(I - K H) P (I - K H)^T + K R K^T``,
  which stays symmetric positive semi-definite under rounding, unlike ``(I - K H) P``;
* every covariance is symmetrised after an update, because rounding makes
  ``P`` drift away from symmetry and the drift compounds over thousands of steps;
* positive definiteness is checked with a Cholesky factorisation, the cheapest
  test that is also exact in floating point;
* linear solves with a covariance use its Cholesky factor (``psd_solve``), never
  an explicit inverse.
"""

from __future__ import annotations

import functools

import numpy as np


_TPC: list = []


def one_blas_thread():
    """Context manager (and decorator) that runs BLAS/LAPACK on one thread.

    OpenBLAS splits the reductions of ``dot``/``gemv`` (and LAPACK built on them) between
    its threads, so the last bits of a result depend on how many threads it runs, i.e. on
    the machine's core count and on ``OPENBLAS_NUM_THREADS``. Iterative estimators
    (Algorithm 1 of Linder et al. 2015, the EKFs) amplify such differences to ~1e-9 relative. Every
    number shipid reports is computed under this limit, so a result is the same in one
    process, in N campaign workers (which run one thread each) and on any core count.
    The matrices are small (tens of columns), so threads only cost here. The controller
    (a scan of the loaded libraries, ~2 ms) is made once per process.
    """
    if not _TPC:
        from threadpoolctl import ThreadpoolController

        _TPC.append(ThreadpoolController())
    return _TPC[0].limit(limits=1)


def single_threaded(fn):
    """Decorator: call ``fn`` under :func:`one_blas_thread` (see there for why)."""
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with one_blas_thread():
            return fn(*args, **kwargs)
    return wrapper


class NotPositiveDefiniteError(np.linalg.LinAlgError):
    """A matrix that must be positive definite is not."""


def symmetrize(a: np.ndarray) -> np.ndarray:
    """Return ``(a + a.T) / 2``."""
    return 0.5 * (a + np.swapaxes(a, -1, -2))


def is_positive_definite(a: np.ndarray) -> bool:
    """True when the symmetric matrix ``a`` has a Cholesky factor."""
    try:
        np.linalg.cholesky(a)
    except np.linalg.LinAlgError:
        return False
    return True


def check_positive_definite(a: np.ndarray, what: str = "covariance") -> np.ndarray:
    """Raise :class:`NotPositiveDefiniteError` unless ``a`` is positive definite; return ``a``."""
    if not np.all(np.isfinite(a)):
        raise NotPositiveDefiniteError(f"{what} has non-finite entries")
    if not is_positive_definite(a):
        w = np.linalg.eigvalsh(symmetrize(a))
        raise NotPositiveDefiniteError(f"{what} is not positive definite (smallest eigenvalue {w[0]:.3g})")
    return a


def psd_solve(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve ``a x = b`` for symmetric positive definite ``a`` through its Cholesky factor."""
    from scipy.linalg import cho_factor, cho_solve  # scipy.linalg only where it is called

    c, low = cho_factor(symmetrize(a), lower=True, check_finite=False)
    return cho_solve((c, low), b, check_finite=False)


def kalman_gain(P: np.ndarray, H: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the gain ``K = P H^T S^-1`` and the innovation covariance ``S = H P H^T + R``."""
    S = symmetrize(H @ P @ H.T + R)
    K = psd_solve(S, H @ P).T  # P H^T S^-1 = (S^-1 H P)^T since P, S symmetric
    return K, S


def joseph_update(P: np.ndarray, K: np.ndarray, H: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Joseph-form measurement update ``(I-KH) P (I-KH)^T + K R K^T``, symmetrised."""
    ikh = np.eye(P.shape[0]) - K @ H
    return symmetrize(ikh @ P @ ikh.T + K @ R @ K.T)
