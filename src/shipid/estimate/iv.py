"""Building blocks of extended instrumental-variable estimators (Söderström & Stoica 1989, ch. 8).

Pure functions: lag matrices, black-box ARX models for instruments, and the weighted IV moment
compression used by Linder et al. (2015) eqs. (39)–(41).

With instruments ``Z`` (N × n_z), prefiltered output ``y`` (N) and regressors ``Phi`` (N × n_g), the
extended IV criterion with weighting ``Q = (Z^T Z / N)^-1`` is

    V(g) = || Z^T (y - Phi g) / N ||_Q^2 = || Qz^T (y - Phi g) ||^2 / N,   Z = Qz Rz (thin QR)

i.e. the least-squares fit of the projections of ``y`` and ``Phi`` on the instrument space (two-stage
least squares). :func:`iv_compress` reduces it further to an ``n_g × n_g`` triangular system so that a
nonlinear search over physical parameters costs almost nothing per evaluation.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from shipid.estimate.fir_kernels import project_qr
from shipid.numerics.iir_kernels import lfilter


def lag_matrix(x: np.ndarray, n_lags: int, start: int) -> np.ndarray:
    """Columns ``x_t, x_{t-1}, ..., x_{t-n_lags+1}`` for rows ``t = start, ..., n-1``."""
    x = np.asarray(x, dtype=float)
    n = x.size
    if n_lags > start + 1:
        raise ValueError("start must be at least n_lags - 1")
    if not n_lags:
        return np.empty((n - start, 0))
    w = np.lib.stride_tricks.sliding_window_view(x[start - n_lags + 1:], n_lags)   # rows: x_{t-n+1} .. x_t
    return w[:, ::-1]


def arx_regressors(y: np.ndarray, u: np.ndarray, na: int, nb: int, s: int) -> np.ndarray:
    """``[-y_{t-1} .. -y_{t-na}, u_t .. u_{t-nb+1}, y_t]`` for rows ``t = s .. n-1``, in Fortran order (each column
    contiguous: LAPACK's layout, which ``numpy.linalg.qr`` copies into about a third faster than a C-order array;
    the factor is the same either way)."""
    n = y.size
    R = np.empty((n - s, na + nb + 1), order="F")
    for j in range(1, na + 1):
        np.negative(y[s - j:n - j], out=R[:, j - 1])
    for j in range(nb):
        R[:, na + j] = u[s - j:n - j]
    R[:, na + nb] = y[s:]
    return R


def arx_fit(y: np.ndarray, u: np.ndarray, na: int = 4, nb: int = 5) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares ARX model ``A(q) y = B(q) u`` with ``B = b_0 + ... + b_{nb-1} q^{-nb+1}``.

    Used as the black-box model from the rudder to each measured signal in the initialising iteration
    of Algorithm 1 (Linder et al. 2015, step A(b)(i)). Returns ``(b, a)`` for ``lfilter``; ``a`` is
    reflected to be stable so that the simulated instrument cannot diverge.
    """
    y = np.asarray(y, dtype=float)
    u = np.asarray(u, dtype=float)
    s = max(na, nb - 1)
    from scipy.linalg import lapack, solve_triangular  # scipy.linalg only where it is called

    R = arx_regressors(y, u, na, nb, s)
    # least squares by a thin QR of [R, y] (O(n k^2), no SVD of the long matrix); lstsq when rank deficient.
    # The factor is LAPACK's dgeqrf in place on the Fortran-order R (numpy.linalg.qr calls the same routine on a
    # copy: the same triangle, without copying the n x (k + 1) matrix twice)
    k = na + nb
    qr, _, _, info = lapack.dgeqrf(R, overwrite_a=True)
    Rf = np.triu(qr[:min(R.shape)])
    d = np.abs(np.diag(Rf[:k, :k]))
    if info == 0 and d.size == k and d.min() > 1e-10 * max(d.max(), 1e-300):
        th = solve_triangular(Rf[:k, :k], Rf[:k, k])
    else:                                   # R was overwritten by the factor: the regressors again
        th, *_ = np.linalg.lstsq(arx_regressors(y, u, na, nb, s)[:, :k], y[s:], rcond=None)
    a = np.concatenate([[1.0], th[:na]])
    roots = np.roots(a)
    if np.any(np.abs(roots) >= 1.0):
        roots = np.where(np.abs(roots) >= 1.0, 0.999 / np.conj(roots), roots)
        a = np.real(np.poly(roots))
    return th[na:], a


