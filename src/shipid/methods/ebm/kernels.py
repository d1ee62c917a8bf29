"""The numba loops of the compiled EBM filter and smoothers (Yoon & Rhee 2003, eqs. 9–10).

What they compute, and the numerics, are described in :mod:`shipid.methods.ebm.compiled`, whose
functions call these loops and turn their status codes into results or errors.

Cache. Compilation is cached on disk (``cache=True``, in ``__pycache__``). numba keys the
cache of a function on the file that defines it only, not on the compiled functions it calls
from other files; the loops here call the model kernels of
:mod:`shipid.methods.ebm.model_kernels` and the linear-algebra kernels of
:mod:`shipid.numerics.numba_linalg`. So this file carries :data:`MODEL_KERNELS_KEY` and
:data:`NUMBA_LINALG_KEY`, the hashes of those files: an edit there must update the key here
(which changes this file and so invalidates its cache; ``tests/methods/ebm/test_kernels.py``
checks the keys). If a key does not match the file found at import, the loops here are
compiled without the disk cache, never run stale.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from shipid.numerics import numba_linalg
from shipid.estimate.cd_ekf import LOG2PI
from shipid.numerics.numba_linalg import cho_solve_inplace, cholesky_into, source_key, symmetrise_inplace
from shipid.methods.ebm import model_kernels
from shipid.methods.ebm.model_kernels import ebm_f_into, ebm_F_into, ebm_h_into, ebm_H_into

#: First 16 hex digits of the SHA-256 of ``model_kernels.py`` (see the module docstring).
MODEL_KERNELS_KEY = "017e7ac1ac440667"

#: First 16 hex digits of the SHA-256 of ``shipid/numerics/numba_linalg.py`` (see the module docstring).
NUMBA_LINALG_KEY = "355c3586dc6b4413"

#: True when the on-disk cache may be used: the compiled callees are the ones the keys name.
CACHE_VALID = (source_key(model_kernels) == MODEL_KERNELS_KEY
               and source_key(numba_linalg) == NUMBA_LINALG_KEY)
_JIT = dict(cache=CACHE_VALID, nogil=True, error_model="numpy")  # no ZeroDivisionError checks in loops

# status codes returned by the compiled loops
OK, P_NOT_PD, S_NOT_PD, TAYLOR_NOT_CONVERGED = 0, 1, 2, 3


# ---------------------------------------------------------------------------------------
# small dense / structured linear algebra
# ---------------------------------------------------------------------------------------
@njit(**_JIT)
def _csr_into(A, rowptr, cols, vals):
    """Non-zeros of the square matrix ``A`` by rows (CSR) into the given buffers."""
    n = A.shape[0]
    e = 0
    for i in range(n):
        rowptr[i] = e
        for j in range(n):
            v = A[i, j]
            if v != 0.0:
                cols[e] = j
                vals[e] = v
                e += 1
    rowptr[n] = e


@njit(**_JIT)
def _spmm(rowptr, cols, vals, X, out):
    """``out = A X`` with A in CSR (rows of X as contiguous axpy's)."""
    n = rowptr.shape[0] - 1
    nc = X.shape[1]
    for i in range(n):
        for j in range(nc):
            out[i, j] = 0.0
        for e in range(rowptr[i], rowptr[i + 1]):
            l = cols[e]
            v = vals[e]
            for j in range(nc):
                out[i, j] += v * X[l, j]


@njit(**_JIT)
def _spmm_t(rowptr, cols, vals, X, out):
    """``out = Aᵀ X`` with A in CSR."""
    n = rowptr.shape[0] - 1
    nc = X.shape[1]
    out[:, :] = 0.0
    for l in range(n):
        for e in range(rowptr[l], rowptr[l + 1]):
            j = cols[e]
            v = vals[e]
            for c in range(nc):
                out[j, c] += v * X[l, c]


@njit(**_JIT)
def _dense_mm(A, X, out):
    """``out = A X`` (dense, rows as axpy's)."""
    n = A.shape[0]
    nc = X.shape[1]
    for i in range(n):
        for j in range(nc):
            out[i, j] = 0.0
        for l in range(A.shape[1]):
            a = A[i, l]
            if a != 0.0:
                for j in range(nc):
                    out[i, j] += a * X[l, j]


@njit(**_JIT)
def _transpose_into(A, out):
    n = A.shape[0]
    for i in range(n):
        for j in range(n):
            out[j, i] = A[i, j]


@njit(**_JIT)
def _taylor_into(Fh, Q, h, tol, max_terms, Phi, Qd, term, tmp, C, G, rowptr, cols, vals):
    """Taylor-series Φ, Q_d as :func:`shipid.estimate.cd_ekf.taylor_discretise` (``Fh = F h``).

    Same terms and stopping rule; ``(F h)^k`` is formed as ``F h (F h)^{k−1}`` (the powers
    commute) and ``C_k`` as ``G + Gᵀ``, ``G = F h C_{k−1}`` (C symmetric), over the non-zeros
    of ``F h``. Returns True when converged (else Φ, Q_d are not to be used).
    """
    n = Fh.shape[0]
    _csr_into(Fh, rowptr, cols, vals)
    # G = Fh Q  ->  C = (G + Gᵀ) h/2,  Q_d = Q h + C,  Φ = I + Fh,  term = Fh
    _spmm(rowptr, cols, vals, Q, G)
    qscale = 0.0
    for i in range(n):
        for j in range(n):
            C[i, j] = (G[i, j] + G[j, i]) * (0.5 * h)
            Qd[i, j] = Q[i, j] * h + C[i, j]
            a = abs(Qd[i, j])
            if a > qscale:
                qscale = a
            Phi[i, j] = Fh[i, j]
            term[i, j] = Fh[i, j]
        Phi[i, i] += 1.0
    if qscale == 0.0:
        qscale = 1.0
    for k in range(2, max_terms):
        # tmp = Fh · (Fh)^{k−1}/(k−1)!  and  G = Fh · C_{k−1}, in one pass over Fh's non-zeros
        for i in range(n):
            for j in range(n):
                tmp[i, j] = 0.0
                G[i, j] = 0.0
            for e in range(rowptr[i], rowptr[i + 1]):
                l = cols[e]
                v = vals[e]
                for j in range(n):
                    tmp[i, j] += v * term[l, j]
                    G[i, j] += v * C[l, j]
        tmax = 0.0
        cmax = 0.0
        fk = 1.0 / k
        fk1 = 1.0 / (k + 1)
        for i in range(n):
            for j in range(n):
                a = tmp[i, j] * fk
                term[i, j] = a
                Phi[i, j] += a
                a = abs(a)
                if a > tmax:
                    tmax = a
        for i in range(n):
            for j in range(i, n):
                c = (G[i, j] + G[j, i]) * fk1
                C[i, j] = c
                C[j, i] = c
                Qd[i, j] += c
                if j != i:
                    Qd[j, i] += c
                c = abs(c)
                if c > cmax:
                    cmax = c
        if tmax <= tol and cmax <= tol * qscale:
            return True
    return False


@njit(**_JIT)
def rk4_into(p, t, x, h, substeps, out, k1, k2, k3, k4, xt):
    n = x.shape[0]
    hs = h / substeps
    out[:] = x
    tt = t
    for _ in range(substeps):
        ebm_f_into(tt, out, p, k1)
        for i in range(n):
            xt[i] = out[i] + 0.5 * hs * k1[i]
        ebm_f_into(tt + 0.5 * hs, xt, p, k2)
        for i in range(n):
            xt[i] = out[i] + 0.5 * hs * k2[i]
        ebm_f_into(tt + 0.5 * hs, xt, p, k3)
        for i in range(n):
            xt[i] = out[i] + hs * k3[i]
        ebm_f_into(tt + hs, xt, p, k4)
        for i in range(n):
            out[i] = out[i] + (hs / 6.0) * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i])
        tt += hs


