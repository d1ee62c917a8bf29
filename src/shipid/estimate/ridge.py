"""Ridge regression on unit-length-scaled regressors (Yoon & Rhee 2003, §4, eqs. 16–18).

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

The textbook standard errors (``cov="iid"``) assume independent residuals; smoothed
force histories are serially correlated, so they are optimistic. ``cov="hac"`` gives the
Newey–West (1987) sandwich with Andrews' (1991) bandwidth and adds the ridge bias.
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
    se_iid: np.ndarray | None = None
    cov_kind: str = "iid"
    bandwidth: int = 0
    bias: np.ndarray | None = None
    se_sampling: np.ndarray | None = None
    vif: np.ndarray | None = None


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


def andrews_bandwidth(g: np.ndarray, segments: np.ndarray | None = None, *, cap: float = 0.25) -> int:
    """Bartlett-kernel bandwidth of Andrews (1991, eq. 6.4, AR(1) plug-in) for the scores ``g`` (n, p).

    ``α̂ = Σ_a 4 ρ_a² σ_a⁴ / ((1 − ρ_a)⁶ (1 + ρ_a)²) / Σ_a σ_a⁴ / (1 − ρ_a)⁴`` from AR(1) fits of each
    column, ``S = 1.1447 (α̂ n)^{1/3}``; capped at ``cap`` times the shortest segment (ρ → 1 would
    give an unbounded lag window).
    """
    g = np.asarray(g, float)
    n = g.shape[0]
    seg = np.zeros(n, int) if segments is None else np.asarray(segments)
    same = seg[1:] == seg[:-1]
    num = den = 0.0
    for a in range(g.shape[1]):
        x0, x1 = g[:-1, a][same], g[1:, a][same]
        d = float(x0 @ x0)
        if d <= 0:
            continue
        rho = float(np.clip(x1 @ x0 / d, -0.999, 0.999))
        s2 = float(np.mean((x1 - rho * x0) ** 2))
        num += 4 * rho ** 2 * s2 ** 2 / ((1 - rho) ** 6 * (1 + rho) ** 2)
        den += s2 ** 2 / (1 - rho) ** 4
    alpha = num / den if den > 0 else 0.0
    shortest = min(np.bincount(np.unique(seg, return_inverse=True)[1]))
    return int(max(1, min(np.ceil(1.1447 * (alpha * n) ** (1.0 / 3.0)), cap * shortest)))


def newey_west(g: np.ndarray, bandwidth: int, segments: np.ndarray | None = None) -> np.ndarray:
    """Long-run covariance ``Γ₀ + Σ_{j=1}^{L} (1 − j/(L+1)) (Γ_j + Γ_jᵀ)`` of the scores ``g`` (n, p),
    ``Γ_j = Σ_t g_t g_{t−j}ᵀ`` over pairs in the same segment (Newey & West 1987, Bartlett kernel)."""
    g = np.asarray(g, float)
    n = g.shape[0]
    seg = np.zeros(n, int) if segments is None else np.asarray(segments)
    S = g.T @ g
    for j in range(1, int(bandwidth) + 1):
        if j >= n:
            break
        m = (seg[j:] == seg[:-j])[:, None]
        G = (g[j:] * m).T @ g[:-j]
        S += (1.0 - j / (bandwidth + 1.0)) * (G + G.T)
    return 0.5 * (S + S.T)


def ridge(H: np.ndarray, y: np.ndarray, k: float | None = None, *, tol: float = 1e-6,
          max_iter: int = 200, cov: str = "iid", segments: np.ndarray | None = None,
          bandwidth: int | None = None) -> RidgeFit:
    """Ridge regression of ``y`` on ``H`` with unit-length scaling (eqs. 16–18).

    Parameters
    ----------
    H : ndarray (N, p)
    y : ndarray (N,)
    k : float, optional
        Biasing parameter; ``None`` chooses it by the Hoerl–Kennard iteration;
        ``0`` gives ordinary least squares.
    cov : str
        ``"iid"``: ``Cov(b) = σ̂² A⁻¹ WᵀW A⁻¹`` (``A = WᵀW + kI``), which assumes independent
        residuals. ``"hac"``: the sandwich ``A⁻¹ S A⁻¹ · n/(n − p)`` with ``S`` the Newey–West
        long-run covariance of the scores ``W_i e_i`` (:func:`newey_west`), which stays valid
        when the residuals are serially correlated; the reported ``se`` then also adds the
        estimated ridge bias ``−k A⁻¹ b`` in quadrature (a root-mean-square error), so that
        ``±2 se`` covers the truth and not only ``E[b]``. ``se_sampling`` keeps the HAC part alone.
    segments : ndarray of int, optional
        Segment label of each row (one per trial): lags never pair rows of different segments.
    bandwidth : int, optional
        Newey–West lag window; default :func:`andrews_bandwidth`.

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
    cov_b_iid = sigma2 * Ainv @ C @ Ainv
    scale = np.sqrt(sc.S_yy / sc.S_jj)
    theta = b * scale
    sc2 = np.outer(scale, scale)
    se_iid = np.sqrt(np.maximum(np.diag(cov_b_iid * sc2), 0.0))
    bias = -k * (Ainv @ b) * scale
    try:
        Cinv_diag = np.diag(np.linalg.inv(C))
    except np.linalg.LinAlgError:
        Cinv_diag = np.full(p, np.inf)
    bw = 0
    if cov == "iid":
        cov_theta = cov_b_iid * sc2
        se = se_sampling = se_iid
    elif cov == "hac":
        gsc = W * res[:, None]
        bw = andrews_bandwidth(gsc, segments) if bandwidth is None else int(bandwidth)
        S = newey_west(gsc, bw, segments)
        cov_b = Ainv @ S @ Ainv * (n / (n - p))
        cov_theta = cov_b * sc2
        se_sampling = np.sqrt(np.maximum(np.diag(cov_theta), 0.0))
        se = np.sqrt(se_sampling ** 2 + bias ** 2)
    else:
        raise ValueError(f"cov must be 'iid' or 'hac', not {cov!r}")
    return RidgeFit(theta=theta, se=se, b=b, k=float(k), iterations=iters, converged=conv,
                    kappa=kappa, R2=float(R2), R2_uncentred=float(R2u), Cp=float(Cp),
                    sigma2=float(sigma2), correlation=C, response_correlation=g,
                    cov_theta=cov_theta, n=n, p=p, se_iid=se_iid, cov_kind=cov, bandwidth=bw,
                    bias=bias, se_sampling=se_sampling, vif=Cinv_diag)


def ols(H: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Ordinary least squares via ``lstsq`` (reference for the k → 0 check)."""
    return np.linalg.lstsq(np.asarray(H, float), np.asarray(y, float), rcond=None)[0]


__all__ = ["Scaled", "RidgeFit", "unit_length_scale", "hoerl_kennard_k", "ridge", "ols", "newey_west", "andrews_bandwidth"]
