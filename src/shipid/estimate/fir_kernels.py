"""Compiled (numba) kernels for FIR-prefiltered lag products: the IV moments of (45) and the AR Gram.

Algorithm 1 of Linder et al. (2015) rebuilds, at every iteration and for every dataset, the moment
matrices ``Z^T Z`` and ``Z^T [Phi, y]`` of prefiltered lag instruments (45) with the FIR prefilter
``L = A(q)`` of the AR noise model (43), and refits that AR model (42). The straightforward computations
(``np.convolve`` per signal, an explicit instrument matrix, ``Z^T Z`` by matrix product, the explicit AR
regressor matrix) remain in :mod:`shipid.estimate.iv`, :mod:`shipid.estimate.arma` and
:mod:`shipid.methods.masscm.estimator` as the reference paths; the tests compare these kernels with them.

* :func:`fir_filter` — ``y = A(q) x`` from rest (what ``np.convolve(a, x)[:n]`` and ``lfilter(a, 1, x)``
  compute), row by row.
* :func:`lag_moments` — ``Z^T Z`` and ``Z^T P`` of lag instruments ``Z[t, (k, i)] = f_k[t - i]``,
  ``t = s .. n-1``, without forming ``Z``: the products with the lag-0 rows, then every other entry of
  ``Z^T Z`` from a lag-0 entry plus the diagonal edge corrections of :func:`shipid.estimate.iv.lag_gram`.
* :func:`ar_normal_equations` — ``X^T X``, ``X^T x`` and ``x^T x`` of the AR(p) regression
  (:func:`shipid.estimate.arma.ar_gram`): lag-0 correlations plus edge corrections.

Compiled with ``cache=True``. The long dot products of :func:`lag_moments` (:func:`_lag_products`),
:func:`ar_normal_equations` and the Cholesky solve may be reassociated (``fastmath={"reassoc",
"contract"}``: vectorised partial sums, fused multiply-add) — only the summation order differs from the
reference paths (rounding level, compared in the tests); nothing else is relaxed (no finite-math
assumptions). :func:`project_qr` finishes the IV compression after the eigen-decomposition.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def fir_filter(a, X):
    """``Y[k, t] = sum_{u <= t} a[u] X[k, t - u]`` for each row k of ``X`` (FIR filter from rest).

    Eight taps per pass over the signal (register blocking); indices never negative (no wrap-around checks).
    """
    K, n = X.shape
    Y = np.zeros((K, n))
    p1 = min(a.size, n)
    for k in range(K):
        y = Y[k]
        x = X[k]
        u = 0
        while u + 8 <= p1:
            a0, a1, a2, a3 = a[u], a[u + 1], a[u + 2], a[u + 3]
            a4, a5, a6, a7 = a[u + 4], a[u + 5], a[u + 6], a[u + 7]
            for t in range(u, min(u + 7, n)):            # start-up: not all eight taps reach back
                acc = 0.0
                for j in range(8):
                    if t - u - j >= 0:
                        acc += a[u + j] * x[t - u - j]
                y[t] += acc
            for t in range(n - u - 7):
                y[t + u + 7] += (a0 * x[t + 7] + a1 * x[t + 6] + a2 * x[t + 5] + a3 * x[t + 4]
                                 + a4 * x[t + 3] + a5 * x[t + 2] + a6 * x[t + 1] + a7 * x[t])
            u += 8
        while u < p1:
            au = a[u]
            for t in range(n - u):
                y[t + u] += au * x[t]
            u += 1
    return Y


@njit(cache=True, fastmath={"reassoc", "contract"})
def _lag_products(F, nls, T, s, off, F0, ZtT):
    """``F0[(k,i), l] = sum_t F[k,t-i] F[l,t]`` and ``ZtT[(k,i), c] = sum_t F[k,t-i] T[c,t]``, t = s..n-1.

    Blocked four lags x two targets per pass (eight accumulators, each vectorised).
    """
    K, n = F.shape
    nT = T.shape[0]
    m = n - s
    nc = K + nT
    for k in range(K):
        nl = nls[k]
        if nl == 0:
            continue
        c = 0
        while c < nc:
            c2 = min(c + 1, nc - 1)
            ta = F[c, s:] if c < K else T[c - K, s:]
            tb = F[c2, s:] if c2 < K else T[c2 - K, s:]
            i = 0
            while i < nl:
                if i + 4 <= nl:
                    f0 = F[k, s - i:n - i]
                    f1 = F[k, s - i - 1:n - i - 1]
                    f2 = F[k, s - i - 2:n - i - 2]
                    f3 = F[k, s - i - 3:n - i - 3]
                    a0 = a1 = a2 = a3 = 0.0
                    b0 = b1 = b2 = b3 = 0.0
                    for t in range(m):
                        v = ta[t]
                        w = tb[t]
                        x0, x1, x2, x3 = f0[t], f1[t], f2[t], f3[t]
                        a0 += x0 * v
                        a1 += x1 * v
                        a2 += x2 * v
                        a3 += x3 * v
                        b0 += x0 * w
                        b1 += x1 * w
                        b2 += x2 * w
                        b3 += x3 * w
                    accs_a = (a0, a1, a2, a3)
                    accs_b = (b0, b1, b2, b3)
                    for j in range(4):
                        r = off[k] + i + j
                        if c < K:
                            F0[r, c] = accs_a[j]
                        else:
                            ZtT[r, c - K] = accs_a[j]
                        if c2 < K:
                            F0[r, c2] = accs_b[j]
                        else:
                            ZtT[r, c2 - K] = accs_b[j]
                    i += 4
                else:
                    f0 = F[k, s - i:n - i]
                    a0 = 0.0
                    b0 = 0.0
                    for t in range(m):
                        a0 += f0[t] * ta[t]
                        b0 += f0[t] * tb[t]
                    r = off[k] + i
                    if c < K:
                        F0[r, c] = a0
                    else:
                        ZtT[r, c - K] = a0
                    if c2 < K:
                        F0[r, c2] = b0
                    else:
                        ZtT[r, c2 - K] = b0
                    i += 1
            c += 2


@njit(cache=True)
def lag_moments(F, nls, T, s):
    """``Z^T Z`` (n_z, n_z) and ``Z^T T^T`` (n_z, n_T) of the lag instruments of the rows of ``F``.

    Parameters
    ----------
    F : (K, n) signals; instrument ``(k, i)`` is ``F[k, t - i]``, ``i < nls[k]``, rows ``t = s .. n-1``
        (signal after signal: the column layout of (45)).
    nls : (K,) int lags per signal (``nls[k] <= s + 1``).
    T : (n_T, n) targets (the prefiltered regressors and output); only samples ``s .. n-1`` are used.
    s : first row.
    """
    K, n = F.shape
    nz = 0
    for k in range(K):
        nz += nls[k]
    nT = T.shape[0]
    off = np.zeros(K + 1, np.int64)
    for k in range(K):
        off[k + 1] = off[k] + nls[k]
    # products with the lag-0 row of every signal and with the targets
    ZtT = np.zeros((nz, nT))
    F0 = np.zeros((nz, K))                          # F0[(k, i), l] = sum_t F[k, t-i] F[l, t]
    _lag_products(F, nls, T, s, off, F0, ZtT)
    # Z^T Z: shifting both lags by one moves the window back one sample (iv.lag_gram):
    # S[(k,i+1),(l,j+1)] = S[(k,i),(l,j)] + F[k,s-1-i] F[l,s-1-j] - F[k,n-1-i] F[l,n-1-j]
    G = np.zeros((nz, nz))
    for k in range(K):
        for i in range(nls[k]):
            a = off[k] + i
            for l in range(K):
                for j in range(nls[l]):
                    b = off[l] + j
                    if b < a:
                        continue
                    mn = min(i, j)
                    i0, j0 = i - mn, j - mn
                    v = F0[off[k] + i0, l] if j0 == 0 else F0[off[l] + j0, k]
                    for q in range(mn):
                        ii, jj = i0 + q, j0 + q
                        v += F[k, s - 1 - ii] * F[l, s - 1 - jj] - F[k, n - 1 - ii] * F[l, n - 1 - jj]
                    G[a, b] = v
                    G[b, a] = v
    return G, ZtT


@njit(cache=True, fastmath={"reassoc", "contract"})
def ar_normal_equations(x, p):
    """``(X^T X, X^T x[p:], x[p:]^T x[p:])`` for ``X[t, i] = x[t - 1 - i]``, ``t = p .. n-1``, ``i < p``.

    ``G[i, i+d] = G[0, d] + sum_{l < i} (x[p-2-l] x[p-2-l-d] - x[n-2-l] x[n-2-l-d])`` (the O(n p) form of
    :func:`shipid.estimate.arma.ar_gram`).
    """
    n = x.size
    m = n - p
    c = np.zeros(p)                                  # c[d] = sum_{t=p}^{n-1} x[t-1] x[t-1-d]
    g = np.zeros(p)                                  # g[j] = sum_{t=p}^{n-1} x[t] x[t-1-j]
    x0 = x[p:]
    x1 = x[p - 1:n - 1]
    xx = 0.0
    for t in range(m):
        xx += x0[t] * x0[t]
    for d in range(p):
        xd = x[p - 1 - d:n - 1 - d]
        ac = 0.0
        for t in range(m):
            ac += x1[t] * xd[t]
        c[d] = ac
    # g[d] is c[d+1] over the window one sample later: g[d] = c[d+1] - x[p-1] x[p-2-d] + x[n-1] x[n-2-d]
    for d in range(p - 1):
        g[d] = c[d + 1] - x[p - 1] * x[p - 2 - d] + x[n - 1] * x[n - 2 - d]
    xl = x[0:n - p]                                   # the last lag directly: x[t - p], t = p .. n-1
    ag = 0.0
    for t in range(m):
        ag += x0[t] * xl[t]
    g[p - 1] = ag
    G = np.zeros((p, p))
    for d in range(p):
        v = c[d]
        G[0, d] = v
        G[d, 0] = v
        for i in range(1, p - d):
            l = i - 1
            h = x[p - 2 - l] * x[p - 2 - l - d] if p - 2 - l - d >= 0 else 0.0
            v += h - x[n - 2 - l] * x[n - 2 - l - d]
            G[i, i + d] = v
            G[i + d, i] = v
    return G, g, xx


__all__ = ["fir_filter", "lag_moments", "ar_normal_equations"]


@njit(cache=True, fastmath={"reassoc", "contract"})
def ridge_cholesky_solve(G, g):
    """Solve ``(G + 1e-12 tr(G)/p I) th = g`` by Cholesky (the regularised normal equations of
    :func:`shipid.estimate.arma.ar_solve_normal`); returns ``(ok, th)``, ``ok`` False if not positive definite."""
    p = G.shape[0]
    ridge = 0.0
    for i in range(p):
        ridge += G[i, i]
    ridge *= 1e-12 / p
    Lc = np.zeros((p, p))
    for j in range(p):
        d = G[j, j] + ridge
        for k in range(j):
            d -= Lc[j, k] * Lc[j, k]
        if not d > 0.0:
            return False, np.zeros(p)
        d = np.sqrt(d)
        Lc[j, j] = d
        for i in range(j + 1, p):
            v = G[i, j]
            for k in range(j):
                v -= Lc[i, k] * Lc[j, k]
            Lc[i, j] = v / d
    z = np.empty(p)
    for i in range(p):
        v = g[i]
        for k in range(i):
            v -= Lc[i, k] * z[k]
        z[i] = v / Lc[i, i]
    th = np.empty(p)
    for i in range(p - 1, -1, -1):
        v = z[i]
        for k in range(i + 1, p):
            v -= Lc[k, i] * th[k]
        th[i] = v / Lc[i, i]
    return True, th


@njit(cache=True)
def ar_fit(xs, p):
    """Least-squares AR(p) of ``xs``: ``(ok, a, mean(eps^2))`` with ``a = [1, -th]`` and ``eps = A(q) xs`` on
    samples ``p .. n-1`` (the pure-AR branch of :func:`shipid.estimate.arma.hannan_rissanen`)."""
    G, g, _xx = ar_normal_equations(xs, p)
    ok, th = ridge_cholesky_solve(G, g)
    a = np.empty(p + 1)
    a[0] = 1.0
    a[1:] = -th
    if not ok:
        return False, a, 0.0
    n = xs.size
    m = n - p
    X = np.empty((1, n))
    X[0] = xs
    e = fir_filter(a, X)[0]                       # e[t] = sum_u a[u] xs[t - u]; used for t = p .. n-1
    s2 = 0.0
    for t in range(p, n):
        s2 += e[t] * e[t]
    return True, a, s2 / m


__all__ += ["ridge_cholesky_solve", "ar_fit"]


@njit(cache=True)
def project_qr(s, V, ZtP, rtol):
    """The rest of :func:`shipid.estimate.iv.iv_compress_products` after ``s, V = eigh(Z^T Z)``.

    ``P = S_k^-1/2 V_k^T Z^T [Phi, y]`` over the eigenvalues ``s > rtol max(s)``, then the triangular
    factor of ``P`` by Householder QR (as LAPACK's ``geqrf``; rows may differ in sign, which leaves the
    criterion unchanged). Returns ``(Rf, kept)``: ``Rf`` the (n_g+1, n_g+1) factor (rows beyond the rank
    zero), ``kept`` the number of instrument directions used.
    """
    nz = s.size
    nc = ZtP.shape[1]
    thr = rtol * max(s[nz - 1], 1e-300)
    kept = 0
    for i in range(nz):
        if s[i] > thr:
            kept += 1
    P = np.empty((kept, nc))
    r = 0
    for i in range(nz):
        if s[i] > thr:
            w = 1.0 / np.sqrt(s[i])
            for c in range(nc):
                acc = 0.0
                for j in range(nz):
                    acc += V[j, i] * ZtP[j, c]
                P[r, c] = acc * w
            r += 1
    # Householder QR of P (kept x nc), R in the upper triangle
    m = kept
    for c in range(min(m, nc)):
        norm = 0.0
        for i in range(c, m):
            norm += P[i, c] * P[i, c]
        norm = np.sqrt(norm)
        if norm == 0.0:
            continue
        alpha = -norm if P[c, c] >= 0 else norm
        v0 = P[c, c] - alpha
        # v = [v0, P[c+1:, c]], H = I - 2 v v^T / (v^T v)
        vtv = v0 * v0
        for i in range(c + 1, m):
            vtv += P[i, c] * P[i, c]
        if vtv > 0.0:
            for cc in range(c + 1, nc):
                dot = v0 * P[c, cc]
                for i in range(c + 1, m):
                    dot += P[i, c] * P[i, cc]
                f = 2.0 * dot / vtv
                P[c, cc] -= f * v0
                for i in range(c + 1, m):
                    P[i, cc] -= f * P[i, c]
        P[c, c] = alpha
        for i in range(c + 1, m):
            P[i, c] = 0.0
    Rf = np.zeros((nc, nc))
    for i in range(min(m, nc)):
        for c in range(i, nc):
            Rf[i, c] = P[i, c]
    return Rf, kept


__all__ += ["project_qr"]