# ---------------------------------------------------------------------------------------
# the filter loop (EBM model)
# ---------------------------------------------------------------------------------------
@njit(**_JIT)
def ebm_filter_loop(p, Q, R, t, z, x0, P0, substeps, check_pd, tol, max_terms,
                     x_pred, P_pred, x_filt, P_filt, Phi_all, Qd_all, innov, S_all, K_all, H_all,
                     nis, HSn, HSH, out):
    """Fill the FilterResult arrays; return (status, sample index). ``out[0]`` = log-likelihood."""
    N = t.shape[0]
    n = x0.shape[0]
    m = z.shape[1]
    nQ = Q.shape[0]
    x = x0.copy()
    xn = np.empty(n)
    P = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            P[i, j] = 0.5 * (P0[i, j] + P0[j, i])
    Fk = np.empty((n, n)); Fh = np.empty((n, n))
    Phi = np.empty((n, n)); Qd = np.empty((n, n))
    term = np.empty((n, n)); tmp = np.empty((n, n)); C = np.empty((n, n)); G = np.empty((n, n))
    rowptr = np.empty(n + 1, dtype=np.int64); cols = np.empty(n * n, dtype=np.int64)
    vals = np.empty(n * n)
    k1 = np.empty(n); k2 = np.empty(n); k3 = np.empty(n); k4 = np.empty(n); xt = np.empty(n)
    T = np.empty((n, n)); Tt = np.empty((n, n)); A = np.empty((n, n)); Lp = np.empty((n, n))
    Hk = np.empty((m, n)); hx = np.empty(m)
    idx = np.empty(m, dtype=np.int64)
    Hm = np.empty((m, n)); Rm = np.empty((m, m)); nu = np.empty(m)
    HP = np.empty((m, n)); S = np.empty((m, m)); Ls = np.empty((m, m))
    B = np.empty((m, 2 * n + 1)); D = np.empty((n, m))
    loglik = 0.0
    for k in range(N):
        if k > 0:
            hk = t[k] - t[k - 1]
            ebm_F_into(t[k - 1], x, p, Fk)
            for i in range(n):
                for j in range(n):
                    Fh[i, j] = Fk[i, j] * hk
            Qk = Q[k - 1] if nQ > 1 else Q[0]
            if not _taylor_into(Fh, Qk, hk, tol, max_terms, Phi, Qd, term, tmp, C, G, rowptr, cols, vals):
                return TAYLOR_NOT_CONVERGED, k
            rk4_into(p, t[k - 1], x, hk, substeps, xn, k1, k2, k3, k4, xt)
            x[:] = xn
            # P⁻ = Φ P Φᵀ + Q_d:  T = Φ P,  A = Φ Tᵀ (= (Φ P Φᵀ)ᵀ), symmetrised, over Φ's non-zeros
            _csr_into(Phi, rowptr, cols, vals)
            _spmm(rowptr, cols, vals, P, T)
            _transpose_into(T, Tt)
            _spmm(rowptr, cols, vals, Tt, A)
            for i in range(n):
                for j in range(i, n):
                    s = 0.5 * (A[i, j] + A[j, i]) + Qd[i, j]
                    P[i, j] = s
                    P[j, i] = s
            Phi_all[k - 1] = Phi
            Qd_all[k - 1] = Qd
        x_pred[k] = x
        P_pred[k] = P
        ebm_H_into(t[k], x, p, Hk)
        H_all[k] = Hk
        mk = 0
        for a in range(m):
            if np.isfinite(z[k, a]):
                idx[mk] = a
                mk += 1
            else:
                H_all[k, a, :] = 0.0
        if mk > 0:
            ebm_h_into(t[k], x, p, hx)
            for a in range(mk):
                ia = idx[a]
                nu[a] = z[k, ia] - hx[ia]
                for j in range(n):
                    Hm[a, j] = Hk[ia, j]
                for b in range(mk):
                    Rm[a, b] = R[ia, idx[b]]
            # HP = Hm P (rows of P as axpy's, over Hm's non-zeros)
            for a in range(mk):
                for j in range(n):
                    HP[a, j] = 0.0
                for l in range(n):
                    v = Hm[a, l]
                    if v != 0.0:
                        for j in range(n):
                            HP[a, j] += v * P[l, j]
            for a in range(mk):
                for b in range(mk):
                    s = 0.0
                    for j in range(n):
                        v = Hm[b, j]
                        if v != 0.0:
                            s += HP[a, j] * v
                    S[a, b] = s + Rm[a, b]
            symmetrise_inplace(S, mk)
            if not cholesky_into(S, mk, Ls):
                return S_NOT_PD, k
            # B = S⁻¹ [Hm | H P | ν]  ->  S⁻¹H,  Kᵀ = S⁻¹ H P  (P Hᵀ S⁻¹ with P, S symmetric),  S⁻¹ν
            for a in range(mk):
                for j in range(n):
                    B[a, j] = Hm[a, j]
                    B[a, n + j] = HP[a, j]
                B[a, 2 * n] = nu[a]
            cho_solve_inplace(Ls, mk, B)
            for a in range(mk):  # x += K ν = Σ_a Kᵀ[a, :] ν_a
                va = nu[a]
                for i in range(n):
                    x[i] += B[a, n + i] * va
            # Joseph form: A = P − K (H P);  P⁺ = A + (K R − A Hᵀ) Kᵀ
            for i in range(n):
                for j in range(n):
                    A[i, j] = P[i, j]
                for a in range(mk):
                    kia = B[a, n + i]
                    for j in range(n):
                        A[i, j] -= kia * HP[a, j]
            for i in range(n):
                for a in range(mk):
                    s = 0.0
                    for b in range(mk):
                        s += B[b, n + i] * Rm[b, a]
                    w = 0.0
                    for j in range(n):
                        v = Hm[a, j]
                        if v != 0.0:
                            w += A[i, j] * v
                    D[i, a] = s - w
            for i in range(n):
                for j in range(n):
                    T[i, j] = A[i, j]
                for a in range(mk):
                    d = D[i, a]
                    for j in range(n):
                        T[i, j] += d * B[a, n + j]
            for i in range(n):
                for j in range(i, n):
                    s = 0.5 * (T[i, j] + T[j, i])
                    P[i, j] = s
                    P[j, i] = s
            # smoother inputs Hᵀ S⁻¹ ν, Hᵀ S⁻¹ H; NIS; log-likelihood
            sn = 0.0
            for a in range(mk):
                sn += nu[a] * B[a, 2 * n]
            for i in range(n):
                HSn[k, i] = 0.0
                for j in range(n):
                    HSH[k, i, j] = 0.0
            for a in range(mk):
                g = B[a, 2 * n]
                for i in range(n):
                    v = Hm[a, i]
                    if v != 0.0:
                        HSn[k, i] += v * g
                        for j in range(n):
                            HSH[k, i, j] += v * B[a, j]
            nis[k] = sn
            logdet = 0.0
            for a in range(mk):
                logdet += np.log(Ls[a, a])
            loglik += -0.5 * (sn + 2.0 * logdet + mk * LOG2PI)
            for a in range(mk):
                ia = idx[a]
                innov[k, ia] = nu[a]
                for b in range(mk):
                    S_all[k, ia, idx[b]] = S[a, b]
                for i in range(n):
                    K_all[k, i, ia] = B[a, n + i]
        x_filt[k] = x
        P_filt[k] = P
        if check_pd and not cholesky_into(P, n, Lp):
            out[0] = loglik
            return P_NOT_PD, k
    out[0] = loglik
    return OK, -1


