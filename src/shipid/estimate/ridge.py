"""Ridge regression on unit-length-scaled regressors (seed 002, Yoon & Rhee 2003, §4, eqs. 16–18).

For one mode (surge, sway or yaw) with regressor matrix ``H`` (N × p) and
response ``y`` (N):

* unit-length scaling **without centring** (§4.2: the intercepts have no physical
  meaning): ``W_ij = H_ij / sqrt(S_jj)``, ``y*_i = y_i / sqrt(S_yy)`` with
  ``S_jj = Σ_i H_ij²`` and ``S_yy = Σ_i y_i²``; ``WᵀW`` is then the matrix of
  (uncentred) correlation coefficients of Tables 1–2, and ``Wᵀy*`` the correlation of
  each regressor with the response;
* ridge estimate (eq. 18) ``b(k) = (WᵀW + k I)⁻¹ Wᵀ y*`` with the biasing
  parameter ``k`` chosen by Hoerl & Kennard's iterative procedure (Hoerl, Kennard &
  Baldwin 1975; Hoerl & Kennard 1976): ``k₀ = p σ̂² / b_OLSᵀ b_OLS`` and
  ``k_{i+1} = p σ̂² / b(k_i)ᵀ b(k_i)`` until the relative change is below ``tol``,
  with ``σ̂²`` the OLS residual variance of the scaled model;
* back-transformation (eq. 17) ``θ_j = b_j sqrt(S_yy / S_jj)``;
* diagnostics (Table 4): condition number ``κ = λ_max/λ_min`` of ``WᵀW``,
  coefficient of multiple determination ``R² = 1 − SSE/SST`` (centred SST, as
  Montgomery & Peck 1982 define it; the uncentred value is reported too),
  Mallows' ``C_p = SSE_k/σ̂² − N + 2 tr(H_k)`` with the ridge hat matrix ``H_k``
  (Mallows 1973; equals p for k = 0), and standard errors from
  ``Cov(b) = σ̂² (WᵀW + kI)⁻¹ WᵀW (WᵀW + kI)⁻¹``.

The standard errors assume independent residuals; smoothed force histories are
serially correlated, so they are optimistic (stated in every Result that uses them).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Scaled:
    """Unit-length scaled regression problem (eq. 16)."""

    W: np.ndarray
    y: np.ndarray
    S_jj: np.ndarray
    S_yy: float

    @property
    def correlation(self) -> np.ndarray:
        """Correlation matrix WᵀW of the regressors (Tables 1–2)."""
        return self.W.T @ self.W

    @property
    def response_correlation(self) -> np.ndarray:
        """Correlation of each regressor with the response, Wᵀy*."""
        return self.W.T @ self.y


def unit_length_scale(H: np.ndarray, y: np.ndarray) -> Scaled:
    """Scale the columns of ``H`` and ``y`` to unit length (no centring), §4.2."""
    H = np.asarray(H, dtype=float)
    y = np.asarray(y, dtype=float)
    S_jj = np.einsum("ij,ij->j", H, H)
    if np.any(S_jj <= 0):
        bad = np.flatnonzero(S_jj <= 0).tolist()
        raise ValueError(f"regressor column(s) {bad} are identically zero")
    S_yy = float(y @ y)
    if S_yy <= 0:
        raise ValueError("the response is identically zero")
    return Scaled(W=H / np.sqrt(S_jj), y=y / np.sqrt(S_yy), S_jj=S_jj, S_yy=S_yy)


@dataclass(frozen=True)
class RidgeFit:
    """A ridge fit of one mode.

    Attributes
    ----------
    theta, se : ndarray (p,)
        Coefficients in the original units (eq. 17) and their standard errors.
    b : ndarray (p,)
        Scaled coefficients (eq. 18).
    k : float
        Biasing parameter used.
    iterations : int
        Hoerl–Kennard iterations (0 when ``k`` was given).
    converged : bool
    kappa, R2, R2_uncentred, Cp : float
        Table 4 diagnostics.
    sigma2 : float
        OLS residual variance of the scaled model.
    correlation : ndarray (p, p)
        WᵀW.
    response_correlation : ndarray (p,)
    cov_theta : ndarray (p, p)
    n, p : int
    """

    theta: np.ndarray
    se: np.ndarray
    b: np.ndarray
    k: float
    iterations: int
    converged: bool
    kappa: float
    R2: float
    R2_uncentred: float
    Cp: float
    sigma2: float
    correlation: np.ndarray
    response_correlation: np.ndarray
    cov_theta: np.ndarray
    n: int
    p: int


def _solve(C: np.ndarray, g: np.ndarray, k: float) -> np.ndarray:
    return np.linalg.solve(C + k * np.eye(C.shape[0]), g)


def hoerl_kennard_k(C: np.ndarray, g: np.ndarray, sigma2: float, *, tol: float = 1e-6,
                    max_iter: int = 200) -> tuple[float, int, bool]:
    """Hoerl–Kennard iterative biasing parameter for scaled normal equations ``C b = g``.

    Returns ``(k, iterations, converged)``.

    On weak data the iteration can run away: each larger ``k`` shrinks ``b``, which
    makes the next ``k`` larger still, until ``bᵀb`` underflows to zero. That breakdown
    is reported as not converged and the one-step Hoerl–Kennard–Baldwin value
    ``k₀ = p σ̂² / b_OLSᵀ b_OLS`` (the first iterate) is returned instead of an
    infinite ``k``.
    """
    p = C.shape[0]
    b = _solve(C, g, 0.0)
    bb = float(b @ b)
    if not bb > 0.0 or not np.isfinite(bb):
        return 0.0, 0, False  # zero OLS solution: no shrinkage can help
    k0 = k = p * sigma2 / bb
    for it in range(1, max_iter + 1):
        b = _solve(C, g, k)
        bb = float(b @ b)
        if not bb > 0.0 or not np.isfinite(bb):
            return k0, it, False  # runaway k (see above)
        k_new = p * sigma2 / bb
        if not np.isfinite(k_new):
            return k0, it, False
        if abs(k_new - k) <= tol * max(k, 1e-300):
            return k_new, it, True
        k = k_new
    return k, max_iter, False


def ridge(H: np.ndarray, y: np.ndarray, k: float | None = None, *, tol: float = 1e-6,
          max_iter: int = 200) -> RidgeFit:
    """Ridge regression of ``y`` on ``H`` with unit-length scaling (eqs. 16–18).

    Parameters
    ----------
    H : ndarray (N, p)
    y : ndarray (N,)
    k : float, optional
        Biasing parameter; ``None`` chooses it by the Hoerl–Kennard iteration;
        ``0`` gives ordinary least squares.

    Returns
    -------
    RidgeFit
        A warning is issued (and ``converged`` is False) when the iteration for
        ``k`` does not settle.
    """
    sc = unit_length_scale(H, y)
    W, ys = sc.W, sc.y
    n, p = W.shape
    if n <= p:
        raise ValueError(f"need more samples than coefficients (have {n} for {p})")
    C = W.T @ W
    g = W.T @ ys
    b_ols = _solve(C, g, 0.0)
    sse_ols = float(np.sum((ys - W @ b_ols) ** 2))
    sigma2 = sse_ols / (n - p)
    if k is None:
        k, iters, conv = hoerl_kennard_k(C, g, sigma2, tol=tol, max_iter=max_iter)
        if not conv:
            warnings.warn(f"Hoerl–Kennard iteration for k did not converge after {iters} steps "
                          f"(using k = {k:.3g})", RuntimeWarning, stacklevel=2)
    else:
        k, iters, conv = float(k), 0, True
    A = C + k * np.eye(p)
    Ainv = np.linalg.inv(A)
    b = Ainv @ g
    res = ys - W @ b
    sse = float(res @ res)
    eig = np.linalg.eigvalsh(C)
    kappa = float(eig[-1] / eig[0]) if eig[0] > 0 else float("inf")
    yc = ys - ys.mean()
    R2 = 1.0 - sse / float(yc @ yc)
    R2u = 1.0 - sse / float(ys @ ys)
    tr_hat = float(np.sum(eig / (eig + k)))
    Cp = sse / sigma2 - n + 2.0 * tr_hat
    cov_b = sigma2 * Ainv @ C @ Ainv
    scale = np.sqrt(sc.S_yy / sc.S_jj)
    theta = b * scale
    cov_theta = cov_b * np.outer(scale, scale)
    se = np.sqrt(np.maximum(np.diag(cov_theta), 0.0))
    return RidgeFit(theta=theta, se=se, b=b, k=float(k), iterations=iters, converged=conv,
                    kappa=kappa, R2=float(R2), R2_uncentred=float(R2u), Cp=float(Cp),
                    sigma2=float(sigma2), correlation=C, response_correlation=g,
                    cov_theta=cov_theta, n=n, p=p)


def ols(H: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Ordinary least squares via ``lstsq`` (reference for the k → 0 check)."""
    return np.linalg.lstsq(np.asarray(H, float), np.asarray(y, float), rcond=None)[0]


__all__ = ["Scaled", "RidgeFit", "unit_length_scale", "hoerl_kennard_k", "ridge", "ols"]
