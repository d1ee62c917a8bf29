"""ARMA noise models by the Hannan–Rissanen method, and the inverse-noise prefilter.

``A(q) x_t = C(q) e_t`` with ``A = 1 + a_1 q^-1 + ... + a_na q^-na``, ``C = 1 + c_1 q^-1 + ...``.
Hannan & Rissanen (1982): (1) a long AR model by least squares estimates the innovations; (2) a
linear least-squares regression of ``x_t`` on its own past and the past estimated innovations gives
``A`` and ``C``. Linear algebra only, so it is fast enough for the prefilters of the iterative IV
method (Linder et al. 2015, eqs. 42–43), which are re-estimated at every iteration of every
Monte Carlo run. Benchmarked against ``statsmodels`` ARIMA (maximum likelihood) in
``benchmarks/bench_masscm_arma.py``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from shipid.estimate.fir_kernels import ar_fit
from shipid.numerics.iir_kernels import lfilter as iir_lfilter


@dataclass(frozen=True)
class ARMA:
    """``A(q) x = C(q) e``, ``var(e) = lam``."""

    a: np.ndarray
    c: np.ndarray
    lam: float

    def prefilter(self, x: np.ndarray) -> np.ndarray:
        """Apply ``L = H^-1 = A/C`` (eq. 43) along axis 0 (a 1-D signal through the compiled
        :func:`shipid.numerics.iir_kernels.lfilter`, ``scipy.signal.lfilter``'s numbers)."""
        if np.ndim(x) == 1:
            return iir_lfilter(self.a, self.c, x)
        from scipy.signal import lfilter  # scipy.signal (with scipy.stats) only where it is called

        return lfilter(self.a, self.c, x, axis=0)


def lagged_columns(x: np.ndarray, lags: int, start: int) -> np.ndarray:
    """The lag matrix of an AR regression: columns x_{t-1} ... x_{t-lags} for rows t = start .. n-1 (a view)."""
    n = x.size
    if not lags:
        return np.empty((n - start, 0))
    # strided view, no copy: row t holds x_{t-lags} .. x_{t-1}; reversed to x_{t-1} .. x_{t-lags}
    return np.lib.stride_tricks.sliding_window_view(x[start - lags: n - 1], lags)[:, ::-1]


def _stabilise(p: np.ndarray) -> np.ndarray:
    """Reflect roots of a monic polynomial in q^-1 to inside the unit circle (same spectrum shape)."""
    if p.size <= 1:
        return p
    roots = np.roots(p)
    bad = np.abs(roots) >= 1.0
    if not bad.any():
        return p
    roots[bad] = 1.0 / np.conj(roots[bad])
    roots = roots / np.maximum(1.0, np.abs(roots) / 0.999)
    return np.real(np.poly(roots))


def _ls(X: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Least squares by the normal equations (well conditioned here: lagged, scaled data), lstsq fallback."""
    if X.shape[1] == 0:
        return np.zeros(0)
    G = X.T @ X
    try:
        c = np.linalg.cholesky(G + 1e-12 * np.trace(G) / G.shape[0] * np.eye(G.shape[0]))
        return np.linalg.solve(c.T, np.linalg.solve(c, X.T @ y))
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(X, y, rcond=None)[0]


def ar_gram(x: np.ndarray, p: int) -> tuple[np.ndarray, np.ndarray]:
    """``X^T X`` and ``X^T x[p:]`` for ``X = lagged_columns(x, p, p)`` in O(n p) instead of O(n p^2).

    Column i of X holds ``x_{t-1-i}``, rows ``t = p .. n-1``. The first row of the Gram matrix is a
    correlation; shifting both lags by one moves the summation window by one sample, so
    ``G[i, i+d] = G[0, d] + sum_{l<i} (x[p-2-l] x[p-2-l-d] - x[n-2-l] x[n-2-l-d])``.
    """
    n = x.size
    # c[d] = sum_{t=p}^{n-1} x[t-1] x[t-1-d], d = 0..p-1;  g[j] = sum_t x[t] x[t-1-j]
    c = np.correlate(x[p - 1:n - 1], x[:n - 1], mode="valid")
    g = np.correlate(x[p:], x[:n - 1], mode="valid")
    i = np.arange(p)[:, None]
    d = np.arange(p)[None, :]
    ok = (i + d) < p
    # head/tail products for l = 0..p-2 and lag d (zero where the index would leave the record)
    head_i = p - 2 - i[:-1]                                   # x[p-2-l]
    hi, hj = head_i, head_i - d
    hv = np.where(hj >= 0, x[hi] * x[np.maximum(hj, 0)], 0.0)
    tl = n - 2 - i[:-1]
    tv = x[tl] * x[tl - d]
    corr = np.vstack([np.zeros((1, p)), np.cumsum(hv - tv, axis=0)])      # corr[i, d] = sum_{l<i}
    U = np.where(ok, c[None, :] + corr, 0.0)                  # U[i, d] = G[i, i+d]
    G = np.zeros((p, p))
    ii, dd = np.nonzero(ok)
    G[ii, ii + dd] = U[ii, dd]
    G[ii + dd, ii] = U[ii, dd]
    return G, g


def ar_solve_normal(G: np.ndarray, g: np.ndarray, x: np.ndarray, p: int) -> np.ndarray:
    """Solve ``G th = g`` as :func:`_ls` does (ridge-regularised Cholesky, least-squares fallback)."""
    try:
        c = np.linalg.cholesky(G + 1e-12 * np.trace(G) / G.shape[0] * np.eye(G.shape[0]))
        return np.linalg.solve(c.T, np.linalg.solve(c, g))
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(lagged_columns(x, p, p), x[p:], rcond=None)[0]


def hannan_rissanen(x: np.ndarray, na: int = 4, nc: int = 4, n_long: int | None = None) -> ARMA:
    """Fit an ARMA(na, nc) model to ``x`` (mean removed) by the two-stage Hannan–Rissanen method.

    Parameters
    ----------
    x : ndarray (n,)
    na, nc : int
        Orders of A and C.
    n_long : int, optional
        Order of the first-stage AR model (default ``max(20, 2 (na + nc))``, at most n/5).

    Returns
    -------
    ARMA
        With A and C reflected to be stable / minimum phase, so that the prefilter ``A/C`` is stable.
    """
    x = np.asarray(x, dtype=float)
    x = x - x.mean()
    n = x.size
    scale = np.std(x)
    if not np.isfinite(scale) or scale == 0.0:
        return ARMA(np.ones(1), np.ones(1), 0.0)
    xs = x / scale
    if nc == 0:                                   # pure AR: one least-squares fit is the whole method
        start = na
        if not na:
            return ARMA(np.ones(1), np.ones(1), float(np.mean(xs**2)) * scale**2)
        G, g = ar_gram(xs, na)
        th = ar_solve_normal(G, g, xs, na)
        a = np.concatenate([[1.0], -th])           # the prefilter A(q) is FIR: stable whatever its roots
        eps = np.convolve(a, xs)[start:n]          # = xs[start:] - X @ th
        return ARMA(a, np.ones(1), float(np.mean(eps**2)) * scale**2)
    nl = n_long if n_long is not None else max(20, 2 * (na + nc))
    nl = int(min(nl, max(1, n // 5)))
    X = lagged_columns(xs, nl, nl)
    ar = _ls(X, xs[nl:])
    e = np.zeros(n)
    e[nl:] = xs[nl:] - X @ ar
    start = nl + max(na, nc)
    R = np.column_stack([-lagged_columns(xs, na, start), lagged_columns(e, nc, start)])
    th = _ls(R, xs[start:])
    a = _stabilise(np.concatenate([[1.0], th[:na]]))
    c = _stabilise(np.concatenate([[1.0], th[na:]]))
    eps = iir_lfilter(a, c, xs)[start:]
    lam = float(np.mean(eps**2)) * scale**2
    return ARMA(a, c, lam)


def fit_ar(x: np.ndarray, p: int) -> ARMA:
    """Pure AR(p) by least squares: ``hannan_rissanen(x, p, 0)`` computed by compiled kernels.

    The same estimator and the same arithmetic steps (mean removal, scaling by the std, the O(n p) normal
    equations of :func:`ar_gram`, the ridge-regularised Cholesky solve of :func:`ar_solve_normal`, the
    residual variance of ``A(q) x``) done by :func:`shipid.estimate.fir_kernels.ar_fit`; only the summation
    order differs (rounding level; ``tests/estimate`` compares the two). Falls back to
    :func:`hannan_rissanen` (its least-squares fallback) when the normal equations are not positive definite.
    """

    x = np.asarray(x, dtype=float)
    x = x - x.mean()
    scale = np.std(x)
    if not p or not np.isfinite(scale) or scale == 0.0 or x.size <= 2 * p:
        return hannan_rissanen(x, p, 0, n_long=p)
    ok, a, s2 = ar_fit(x / scale, int(p))
    if not ok:
        return hannan_rissanen(x, p, 0, n_long=p)
    return ARMA(a, np.ones(1), float(s2) * scale**2)


__all__ = ["ARMA", "hannan_rissanen", "fit_ar", "lagged_columns", "ar_gram", "ar_solve_normal"]
