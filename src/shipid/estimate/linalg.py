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

import numpy as np
from scipy import linalg as sla


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
    c, low = sla.cho_factor(symmetrize(a), lower=True, check_finite=False)
    return sla.cho_solve((c, low), b, check_finite=False)


def kalman_gain(P: np.ndarray, H: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the gain ``K = P H^T S^-1`` and the innovation covariance ``S = H P H^T + R``."""
    S = symmetrize(H @ P @ H.T + R)
    K = psd_solve(S, H @ P).T  # P H^T S^-1 = (S^-1 H P)^T since P, S symmetric
    return K, S


def joseph_update(P: np.ndarray, K: np.ndarray, H: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Joseph-form measurement update ``(I-KH) P (I-KH)^T + K R K^T``, symmetrised."""
    ikh = np.eye(P.shape[0]) - K @ H
    return symmetrize(ikh @ P @ ikh.T + K @ R @ K.T)