# ---------------------------------------------------------------------------------------
# smoothers (generic: they read a FilterResult's arrays)
# ---------------------------------------------------------------------------------------
@njit(**_JIT)
def mbf_loop(x_filt, P_filt, K_all, H_all, HSn, HSH, Phi_all, xs, Ps):
    N, n = x_filt.shape
    m = H_all.shape[1]
    lam = np.zeros(n); lam_m = np.zeros(n)
    Lam = np.zeros((n, n)); Lam_m = np.empty((n, n))
    T = np.empty((n, n)); W = np.empty((n, n)); E = np.empty((n, n))
    Ut = np.empty((m, n)); Zt = np.empty((m, n)); Gm = np.empty((m, m)); g = np.empty(m)
    rowptr = np.empty(n + 1, dtype=np.int64); cols = np.empty(n * n, dtype=np.int64)
    vals = np.empty(n * n)
    lam_zero = True
    for k in range(N - 1, -1, -1):
        Pf = P_filt[k]
        # x̂(k|N) = x̂(k|k) − P λ,   P(k|N) = P − P Λ P  (symmetrised)
        for i in range(n):
            s = 0.0
            for j in range(n):
                s += Pf[i, j] * lam[j]
            xs[k, i] = x_filt[k, i] - s
        if lam_zero:
            for i in range(n):
                for j in range(n):
                    Ps[k, i, j] = 0.5 * (Pf[i, j] + Pf[j, i])
        else:
            _dense_mm(Pf, Lam, T)
            _dense_mm(T, Pf, W)
            for i in range(n):
                for j in range(i, n):
                    s = 0.5 * ((Pf[i, j] - W[i, j]) + (Pf[j, i] - W[j, i]))
                    Ps[k, i, j] = s
                    Ps[k, j, i] = s
        if k == 0:
            break
        lam_zero = False
        Kk = K_all[k]
        Hk = H_all[k]
        # λ⁻ = −Hᵀ S⁻¹ ν + λ − Hᵀ (Kᵀ λ)
        for a in range(m):
            s = 0.0
            for i in range(n):
                s += Kk[i, a] * lam[i]
            g[a] = s
        for i in range(n):
            s = lam[i] - HSn[k, i]
            for a in range(m):
                s -= Hk[a, i] * g[a]
            lam_m[i] = s
        # Λ⁻ = Hᵀ S⁻¹ H + Λ − (Z H + (Z H)ᵀ),  U = Λ K,  Z = U − ½ Hᵀ (Kᵀ U)
        # (= Hᵀ S⁻¹ H + (I − K H)ᵀ Λ (I − K H), using Λ = Λᵀ);  Uᵀ = Kᵀ Λ row-wise
        for a in range(m):
            for j in range(n):
                Ut[a, j] = 0.0
            for i in range(n):
                kia = Kk[i, a]
                if kia != 0.0:
                    for j in range(n):
                        Ut[a, j] += kia * Lam[i, j]
        for a in range(m):
            for b in range(m):
                s = 0.0
                for i in range(n):
                    s += Kk[i, a] * Ut[b, i]
                Gm[a, b] = s
        for a in range(m):
            for i in range(n):
                Zt[a, i] = Ut[a, i]
            for b in range(m):
                gba = 0.5 * Gm[b, a]
                if gba != 0.0:
                    for i in range(n):
                        Zt[a, i] -= gba * Hk[b, i]
        for i in range(n):
            for j in range(n):
                E[i, j] = 0.0
            for a in range(m):
                za = Zt[a, i]
                if za != 0.0:
                    for j in range(n):
                        E[i, j] += za * Hk[a, j]
        for i in range(n):
            for j in range(n):
                Lam_m[i, j] = HSH[k, i, j] + Lam[i, j] - E[i, j] - E[j, i]
        # back through Φ_{k−1}: λ = Φᵀ λ⁻,  Λ = Φᵀ Λ⁻ Φ (symmetrised), over Φ's non-zeros
        Ph = Phi_all[k - 1]
        _csr_into(Ph, rowptr, cols, vals)
        for i in range(n):
            lam[i] = 0.0
        for l in range(n):
            for e in range(rowptr[l], rowptr[l + 1]):
                lam[cols[e]] += vals[e] * lam_m[l]
        _spmm_t(rowptr, cols, vals, Lam_m, T)     # T = Φᵀ Λ⁻
        _transpose_into(T, W)
        _spmm_t(rowptr, cols, vals, W, E)         # E = Φᵀ Tᵀ = (Φᵀ Λ⁻ Φ)ᵀ
        for i in range(n):
            for j in range(i, n):
                s = 0.5 * (E[i, j] + E[j, i])
                Lam[i, j] = s
                Lam[j, i] = s


