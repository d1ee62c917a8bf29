"""Compiled (numba) step 1 of the MMG pipeline: the kinematic CD-EKF and the RTS smoother.

The same algorithms as the reference path that :func:`shipid.methods.mmg.estimator.smooth_run`
runs with ``compiled=False`` — :func:`shipid.estimate.cd_ekf.cd_ekf` (Yoon & Rhee 2003,
eq. 9) on the 9-state kinematic model ``s = [x0, y0, ψ, u, v, r, u̇, v̇, ṙ]``
driven by white jerk noise, followed by :func:`shipid.estimate.smoothers.rts_smoother` —
fused into one compiled pass that returns only what step 2 reads (smoothed states, their
standard deviations, the NIS per sample and the log-likelihood). Tests require agreement
with the reference to rounding (``tests/methods/mmg/test_kernels.py``).

Numerics (the standards of :mod:`shipid.numerics.linalg`, kept): float64, no ``fastmath``.

* Φ and Q_d by the Taylor series of :func:`shipid.estimate.cd_ekf.taylor_discretise`
  (same terms, same stopping rule). The kinematic Jacobian has 10 non-zeros,
  so the products with ``F h`` run over its non-zeros (exact zeros contribute nothing).
  If the series has not converged after ``max_terms`` the run is handed to the reference
  path (which falls back to Van Loan's ``expm``).
* ``P⁻ = Φ P Φᵀ + Q_d``, symmetrised; the measurement update is the batch EKF update of
  eq. 9 over the channels present (Cholesky of S), the covariance update the Joseph form
  ``(I − K H) P (I − K H)ᵀ + K R Kᵀ``, symmetrised. Positive definiteness of the filtered
  covariance is checked by Cholesky every 50th sample and at the last (as the reference);
  a failure, or an S that is not positive definite, is reported by status code and
  raised by the caller with the reference's message.
* RTS: ``C_k = P(k|k) Φ_kᵀ P(k+1|k)⁻¹`` through a Cholesky solve with ``P(k+1|k)``.

Cache. Compilation is cached on disk (``cache=True``). numba keys the cache of a function
on the file that defines it only, not on the compiled functions it calls from other files;
the loop here calls the Cholesky and symmetrisation kernels of
:mod:`shipid.numerics.numba_linalg`. So this file carries :data:`NUMBA_LINALG_KEY`, the hash
of that file: an edit there must update the key here (``tests/methods/mmg/test_kernels.py``
checks it). If the key does not match the file found at import, the loops here are compiled
without the disk cache, never run stale.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from shipid.numerics import numba_linalg
from shipid.estimate.cd_ekf import LOG2PI
from shipid.numerics.linalg import check_positive_definite
from shipid.numerics.numba_linalg import cho_solve_inplace, cholesky_into, source_key, symmetrise_inplace

#: First 16 hex digits of the SHA-256 of ``shipid/numerics/numba_linalg.py`` (see the module docstring).
NUMBA_LINALG_KEY = "355c3586dc6b4413"

#: True when the on-disk cache may be used: the compiled callees are the ones the key names.
CACHE_VALID = source_key(numba_linalg) == NUMBA_LINALG_KEY
_JIT = dict(cache=CACHE_VALID, nogil=True, error_model="numpy")

# status codes of the compiled loop
OK, P_NOT_PD, S_NOT_PD, TAYLOR_NOT_CONVERGED = 0, 1, 2, 3
NS = 9          # states
NM = 6          # measurements: the first six states


@njit(**_JIT)
def _mm(A, B, out):
    """out = A @ B (dense)."""
    n, p = A.shape
    q = B.shape[1]
    for i in range(n):
        for j in range(q):
            s = 0.0
            for k in range(p):
                s += A[i, k] * B[k, j]
            out[i, j] = s


@njit(**_JIT)
def _mmT(A, B, out):
    """out = A @ Bᵀ (dense)."""
    n, p = A.shape
    q = B.shape[0]
    for i in range(n):
        for j in range(q):
            s = 0.0
            for k in range(p):
                s += A[i, k] * B[j, k]
            out[i, j] = s


@njit(**_JIT)
def _kin_f(x, out):
    c, s = np.cos(x[2]), np.sin(x[2])
    out[0] = x[3] * c - x[4] * s
    out[1] = x[3] * s + x[4] * c
    out[2] = x[5]
    out[3] = x[6]
    out[4] = x[7]
    out[5] = x[8]
    out[6] = 0.0
    out[7] = 0.0
    out[8] = 0.0


@njit(**_JIT)
def _kin_rk4(x, h, k1, k2, k3, k4, xt):
    """One RK4 step of length ``h`` of :func:`_kin_f`, in place on ``x`` (``k1..k4``, ``xt``: work arrays).

    The compiled twin of :func:`shipid.numerics.integrate.rk4_propagate` on
    :func:`shipid.methods.mmg.estimator.kinematic_f`; ``tests/methods/mmg/test_kernels.py`` checks they agree.
    """
    n = x.size
    _kin_f(x, k1)
    for i in range(n):
        xt[i] = x[i] + 0.5 * h * k1[i]
    _kin_f(xt, k2)
    for i in range(n):
        xt[i] = x[i] + 0.5 * h * k2[i]
    _kin_f(xt, k3)
    for i in range(n):
        xt[i] = x[i] + h * k3[i]
    _kin_f(xt, k4)
    for i in range(n):
        x[i] = x[i] + (h / 6.0) * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i])


@njit(**_JIT)
def _kin_F_nz(x, h, rows, cols, vals):
    """Non-zeros of ``F(x) h`` of the kinematic model (10 entries; their count is returned)."""
    psi, u, v = x[2], x[3], x[4]
    c, s = np.cos(psi), np.sin(psi)
    rows[0], cols[0], vals[0] = 0, 2, (-u * s - v * c) * h
    rows[1], cols[1], vals[1] = 0, 3, c * h
    rows[2], cols[2], vals[2] = 0, 4, -s * h
    rows[3], cols[3], vals[3] = 1, 2, (u * c - v * s) * h
    rows[4], cols[4], vals[4] = 1, 3, s * h
    rows[5], cols[5], vals[5] = 1, 4, c * h
    rows[6], cols[6], vals[6] = 2, 5, h
    rows[7], cols[7], vals[7] = 3, 6, h
    rows[8], cols[8], vals[8] = 4, 7, h
    rows[9], cols[9], vals[9] = 5, 8, h
    return 10


@njit(**_JIT)
def _taylor(rows, cols, vals, nz, Q, h, tol, max_terms, Phi, Qd, term, C, T1, T2):
    """Φ, Q_d by the series of :func:`shipid.estimate.cd_ekf.taylor_discretise`; False if not converged."""
    n = Q.shape[0]
    # term = Fh; Phi = I + Fh
    for i in range(n):
        for j in range(n):
            term[i, j] = 0.0
            Phi[i, j] = 1.0 if i == j else 0.0
    for e in range(nz):
        term[rows[e], cols[e]] += vals[e]
        Phi[rows[e], cols[e]] += vals[e]
    # C = (Fh Q + Q Fhᵀ) * (0.5 h); Qd = Q h + C
    for i in range(n):
        for j in range(n):
            T1[i, j] = 0.0
    for e in range(nz):            # T1 = Fh Q
        a, b, w = rows[e], cols[e], vals[e]
        for j in range(n):
            T1[a, j] += w * Q[b, j]
    qscale = 0.0
    for i in range(n):
        for j in range(n):
            C[i, j] = (T1[i, j] + T1[j, i]) * (0.5 * h)       # Q Fhᵀ = (Fh Q)ᵀ (Q symmetric)
            Qd[i, j] = Q[i, j] * h + C[i, j]
            if abs(Qd[i, j]) > qscale:
                qscale = abs(Qd[i, j])
    if qscale == 0.0:
        qscale = 1.0
    for k in range(2, max_terms):
        # term = (term @ Fh) / k
        for i in range(n):
            for j in range(n):
                T2[i, j] = 0.0
        for e in range(nz):
            a, b, w = rows[e], cols[e], vals[e]
            for i in range(n):
                T2[i, b] += term[i, a] * w
        tmax = 0.0
        for i in range(n):
            for j in range(n):
                term[i, j] = T2[i, j] * (1.0 / k)
                Phi[i, j] += term[i, j]
                if abs(term[i, j]) > tmax:
                    tmax = abs(term[i, j])
        # C = (Fh C + C Fhᵀ) / (k + 1)
        for i in range(n):
            for j in range(n):
                T1[i, j] = 0.0
        for e in range(nz):
            a, b, w = rows[e], cols[e], vals[e]
            for j in range(n):
                T1[a, j] += w * C[b, j]
        cmax = 0.0
        for i in range(n):
            for j in range(n):
                C[i, j] = (T1[i, j] + T1[j, i]) * (1.0 / (k + 1))
                Qd[i, j] += C[i, j]
                if abs(C[i, j]) > cmax:
                    cmax = abs(C[i, j])
        if tmax <= tol and cmax <= tol * qscale:
            symmetrise_inplace(Qd, Qd.shape[0])
            return True
    return False


@njit(**_JIT)
def _filter_smooth(t, z, Q, R, x0, P0, tol, max_terms, check_pd,
                   x_pred, P_pred, x_filt, P_filt, Phi_all, xs, std, nis, out):
    N = t.size
    n = NS
    x = x0.copy()
    P = P0.copy()
    symmetrise_inplace(P, P.shape[0])
    rows = np.empty(16, np.int64)
    cols = np.empty(16, np.int64)
    vals = np.empty(16)
    Phi = np.empty((n, n)); Qd = np.empty((n, n)); term = np.empty((n, n)); C = np.empty((n, n))
    T1 = np.empty((n, n)); T2 = np.empty((n, n)); L = np.zeros((n, n))
    k1 = np.empty(n); k2 = np.empty(n); k3 = np.empty(n); k4 = np.empty(n); xt = np.empty(n)
    idx = np.empty(NM, np.int64)
    S = np.empty((NM, NM)); Ls = np.zeros((NM, NM)); B = np.empty((NM, n + 1))
    K = np.empty((n, NM)); nu = np.empty(NM); A = np.empty((n, n))
    loglik = 0.0
    for k in range(N):
        if k > 0:
            hk = t[k] - t[k - 1]
            nz = _kin_F_nz(x, hk, rows, cols, vals)
            if not _taylor(rows, cols, vals, nz, Q, hk, tol, max_terms, Phi, Qd, term, C, T1, T2):
                return TAYLOR_NOT_CONVERGED, k
            _kin_rk4(x, hk, k1, k2, k3, k4, xt)
            # P = Φ P Φᵀ + Q_d
            _mm(Phi, P, T1)
            _mmT(T1, Phi, P)
            for i in range(n):
                for j in range(n):
                    P[i, j] += Qd[i, j]
            symmetrise_inplace(P, P.shape[0])
            Phi_all[k - 1] = Phi
        x_pred[k] = x
        P_pred[k] = P
        mo = 0
        for j in range(NM):
            if np.isfinite(z[k, j]):
                idx[mo] = j
                mo += 1
        if mo > 0:
            for a in range(mo):
                nu[a] = z[k, idx[a]] - x[idx[a]]
                for b in range(mo):
                    S[a, b] = P[idx[a], idx[b]] + R[idx[a], idx[b]]
            symmetrise_inplace(S, mo)
            if not cholesky_into(S, mo, Ls):
                return S_NOT_PD, k
            # B = S⁻¹ [H | ν]
            for a in range(mo):
                for j in range(n + 1):
                    B[a, j] = 0.0
                B[a, idx[a]] = 1.0
                B[a, n] = nu[a]
            cho_solve_inplace(Ls, mo, B)
            # K = (S⁻¹ H P)ᵀ = P Hᵀ S⁻¹
            for i in range(n):
                for a in range(mo):
                    s = 0.0
                    for j in range(n):
                        s += B[a, j] * P[j, i]
                    K[i, a] = s
            for i in range(n):
                s = 0.0
                for a in range(mo):
                    s += K[i, a] * nu[a]
                x[i] += s
            # Joseph form: A = I − K H;  P = A P Aᵀ + K R Kᵀ
            for i in range(n):
                for j in range(n):
                    A[i, j] = 1.0 if i == j else 0.0
                for a in range(mo):
                    A[i, idx[a]] -= K[i, a]
            _mm(A, P, T1)
            _mmT(T1, A, T2)
            for i in range(n):
                for j in range(n):
                    s = 0.0
                    for a in range(mo):
                        ka = K[i, a]
                        for b in range(mo):
                            s += ka * R[idx[a], idx[b]] * K[j, b]
                    P[i, j] = T2[i, j] + s
            symmetrise_inplace(P, P.shape[0])
            q = 0.0
            logdet = 0.0
            for a in range(mo):
                q += nu[a] * B[a, n]
                logdet += np.log(Ls[a, a])
            nis[k] = q
            loglik += -0.5 * (q + 2.0 * logdet + mo * LOG2PI)
        if check_pd and (k % 50 == 0 or k == N - 1):
            x_filt[k] = x
            P_filt[k] = P
            ok = True
            for i in range(n):
                for j in range(n):
                    if not np.isfinite(P[i, j]):
                        ok = False
            if not ok or not cholesky_into(P, n, L):
                return P_NOT_PD, k
        x_filt[k] = x
        P_filt[k] = P
    out[0] = loglik
    # RTS backward pass
    Ps = P_filt[N - 1].copy()
    xs[N - 1] = x_filt[N - 1]
    for i in range(n):
        std[N - 1, i] = np.sqrt(max(Ps[i, i], 0.0))
    Pn = np.empty((n, n)); D = np.empty((n, n)); dx = np.empty(n)
    for k in range(N - 2, -1, -1):
        Pf = P_filt[k]
        Pp = P_pred[k + 1]
        for i in range(n):
            for j in range(n):
                A[i, j] = 0.5 * (Pp[i, j] + Pp[j, i])
        if not cholesky_into(A, n, L):
            return P_NOT_PD, k + 1
        _mm(Phi_all[k], Pf, T1)           # Φ P_f
        cho_solve_inplace(L, n, T1)              # Pp⁻¹ Φ P_f = Cᵀ
        for i in range(n):
            dx[i] = xs[k + 1, i] - x_pred[k + 1, i]
        for i in range(n):
            s = 0.0
            for j in range(n):
                s += T1[j, i] * dx[j]
            xs[k, i] = x_filt[k, i] + s
        for i in range(n):
            for j in range(n):
                D[i, j] = Ps[i, j] - Pp[i, j]
        # C D Cᵀ with C = T1ᵀ
        for i in range(n):             # T2 = C D = T1ᵀ D
            for j in range(n):
                s = 0.0
                for a in range(n):
                    s += T1[a, i] * D[a, j]
                T2[i, j] = s
        for i in range(n):
            for j in range(n):
                s = 0.0
                for a in range(n):
                    s += T2[i, a] * T1[a, j]
                Pn[i, j] = Pf[i, j] + s
        symmetrise_inplace(Pn, Pn.shape[0])
        Ps[:, :] = Pn
        for i in range(n):
            std[k, i] = np.sqrt(max(Ps[i, i], 0.0))
    return OK, -1


def kinematic_filter_smoother(t: np.ndarray, z: np.ndarray, Q: np.ndarray, R: np.ndarray, x0: np.ndarray,
                              P0: np.ndarray, *, tol: float = 1e-15, max_terms: int = 40,
                              check_pd: bool = True):
    """Kinematic CD-EKF (eq. 9) and RTS smoother in one compiled pass.

    Parameters
    ----------
    t : ndarray (N,)
    z : ndarray (N, 6)
        Measured ``[x0, y0, ψ, u, v, r]``; NaN = missing (skipped in the update).
    Q : ndarray (9, 9)
        Process-noise spectral density (symmetric).
    R : ndarray (6, 6)
        Measurement-noise covariance.
    x0, P0 : prior at ``t[0]``.

    Returns
    -------
    tuple or None
        ``(x_smooth (N, 9), std_smooth (N, 9), nis (N,), loglik)``; None when the Taylor
        series did not converge at some sample (the caller then runs the reference path).

    Raises
    ------
    NotPositiveDefiniteError
        The innovation covariance or the filtered covariance (checked every 50th sample and at
        the last) is not positive definite; the message is the reference's.
    """

    c = np.ascontiguousarray
    t = c(t, dtype=float)
    z = c(z, dtype=float)
    N = t.size
    if z.shape != (N, NM):
        raise ValueError(f"z must be (N, {NM}), got {z.shape}")
    x_pred = np.empty((N, NS)); P_pred = np.empty((N, NS, NS))
    x_filt = np.empty((N, NS)); P_filt = np.empty((N, NS, NS))
    Phi = np.empty((max(N - 1, 0), NS, NS))
    xs = np.empty((N, NS)); std = np.empty((N, NS)); nis = np.full(N, np.nan); out = np.zeros(1)
    status, k = _filter_smooth(t, z, c(Q, dtype=float), c(R, dtype=float), c(x0, dtype=float).ravel(),
                               c(P0, dtype=float), float(tol), int(max_terms), bool(check_pd),
                               x_pred, P_pred, x_filt, P_filt, Phi, xs, std, nis, out)
    if status == TAYLOR_NOT_CONVERGED:
        return None
    if status == S_NOT_PD:
        ok = np.isfinite(z[k])
        S = P_pred[k][:NM, :NM][np.ix_(ok, ok)] + R[np.ix_(ok, ok)]
        check_positive_definite(0.5 * (S + S.T), f"innovation covariance at sample {k} (t = {t[k]:.6g} s)")
        raise np.linalg.LinAlgError(f"innovation covariance at sample {k} (t = {t[k]:.6g} s) is not positive "
                                    "definite")
    if status == P_NOT_PD:
        M = P_filt[k]
        check_positive_definite(M, f"filter covariance at sample {k} (t = {t[k]:.6g} s)")
        raise np.linalg.LinAlgError(f"filter covariance at sample {k} (t = {t[k]:.6g} s) is not positive definite")
    return xs, std, nis, float(out[0])


__all__ = ["NUMBA_LINALG_KEY", "CACHE_VALID", "kinematic_filter_smoother"]
