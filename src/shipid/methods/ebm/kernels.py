"""Compiled (numba) continuous–discrete EKF and fixed-interval smoothers (seed 002, Yoon & Rhee 2003).

The same algorithms as the reference pure-Python path — :func:`shipid.estimate.cd_ekf.cd_ekf`
(eq. 9, Fig. 3), :func:`shipid.estimate.smoothers.mbf_smoother` (eq. 10, Bierman 1973) and
:func:`~shipid.estimate.smoothers.rts_smoother` — compiled with numba, returning the same
:class:`~shipid.estimate.cd_ekf.FilterResult` / :class:`~shipid.estimate.smoothers.SmootherResult`.
The reference path stays the definition: tests run both on a seeded trial and require
agreement to ~1e-9 relative (``tests/methods/ebm/test_kernels.py``).

What is compiled
----------------
* :func:`ebm_cd_ekf`: the filter for the 17-state EBM model of
  :mod:`shipid.models.ebm_state` (eqs. 4–8). The model's ``f, F, h, H`` are compiled
  kernels here (:func:`ebm_f`, :func:`ebm_F`, :func:`ebm_h`, :func:`ebm_H`) on the parameter
  vector of :meth:`shipid.models.ebm_state.EbmModel.kernel_params`; a generic model given as
  Python callables keeps using the reference :func:`~shipid.estimate.cd_ekf.cd_ekf`.
* :func:`mbf_smoother_fast`, :func:`rts_smoother_fast`: generic — they only read the arrays
  of a :class:`FilterResult`, whichever filter produced it.

Numerics (the standards of :mod:`shipid.estimate.linalg`, kept)
---------------------------------------------------------------
float64 throughout, no ``fastmath``. The per-sample algebra is the reference's, evaluated
so that the structure of the problem is not paid for in flops:

* Φ and Q_d by the same Taylor series as :func:`~shipid.estimate.cd_ekf.taylor_discretise`
  (same terms, same stopping rule). ``F`` has 24 non-zeros of 289, so products with ``F h``
  run over its non-zeros; ``C_k = F C_{k−1} + C_{k−1} Fᵀ`` is formed as ``G + Gᵀ`` with
  ``G = F C_{k−1}`` (``C`` is symmetric). If the series has not converged after
  ``max_terms`` the whole trial is handed to the reference path (which falls back to Van
  Loan's ``expm``), so no unconverged Φ is ever used.
* ``P⁻ = Φ P Φᵀ + Q_d`` skipping the zeros of Φ; the upper triangle is computed and
  mirrored, so P⁻ is exactly symmetric.
* The measurement update is the batch update of eq. 9 (all six measurements at once,
  Cholesky of S) — *no sequential scalar processing*, so the gains, ``S`` and the
  smoother's inputs are those of the reference. The covariance update is the Joseph form
  ``(I − K H) P (I − K H)ᵀ + K R Kᵀ``, evaluated through the low rank of ``K H``:
  ``A = P − K (H P)``, ``P⁺ = A + (K R − A Hᵀ) Kᵀ`` (algebraically identical; the Joseph
  form's insensitivity to errors in K is a property of the expression, not of the
  evaluation order), then symmetrised.
* Positive definiteness of the filtered covariance is checked by a Cholesky factorisation
  at *every* sample (the reference checks every 50th, for cost); a failure, or an innovation
  covariance S that is not positive definite, raises
  :class:`~shipid.estimate.linalg.NotPositiveDefiniteError` naming the sample index and time
  — nothing is returned from a failed run.
* MBF backward pass: ``(I − K H)ᵀ Λ (I − K H) = Λ − (Z H + (Z H)ᵀ)`` with ``U = Λ K``,
  ``Z = U − ½ Hᵀ (Kᵀ U)`` (again exact algebra, using Λ = Λᵀ).

Compilation is cached on disk (``cache=True``, in ``__pycache__``), so only the first
import on a machine pays the compile (~30 s on the shared 2-core machine). Everything compiled lives in this one file on
purpose: numba's cache is invalidated by changes to the file that holds a function, not by
changes to compiled functions it calls from other files.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numba import njit

from shipid.estimate.cd_ekf import LOG2PI, FilterResult, cd_ekf
from shipid.estimate.linalg import NotPositiveDefiniteError
from shipid.estimate.smoothers import SmootherResult

_JIT = dict(cache=True, nogil=True, error_model="numpy")  # no ZeroDivisionError checks in loops

# status codes returned by the compiled loops
OK, P_NOT_PD, S_NOT_PD, TAYLOR_NOT_CONVERGED = 0, 1, 2, 3


# ---------------------------------------------------------------------------------------
# EBM 17-state model kernels (mirror of shipid.models.ebm_state.EbmModel.f/F/h/H)
# p = [m, x_G, Minv (row-major, 9), x_D, y_D, y_S, absolute (0/1)]
# ---------------------------------------------------------------------------------------
@njit(**_JIT)
def ebm_f_into(t, x, p, dx):
    """State equation (eq. 6) into ``dx`` (see :meth:`EbmModel.f`)."""
    ur, vr, r, psi = x[0], x[1], x[2], x[5]
    m, xg = p[0], p[1]
    rhs0 = m * (vr * r + xg * r * r) + x[6]
    rhs1 = -m * ur * r + x[9]
    rhs2 = -m * xg * ur * r + x[12]
    dx[0] = p[2] * rhs0 + p[3] * rhs1 + p[4] * rhs2
    dx[1] = p[5] * rhs0 + p[6] * rhs1 + p[7] * rhs2
    dx[2] = p[8] * rhs0 + p[9] * rhs1 + p[10] * rhs2
    c, s = np.cos(psi), np.sin(psi)
    dx[3] = ur * c - vr * s
    dx[4] = ur * s + vr * c
    if p[14] != 0.0:
        dx[3] += x[15]
        dx[4] += x[16]
    dx[5] = r
    dx[6] = x[7]
    dx[7] = x[8]
    dx[8] = 0.0
    dx[9] = x[10]
    dx[10] = x[11]
    dx[11] = 0.0
    dx[12] = x[13]
    dx[13] = x[14]
    dx[14] = 0.0
    dx[15] = 0.0
    dx[16] = 0.0


@njit(**_JIT)
def ebm_F_into(t, x, p, F):
    """Jacobian ∂f/∂x into ``F`` (17 × 17, see :meth:`EbmModel.F`)."""
    ur, vr, r, psi = x[0], x[1], x[2], x[5]
    m, xg = p[0], p[1]
    F[:, :] = 0.0
    j00, j01, j02 = 0.0, m * r, m * (vr + 2 * xg * r)
    j10, j11, j12 = -m * r, 0.0, -m * ur
    j20, j21, j22 = -m * xg * r, 0.0, -m * xg * ur
    for i in range(3):
        a, b, c3 = p[2 + 3 * i], p[3 + 3 * i], p[4 + 3 * i]
        F[i, 0] = a * j00 + b * j10 + c3 * j20
        F[i, 1] = a * j01 + b * j11 + c3 * j21
        F[i, 2] = a * j02 + b * j12 + c3 * j22
        F[i, 6] = a
        F[i, 9] = b
        F[i, 12] = c3
    c, s = np.cos(psi), np.sin(psi)
    F[3, 0], F[3, 1], F[3, 5] = c, -s, -ur * s - vr * c
    F[4, 0], F[4, 1], F[4, 5] = s, c, ur * c - vr * s
    if p[14] != 0.0:
        F[3, 15] = 1.0
        F[4, 16] = 1.0
    F[5, 2] = 1.0
    for i in (6, 9, 12):
        F[i, i + 1] = 1.0
        F[i + 1, i + 2] = 1.0


@njit(**_JIT)
def ebm_h_into(t, x, p, out):
    """Measurement function of eq. 8 into ``out`` (6,) (see :meth:`EbmModel.h`)."""
    ur, vr, r, xr, yr, psi, cx, cy = x[0], x[1], x[2], x[3], x[4], x[5], x[15], x[16]
    c, s = np.cos(psi), np.sin(psi)
    xD, yD = p[11], p[12]
    tt = 0.0 if p[14] != 0.0 else t
    a = ur - yD * r
    b = vr + xD * r
    out[0] = xr + xD * c - yD * s + cx * tt
    out[1] = yr + xD * s + yD * c + cy * tt
    out[2] = a * c - b * s + cx
    out[3] = a * s + b * c + cy
    out[4] = psi
    out[5] = ur - p[13] * r


@njit(**_JIT)
def ebm_H_into(t, x, p, H):
    """Jacobian ∂h/∂x into ``H`` (6 × 17, see :meth:`EbmModel.H`)."""
    ur, vr, r, psi = x[0], x[1], x[2], x[5]
    c, s = np.cos(psi), np.sin(psi)
    xD, yD = p[11], p[12]
    tt = 0.0 if p[14] != 0.0 else t
    a = ur - yD * r
    b = vr + xD * r
    H[:, :] = 0.0
    H[0, 3] = 1.0
    H[0, 5] = -xD * s - yD * c
    H[0, 15] = tt
    H[1, 4] = 1.0
    H[1, 5] = xD * c - yD * s
    H[1, 16] = tt
    H[2, 0], H[2, 1], H[2, 2] = c, -s, -yD * c - xD * s
    H[2, 5] = -a * s - b * c
    H[2, 15] = 1.0
    H[3, 0], H[3, 1], H[3, 2] = s, c, -yD * s + xD * c
    H[3, 5] = a * c - b * s
    H[3, 16] = 1.0
    H[4, 5] = 1.0
    H[5, 0], H[5, 2] = 1.0, -p[13]


def _allocating(into, shape, p: np.ndarray, t: float, x: np.ndarray) -> np.ndarray:
    """Call a compiled ``*_into(t, x, p, out)`` kernel on a fresh output array of ``shape``."""
    out = np.empty(shape)
    into(float(t), np.ascontiguousarray(x, dtype=float), p, out)
    return out


def ebm_f(p: np.ndarray, t: float, x: np.ndarray) -> np.ndarray:
    """Allocating wrapper of :func:`ebm_f_into` (for tests and scripts)."""
    return _allocating(ebm_f_into, 17, p, t, x)


def ebm_F(p: np.ndarray, t: float, x: np.ndarray) -> np.ndarray:
    """Allocating wrapper of :func:`ebm_F_into`."""
    return _allocating(ebm_F_into, (17, 17), p, t, x)


def ebm_h(p: np.ndarray, t: float, x: np.ndarray) -> np.ndarray:
    """Allocating wrapper of :func:`ebm_h_into`."""
    return _allocating(ebm_h_into, 6, p, t, x)


def ebm_H(p: np.ndarray, t: float, x: np.ndarray) -> np.ndarray:
    """Allocating wrapper of :func:`ebm_H_into`."""
    return _allocating(ebm_H_into, (6, 17), p, t, x)


# ---------------------------------------------------------------------------------------
# small dense / structured linear algebra
# ---------------------------------------------------------------------------------------
@njit(**_JIT)
def _cholesky_into(A, n, L):
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
def _cho_solve_inplace(L, n, B):
    """Solve (L Lᵀ) X = B in place, B (n × ncol)."""
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
def _rk4_into(p, t, x, h, substeps, out, k1, k2, k3, k4, xt):
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
def _ebm_filter_loop(p, Q, R, t, z, x0, P0, substeps, check_pd, tol, max_terms,
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
            _rk4_into(p, t[k - 1], x, hk, substeps, xn, k1, k2, k3, k4, xt)
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
            for a in range(mk):
                for b in range(a + 1, mk):
                    s = 0.5 * (S[a, b] + S[b, a])
                    S[a, b] = s
                    S[b, a] = s
            if not _cholesky_into(S, mk, Ls):
                return S_NOT_PD, k
            # B = S⁻¹ [Hm | H P | ν]  ->  S⁻¹H,  Kᵀ = S⁻¹ H P  (P Hᵀ S⁻¹ with P, S symmetric),  S⁻¹ν
            for a in range(mk):
                for j in range(n):
                    B[a, j] = Hm[a, j]
                    B[a, n + j] = HP[a, j]
                B[a, 2 * n] = nu[a]
            _cho_solve_inplace(Ls, mk, B)
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
        if check_pd and not _cholesky_into(P, n, Lp):
            out[0] = loglik
            return P_NOT_PD, k
    out[0] = loglik
    return OK, -1


def _raise_not_pd(what: str, k: int, t: float, M: np.ndarray) -> None:
    with np.errstate(all="ignore"):
        finite = bool(np.all(np.isfinite(M)))
        lo = float(np.linalg.eigvalsh(0.5 * (M + M.T))[0]) if finite else float("nan")
    detail = f"smallest eigenvalue {lo:.3g}" if finite else "non-finite entries"
    raise NotPositiveDefiniteError(f"{what} at sample {k} (t = {t:.6g} s) is not positive definite ({detail})")


def ebm_cd_ekf(model, Q: np.ndarray, R: np.ndarray, t: np.ndarray, z: np.ndarray, x0: np.ndarray,
               P0: np.ndarray, *, substeps: int = 1, check_pd: bool = True, tol: float = 1e-15,
               max_terms: int = 40) -> FilterResult:
    """The CD-EKF of :func:`shipid.estimate.cd_ekf.cd_ekf` for the 17-state EBM model, compiled.

    Parameters
    ----------
    model : shipid.models.ebm_state.EbmModel
        Supplies :meth:`~shipid.models.ebm_state.EbmModel.kernel_params`; ``model.f/F/h/H``
        serve the reference fallback.
    Q, R, t, z, x0, P0, substeps, check_pd
        As :func:`~shipid.estimate.cd_ekf.cd_ekf` (NaN in ``z`` = missing measurement).
    tol, max_terms
        Stopping rule of the Taylor discretisation (as
        :func:`~shipid.estimate.cd_ekf.taylor_discretise`); if it does not converge at some
        sample the whole run is done by the reference path (Van Loan fallback there).

    Returns
    -------
    FilterResult
        Same fields as the reference; equal to it to rounding (~1e-12 relative).

    Raises
    ------
    NotPositiveDefiniteError
        The innovation covariance S, or (``check_pd``, checked at every sample) the filtered
        covariance, is not positive definite; the message names the sample index and time.
    """
    p = np.ascontiguousarray(model.kernel_params(), dtype=float)
    t = np.ascontiguousarray(t, dtype=float)
    z = np.ascontiguousarray(z, dtype=float)
    N, m = z.shape
    x0 = np.ascontiguousarray(x0, dtype=float).ravel()
    n = x0.size
    if n != 17 or m != 6:
        raise ValueError(f"ebm_cd_ekf needs 17 states and 6 measurements, got {n} and {m}")
    Qa = np.asarray(Q, dtype=float)
    Qa = np.ascontiguousarray(Qa[None] if Qa.ndim == 2 else Qa)
    if Qa.shape[0] > 1 and Qa.shape[0] != max(N - 1, 1):
        raise ValueError(f"Q per step must have N - 1 = {N - 1} matrices, got {Qa.shape[0]}")
    R = np.ascontiguousarray(R, dtype=float)
    P0 = np.ascontiguousarray(P0, dtype=float)
    fr = FilterResult.allocate(t, N, n, m)
    out = np.zeros(1)
    status, k = _ebm_filter_loop(p, Qa, R, t, z, x0, P0, int(substeps), bool(check_pd), float(tol),
                                 int(max_terms), *fr.buffers(), out)
    if status == TAYLOR_NOT_CONVERGED:
        return cd_ekf(model.f, model.F, model.h, model.H, Q, R, t, z, x0, P0, substeps=substeps,
                      check_pd=check_pd)
    if status == S_NOT_PD:
        ok = np.isfinite(z[k])
        Hm = fr.H[k][ok]
        _raise_not_pd("innovation covariance", k, t[k], Hm @ fr.P_pred[k] @ Hm.T + R[np.ix_(ok, ok)])
    if status == P_NOT_PD:
        _raise_not_pd("filter covariance", k, t[k], fr.P_filt[k])
    return replace(fr, loglik=float(out[0]))


# ---------------------------------------------------------------------------------------
# smoothers (generic: they read a FilterResult's arrays)
# ---------------------------------------------------------------------------------------
@njit(**_JIT)
def _mbf_loop(x_filt, P_filt, K_all, H_all, HSn, HSH, Phi_all, xs, Ps):
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


def mbf_smoother_fast(fr: FilterResult) -> SmootherResult:
    """Compiled :func:`shipid.estimate.smoothers.mbf_smoother` (same algorithm, eq. 10)."""
    xs = np.empty_like(fr.x_filt)
    Ps = np.empty_like(fr.P_filt)
    c = np.ascontiguousarray
    _mbf_loop(c(fr.x_filt), c(fr.P_filt), c(fr.K), c(fr.H), c(fr.HtSinv_nu), c(fr.HtSinv_H), c(fr.Phi), xs, Ps)
    return SmootherResult(t=fr.t, x=xs, P=Ps, method="mbf")


@njit(**_JIT)
def _rts_loop(x_filt, P_filt, x_pred, P_pred, Phi_all, xs, Ps):
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
        if not _cholesky_into(Pp, n, L):
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
        _cho_solve_inplace(L, n, X)
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


def rts_smoother_fast(fr: FilterResult) -> SmootherResult:
    """Compiled :func:`shipid.estimate.smoothers.rts_smoother` (same algorithm).

    Raises :class:`NotPositiveDefiniteError` naming the sample whose predicted covariance
    cannot be factorised (the reference raises scipy's LinAlgError there).
    """
    xs = np.empty_like(fr.x_filt)
    Ps = np.empty_like(fr.P_filt)
    c = np.ascontiguousarray
    k = _rts_loop(c(fr.x_filt), c(fr.P_filt), c(fr.x_pred), c(fr.P_pred), c(fr.Phi), xs, Ps)
    if k >= 0:
        _raise_not_pd("predicted covariance", k, fr.t[k], fr.P_pred[k])
    return SmootherResult(t=fr.t, x=xs, P=Ps, method="rts")


__all__ = ["ebm_cd_ekf", "mbf_smoother_fast", "rts_smoother_fast", "ebm_f", "ebm_F", "ebm_h", "ebm_H",
           "ebm_f_into", "ebm_F_into", "ebm_h_into", "ebm_H_into"]