@njit(**_JIT)
def rts_loop(x_filt, P_filt, x_pred, P_pred, Phi_all, xs, Ps):
    N, n = x_filt.shape
    xs[N - 1] = x_filt[N - 1]
    Ps[N - 1] = P_filt[N - 1]
    Pp = np.empty((n, n)); L = np.empty((n, n)); X = np.empty((n, n)); Cm = np.empty((n, n))
    D = np.empty((n, n)); T = np.empty((n, n)); dx = np.empty(n)
    for k in range(N - 2, -1, -1):
        Pf = P_filt[k]
        for i in range(n):
            for j in range(n):
                Pp[i, j] = 0.5 * (P_pred[k + 1, i, j] + P_pred[k + 1, j, i])
        if not cholesky_into(Pp, n, L):
            return k + 1
        # X = Φ P_f  ->  X = P_p⁻¹ Φ P_f,  C = Xᵀ = P_f Φᵀ P_p⁻¹
        Ph = Phi_all[k]
        X[:, :] = 0.0
        for i in range(n):
            for l in range(n):
                a = Ph[i, l]
                if a != 0.0:
                    for j in range(n):
                        X[i, j] += a * Pf[l, j]
        cho_solve_inplace(L, n, X)
        for i in range(n):
            for j in range(n):
                Cm[i, j] = X[j, i]
        for i in range(n):
            dx[i] = xs[k + 1, i] - x_pred[k + 1, i]
        for i in range(n):
            s = 0.0
            for j in range(n):
                s += Cm[i, j] * dx[j]
            xs[k, i] = x_filt[k, i] + s
        for i in range(n):
            for j in range(n):
                D[i, j] = Ps[k + 1, i, j] - Pp[i, j]
        T[:, :] = 0.0
        for i in range(n):
            for l in range(n):
                a = Cm[i, l]
                if a != 0.0:
                    for j in range(n):
                        T[i, j] += a * D[l, j]
        for i in range(n):
            for j in range(i, n):
                s = 0.0
                for l in range(n):
                    s += T[i, l] * Cm[j, l]
                s = 0.5 * (Pf[i, j] + Pf[j, i]) + s  # upper triangle, mirrored: symmetric
                Ps[k, i, j] = s
                Ps[k, j, i] = s
    return -1


__all__ = ["OK", "P_NOT_PD", "S_NOT_PD", "TAYLOR_NOT_CONVERGED", "MODEL_KERNELS_KEY", "NUMBA_LINALG_KEY", "CACHE_VALID",
           "source_key", "rk4_into", "ebm_filter_loop", "mbf_loop", "rts_loop"]