def arx_simulate(b: np.ndarray, a: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Noise-free simulation ``y = B/A u`` of a 1-D input from rest (:func:`shipid.numerics.iir_kernels.lfilter`,
    ``scipy.signal.lfilter``'s numbers)."""
    return lfilter(b, a, u)


@functools.lru_cache(maxsize=8)
def _lag_layout(nls: tuple[int, ...]):
    lag = np.concatenate([np.arange(nl) for nl in nls])
    sig = np.concatenate([np.full(nl, k) for k, nl in enumerate(nls)])
    nz = lag.size
    a, b = np.arange(nz)[:, None], np.arange(nz)[None, :]
    mn = np.minimum(lag[:, None], lag[None, :])
    ba, bb = a - mn, b - mn                                     # the entry on a lag-0 row or column
    f0 = np.where(lag[ba] == 0, sig[ba] * nz + bb, sig[bb] * nz + ba).ravel()   # into F0 (by symmetry)
    qidx = (a * (2 * nz - 1) + (b - a + nz - 1)).ravel()       # skew: Q[a, b - a + nz - 1] = D[a, b]
    g1 = (a * (nz + 1) + b).ravel()                             # GCp[a, b]   = GC[a - 1, b - 1]
    g2 = (ba * (nz + 1) + bb).ravel()                           # GCp[ba, bb] = GC[a - mn - 1, b - mn - 1]
    return nz, f0, qidx, g1, g2, np.flatnonzero(lag == 0)


def lag_gram(ZT: np.ndarray, h: np.ndarray, nls: tuple[int, ...]) -> np.ndarray:
    """``Z^T Z`` for an instrument matrix of lags, in O(m n_sig n_z) instead of O(m n_z^2).

    Parameters
    ----------
    ZT : ndarray (n_z, m)
        ``Z`` transposed; its rows are lags ``0 .. nls[k]-1`` of signal k, signal after signal
        (the layout of (45)), i.e. ``Z[t, (k, i)] = x_k[t - i]``.
    h : ndarray (n_z,)
        The row of ``Z`` one sample before its first row (``x_k[t0 - 1 - i]``).
    nls : tuple of int
        Lags per signal.

    Shifting both lags by one moves the summation window back one sample, so
    ``S[(k,i+1), (l,j+1)] = S[(k,i), (l,j)] + h h^T - e e^T`` (``e`` the last row of ``Z``): every entry is
    a lag-0 row of ``S`` (a small product) plus a diagonal partial sum of ``D = h h^T - e e^T``.
    """
    lag0 = _lag_layout(tuple(int(v) for v in nls))[-1]
    return lag_gram_from(ZT[lag0] @ ZT.T, h, ZT[:, -1], nls)


def lag_gram_from(F0: np.ndarray, h: np.ndarray, e: np.ndarray, nls: tuple[int, ...]) -> np.ndarray:
    """:func:`lag_gram` from its products: ``F0 = Z[:, lag0]^T Z`` (n_sig, n_z), the products of every
    signal's lag-0 column with all columns, and ``e`` the last row of ``Z`` (``h`` as in :func:`lag_gram`).

    Lets a caller form ``F0`` block by block without holding ``Z`` (:func:`shipid.methods.masscm.moments.lag_products`).
    """
    nz, f0, qidx, g1, g2, _lag0 = _lag_layout(tuple(int(v) for v in nls))
    D = np.outer(h, h) - np.outer(e, e)
    Q = np.zeros(nz * (2 * nz - 1))
    Q[qidx] = D.ravel()
    Qc = np.cumsum(Q.reshape(nz, 2 * nz - 1), axis=0)           # cumulative sums along the diagonals
    GCp = np.zeros((nz + 1, nz + 1))
    GCp[1:, 1:] = Qc.ravel()[qidx].reshape(nz, nz)
    GCf = GCp.ravel()
    return (F0.ravel()[f0] + GCf[g1] - GCf[g2]).reshape(nz, nz)


@dataclass(frozen=True)
class IVMoments:
    """Compressed IV criterion of one dataset: ``V(g) = ||R g - r||^2 + rss0`` (scaled by 1/N elsewhere).

    Attributes
    ----------
    R : ndarray (n_g, n_g)
        Upper-triangular factor of the projected regressors.
    r : ndarray (n_g,)
    rss0 : float
        Residual part orthogonal to the regressors (the minimum of the unweighted criterion).
    n : int
        Number of samples used.
    rank_ok : bool
        False when the instrument matrix is rank deficient (not informative).
    """

    R: np.ndarray
    r: np.ndarray
    rss0: float
    n: int
    rank_ok: bool


def iv_compress(Z: np.ndarray, y: np.ndarray, Phi: np.ndarray, rtol: float = 1e-12) -> IVMoments:
    """Compress the extended-IV criterion with ``Q = (Z^T Z/N)^-1`` (eqs. 40–41) to a small triangle.

    Works from the moment matrices ``Z^T Z`` and ``Z^T [Phi, y]`` (one pass over the data): with the
    eigen-decomposition ``Z^T Z = V S V^T`` the projections are ``S^-1/2 V^T Z^T [Phi, y]`` (equal to
    ``Qz^T [Phi, y]`` up to an orthogonal rotation, which leaves the criterion unchanged). Instrument
    directions with eigenvalues below ``rtol`` times the largest are dropped instead of inverting a
    singular Q (lagged instruments of smooth signals are strongly collinear). With fewer directions kept
    than parameters the factor is padded with zero rows (the same criterion; ``rank_ok`` False).
    """
    return iv_compress_products(Z.T @ Z, Z.T @ np.column_stack([Phi, y]), y.size, rtol)


def iv_compress_products(ZtZ: np.ndarray, ZtP: np.ndarray, n: int, rtol: float = 1e-12) -> IVMoments:
    """:func:`iv_compress` from the moment matrices ``Z^T Z`` and ``Z^T [Phi, y]`` (``n`` samples).

    For callers that form the products themselves (e.g. from a transposed, contiguous instrument matrix).
    """
    s, V = np.linalg.eigh(ZtZ)
    keep = s > rtol * max(s[-1], 1e-300)
    P = (V[:, keep].T @ ZtP) / np.sqrt(s[keep])[:, None]
    ng = ZtP.shape[1] - 1
    Rf = np.zeros((ng + 1, ng + 1))
    Rq = np.linalg.qr(P, mode="r")
    Rf[:Rq.shape[0]] = Rq               # fewer directions than columns: rows beyond the rank are zero
    R = Rf[:ng, :ng]
    r = Rf[:ng, ng]
    rss0 = float(Rf[ng, ng] ** 2)
    return IVMoments(R=R, r=r, rss0=rss0, n=n, rank_ok=bool(keep.sum() >= ng))


def iv_compress_products_compiled(ZtZ: np.ndarray, ZtP: np.ndarray, n: int, rtol: float = 1e-12) -> IVMoments:
    """:func:`iv_compress_products` with the projection and QR compiled
    (:func:`shipid.estimate.fir_kernels.project_qr`); the eigen-decomposition is the same LAPACK call."""

    s, V = np.linalg.eigh(ZtZ)
    Rf, kept = project_qr(s, V, np.ascontiguousarray(ZtP), float(rtol))
    ng = ZtP.shape[1] - 1
    rss0 = float(Rf[ng, ng] ** 2) if kept > ng else 0.0
    return IVMoments(R=Rf[:ng, :ng].copy(), r=Rf[:ng, ng].copy(), rss0=rss0, n=n, rank_ok=bool(kept >= ng))


__all__ = ["iv_compress_products_compiled", "lag_matrix", "arx_regressors", "arx_fit", "arx_simulate", "IVMoments", "iv_compress", "iv_compress_products", "lag_gram",
           "lag_gram_from"]
