"""Compiled (numba) parallel state-augmented EKF of the DP schemes (Fossen, Sagatun & Sørensen 1996).

The filter of Table 1 (eqs. 15–19) on the parallel configuration of eqs. 20–25: N trials of one
scheme stacked as ``ξ = [x1; …; xN; θ]``, on the surge model (eqs. 31–32 in momentum form, state
``[h_u, s, b_u]``) or the momentum model (eqs. 35–38, ERRATA 001 readings, state ``[h, η, b_h]``).
It is the compiled twin of :func:`shipid.estimate.ekf_augmented.parallel_augmented_ekf` on the
models of :mod:`shipid.methods.dp.stage_models` and computes the same thing in the same order:

* time update: one RK4 step of each active trial's continuous model with its exact chain-rule
  Jacobians ``∂x⁺/∂x`` and ``∂x⁺/∂θ`` (the variational system stepped by the same four stages as
  :func:`shipid.numerics.integrate.rk4_step_jacobians`), ``P = sym(Φ P Φᵀ + Q)``; a trial past
  its last sample is frozen (identity, no noise);
* measurement update over every channel measured at the step: ``S = sym(H P Hᵀ + R)``,
  ``K = P Hᵀ S⁻¹`` through the Cholesky factor of S, zero gain rows for the considered
  (Schmidt–Kalman) parameters, the Joseph form ``(I − KH) P (I − KH)ᵀ + K R Kᵀ``, symmetrised,
  and a Cholesky test of positive definiteness; heading innovations wrapped to (−π, π].

``tests/estimate/test_ekf_augmented.py`` checks that it agrees with the Python filter to
round-off (1e-12 relative in θ, its covariance and the log-likelihood); ``tests/methods/dp/
test_rk4_kernels.py`` checks its RK4 step against the package's one RK4.

Everything compiled here lives in this one file (numba's on-disk cache is keyed on it).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from shipid.numerics import numba_linalg
from shipid.numerics.numba_linalg import cholesky_into as _chol
from shipid.numerics.numba_linalg import source_key

#: First 16 hex digits of the SHA-256 of ``shipid/numerics/numba_linalg.py``, whose Cholesky kernel the
#: filter calls: numba keys the on-disk cache on this file only, so an edit there must update this key
#: (``tests/numerics/test_numba_linalg.py`` checks it); if it does not match, the kernels compile without
#: the disk cache, never run stale.
NUMBA_LINALG_KEY = "355c3586dc6b4413"
CACHE_VALID = source_key(numba_linalg) == NUMBA_LINALG_KEY
_JIT = dict(cache=CACHE_VALID, nogil=True, error_model="numpy")
LOG2PI = float(np.log(2.0 * np.pi))
#: Model codes of :func:`parallel_aekf`.
SURGE, MOMENTUM = 0, 1


@njit(**_JIT)
def _model(kind, x, u, th, M, Minv, arms, f, A, B):
    """``ẋ`` (into f), ``∂ẋ/∂x`` (A) and ``∂ẋ/∂θ`` for all nine θ (B, nx × 9) of one trial.

    ``u = [u1 … u6, α6]``; surge: eqs. 31–32 in momentum form; momentum: eqs. 35–37.
    """
    A[:, :] = 0.0
    B[:, :] = 0.0
    ca, sa = np.cos(u[6]), np.sin(u[6])
    if kind == SURGE:
        m11 = M[0, 0]
        f[0] = th[0] * x[0] + th[5] * (u[0] + u[1]) + th[8] * ca * u[5] + x[2]
        f[1] = x[0] / m11
        f[2] = 0.0
        A[0, 0] = th[0]
        A[0, 2] = 1.0
        A[1, 0] = 1.0 / m11
        B[0, 0] = x[0]
        B[0, 5] = u[0] + u[1]
        B[0, 8] = ca * u[5]
        return
    l1, l2, l3, l4, l5, l6 = arms[0], arms[1], arms[2], arms[3], arms[4], arms[5]
    k1 = th[5] * u[0]
    k2 = th[5] * u[1]
    k3 = th[6] * u[2]
    k4 = th[6] * u[3]
    k5 = th[7] * u[4]
    k6 = th[8] * u[5]
    tau0 = k1 + k2 + ca * k6
    tau1 = k3 + k4 + k5 + sa * k6
    tau2 = l1 * k1 - l2 * k2 - l3 * k3 - l4 * k4 + l5 * k5 + l6 * sa * k6
    nu0 = Minv[0, 0] * x[0] + Minv[0, 1] * x[1] + Minv[0, 2] * x[2]
    nu1 = Minv[1, 0] * x[0] + Minv[1, 1] * x[1] + Minv[1, 2] * x[2]
    nu2 = Minv[2, 0] * x[0] + Minv[2, 1] * x[1] + Minv[2, 2] * x[2]
    m11, m22, m23 = M[0, 0], M[1, 1], M[1, 2]
    a = m22 * nu1 + m23 * nu2
    Ah00, Ah11, Ah12, Ah21, Ah22 = th[0], th[1], th[2], th[3], th[4]
    f[0] = -(-a * nu2) + Ah00 * x[0] + tau0 + x[6]
    f[1] = -(m11 * nu0 * nu2) + Ah11 * x[1] + Ah12 * x[2] + tau1 + x[7]
    f[2] = -(a * nu0 - m11 * nu0 * nu1) + Ah21 * x[1] + Ah22 * x[2] + tau2 + x[8]
    c, s = np.cos(x[5]), np.sin(x[5])
    f[3] = c * nu0 - s * nu1
    f[4] = s * nu0 + c * nu1
    f[5] = nu2
    f[6] = 0.0
    f[7] = 0.0
    f[8] = 0.0
    # ∂(C(ν)ν)/∂ν, times M⁻¹
    J = np.zeros((3, 3))
    J[0, 1] = -m22 * nu2
    J[0, 2] = -a - m23 * nu2
    J[1, 0] = m11 * nu2
    J[1, 2] = m11 * nu0
    J[2, 0] = a - m11 * nu1
    J[2, 1] = (m22 - m11) * nu0
    J[2, 2] = m23 * nu0
    for i in range(3):
        for j in range(3):
            acc = 0.0
            for l in range(3):
                acc += J[i, l] * Minv[l, j]
            A[i, j] = -acc
    A[0, 0] += Ah00
    A[1, 1] += Ah11
    A[1, 2] += Ah12
    A[2, 1] += Ah21
    A[2, 2] += Ah22
    A[0, 6] = 1.0
    A[1, 7] = 1.0
    A[2, 8] = 1.0
    for j in range(3):
        A[3, j] = c * Minv[0, j] - s * Minv[1, j]
        A[4, j] = s * Minv[0, j] + c * Minv[1, j]
        A[5, j] = Minv[2, j]
    A[3, 5] = -s * nu0 - c * nu1
    A[4, 5] = c * nu0 - s * nu1
    # eq. 46 (θ1..θ5 in A_h) and eq. 47 with the columns of eq. 7 (θ6..θ9)
    B[0, 0] = x[0]
    B[1, 1] = x[1]
    B[1, 2] = x[2]
    B[2, 3] = x[1]
    B[2, 4] = x[2]
    B[0, 5] = u[0] + u[1]
    B[2, 5] = l1 * u[0] - l2 * u[1]
    B[1, 6] = u[2] + u[3]
    B[2, 6] = -l3 * u[2] - l4 * u[3]
    B[1, 7] = u[4]
    B[2, 7] = l5 * u[4]
    B[0, 8] = ca * u[5]
    B[1, 8] = sa * u[5]
    B[2, 8] = l6 * sa * u[5]


@njit(**_JIT)
def rk4_aug(kind, x, u, th, est, M, Minv, arms, h, Fx, Ft):
    """One RK4 step of a trial's model and its exact Jacobians (into Fx (nx, nx), Ft (nx, p)).

    The compiled twin of :func:`shipid.numerics.integrate.rk4_step_jacobians`: the variational
    system ``ẋ = f``, ``Ṡ_x = A S_x``, ``Ṡ_θ = A S_θ + B`` stepped by the same four stages from
    ``S_x = I``, ``S_θ = 0``. Returns the next state.
    """
    nx = x.size
    p = est.size
    f = np.empty(nx)
    A = np.empty((nx, nx))
    B9 = np.empty((nx, 9))
    kx = np.empty((4, nx))
    kS = np.empty((4, nx, nx))
    kT = np.empty((4, nx, p))
    xs = x.copy()
    Sx = np.eye(nx)
    St = np.zeros((nx, p))
    for st in range(4):
        if st == 1 or st == 2:
            w = 0.5 * h
        else:
            w = h
        if st > 0:
            for i in range(nx):
                xs[i] = x[i] + w * kx[st - 1, i]
                for j in range(nx):
                    Sx[i, j] = (1.0 if i == j else 0.0) + w * kS[st - 1, i, j]
                for j in range(p):
                    St[i, j] = 0.0 + w * kT[st - 1, i, j]
        _model(kind, xs, u, th, M, Minv, arms, f, A, B9)
        for i in range(nx):
            kx[st, i] = f[i]
            for j in range(nx):
                acc = 0.0
                for l in range(nx):
                    acc += A[i, l] * Sx[l, j]
                kS[st, i, j] = acc
            for j in range(p):
                acc = 0.0
                for l in range(nx):
                    acc += A[i, l] * St[l, j]
                kT[st, i, j] = acc + B9[i, est[j]]
    c = h / 6.0
    xn = np.empty(nx)
    for i in range(nx):
        xn[i] = x[i] + c * (kx[0, i] + 2.0 * kx[1, i] + 2.0 * kx[2, i] + kx[3, i])
        for j in range(nx):
            Fx[i, j] = (1.0 if i == j else 0.0) + c * (kS[0, i, j] + 2.0 * kS[1, i, j] + 2.0 * kS[2, i, j]
                                                       + kS[3, i, j])
        for j in range(p):
            Ft[i, j] = 0.0 + c * (kT[0, i, j] + 2.0 * kT[1, i, j] + 2.0 * kT[2, i, j] + kT[3, i, j])
    return xn


@njit(**_JIT)
def parallel_aekf(kind, Z, lens, dt, U, th_full, est, x0, P0, qx, Qt, R, cons, wrap, M, Minv, arms):
    """Parallel state-augmented EKF over N trials (eqs. 20–25, Table 1); see the module docstring.

    Parameters
    ----------
    kind : int
        :data:`SURGE` or :data:`MOMENTUM`.
    Z : (N, n, nz)
        Measurements of each trial (the measured states are ``x[nx − … ]``: s for surge, η for
        momentum), NaN where missing or past the trial's end.
    lens : (N,) int
        Samples of each trial.
    dt : (N, n) sample intervals (bis) of each trial's step k → k + 1.
    U : (N, n, 7) inputs ``[u1 … u6, α6]`` held over each step.
    th_full : (9,) θ1..θ9: the values of those not estimated.
    est : (p,) int
        Indices of θ in the augmented state (free and considered).
    x0 : (N, nx); P0 : (N nx + p, N nx + p)
    qx : (N, nx) process-noise intensities of each trial's states (× dt per step).
    Qt : (p, p) parameter random walk per step.
    R : (N, nz) measurement variances.
    cons : (p,) bool
        Considered parameters (zero gain rows).
    wrap : (nz,) bool
        Channels whose innovation is an angle.

    Returns
    -------
    X (N, n, nx), TH (n, p), PTH (n, p, p), PD (n, nξ), INN (n, N nz), SS (n, N nz, N nz), NIS (n,),
    NIS_TR (N, n), loglik, P (the last), failed step (−1: none; its cause in ``fail_code``: 1 S or P not positive
    definite, 2 non-finite state), fail_code.
    """
    N, n, nz = Z.shape
    nx = x0.shape[1]
    p = est.size
    nxi = N * nx + p
    mz = N * nz
    th = th_full.copy()
    xi = np.empty(nxi)
    for i in range(N):
        for j in range(nx):
            xi[i * nx + j] = x0[i, j]
    for j in range(p):
        xi[N * nx + j] = th_full[est[j]]
    P = 0.5 * (P0 + P0.T)
    X = np.empty((N, n, nx))
    TH = np.empty((n, p))
    PTH = np.empty((n, p, p))
    PD = np.empty((n, nxi))
    INN = np.full((n, mz), np.nan)
    SS = np.full((n, mz, mz), np.nan)
    NIS = np.full(n, np.nan)
    NIS_TR = np.full((N, n), np.nan)
    loglik = 0.0
    Lp = np.zeros((nxi, nxi))
    Phi = np.eye(nxi)
    Fx = np.empty((nx, nx))
    Ft = np.empty((nx, p))
    rows = np.empty(mz, dtype=np.int64)     # measured channel -> index in ξ
    chan = np.empty(mz, dtype=np.int64)     # measured channel -> index in the stacked z
    off = 1 if kind == SURGE else 3         # first measured state: s (surge) or η (momentum)
    for k in range(n):
        m = 0
        for i in range(N):
            for c in range(nz):
                if np.isfinite(Z[i, k, c]):
                    rows[m] = i * nx + off + c
                    chan[m] = i * nz + c
                    m += 1
        if m > 0:
            S = np.empty((m, m))
            HP = np.empty((m, nxi))
            nu = np.empty(m)
            Rm = np.zeros(m)
            for a in range(m):
                HP[a, :] = P[rows[a], :]
                i, c = chan[a] // nz, chan[a] % nz
                Rm[a] = R[i, c]
                d = Z[i, k, c] - xi[rows[a]]
                if wrap[c]:
                    d = np.arctan2(np.sin(d), np.cos(d))
                nu[a] = d
            for a in range(m):
                for b in range(m):
                    S[a, b] = HP[a, rows[b]] + (Rm[a] if a == b else 0.0)
            S = 0.5 * (S + S.T)
            Ls = np.zeros((m, m))
            if not _chol(S, m, Ls):
                return X, TH, PTH, PD, INN, SS, NIS, NIS_TR, loglik, P, k, 1
            # K = (S⁻¹ H P)ᵀ by forward and back substitution on the factor
            Y = np.empty((m, nxi))
            for col in range(nxi):
                for a in range(m):
                    s_ = HP[a, col]
                    for b in range(a):
                        s_ -= Ls[a, b] * Y[b, col]
                    Y[a, col] = s_ / Ls[a, a]
                for a in range(m - 1, -1, -1):
                    s_ = Y[a, col]
                    for b in range(a + 1, m):
                        s_ -= Ls[b, a] * Y[b, col]
                    Y[a, col] = s_ / Ls[a, a]
            K = Y.T.copy()
            for j in range(p):
                if cons[j]:
                    K[N * nx + j, :] = 0.0
            xi += K @ nu
            IKH = np.eye(nxi)
            for a in range(m):
                for r in range(nxi):
                    IKH[r, rows[a]] -= K[r, a]
            KR = K * Rm
            Pn = IKH @ P @ IKH.T + KR @ K.T
            P = 0.5 * (Pn + Pn.T)
            if not _chol(P, nxi, Lp):
                return X, TH, PTH, PD, INN, SS, NIS, NIS_TR, loglik, P, k, 1
            w = np.empty(m)
            for a in range(m):
                s_ = nu[a]
                for b in range(a):
                    s_ -= Ls[a, b] * w[b]
                w[a] = s_ / Ls[a, a]
            nis = 0.0
            ld = 0.0
            for a in range(m):
                nis += w[a] * w[a]
                ld += np.log(Ls[a, a])
            NIS[k] = nis
            loglik += -0.5 * (nis + 2.0 * ld + m * LOG2PI)
            for a in range(m):
                INN[k, chan[a]] = nu[a]
                for b in range(m):
                    SS[k, chan[a], chan[b]] = S[a, b]
            # NIS of each trial from its own block of S
            for i in range(N):
                idx = np.empty(nz, dtype=np.int64)
                mi = 0
                for a in range(m):
                    if chan[a] // nz == i:
                        idx[mi] = a
                        mi += 1
                if mi == 0:
                    continue
                Si = np.empty((mi, mi))
                vi = np.empty(mi)
                for a in range(mi):
                    vi[a] = nu[idx[a]]
                    for b in range(mi):
                        Si[a, b] = S[idx[a], idx[b]]
                NIS_TR[i, k] = vi @ np.linalg.solve(Si, vi)
        for j in range(nxi):
            if not np.isfinite(xi[j]):
                return X, TH, PTH, PD, INN, SS, NIS, NIS_TR, loglik, P, k, 2
        for i in range(N):
            for j in range(nx):
                X[i, k, j] = xi[i * nx + j]
        for j in range(p):
            TH[k, j] = xi[N * nx + j]
            for l in range(p):
                PTH[k, j, l] = P[N * nx + j, N * nx + l]
        for j in range(nxi):
            PD[k, j] = P[j, j]
        if k == n - 1:
            break
        # time update
        for j in range(p):
            th[est[j]] = xi[N * nx + j]
        Phi[:, :] = 0.0
        for j in range(nxi):
            Phi[j, j] = 1.0
        Q = np.zeros(nxi)
        for i in range(N):
            if k < lens[i] - 1:
                xn = rk4_aug(kind, xi[i * nx:(i + 1) * nx].copy(), U[i, k], th, est, M, Minv, arms, dt[i, k],
                             Fx, Ft)
                for a in range(nx):
                    xi[i * nx + a] = xn[a]
                    for b in range(nx):
                        Phi[i * nx + a, i * nx + b] = Fx[a, b]
                    for b in range(p):
                        Phi[i * nx + a, N * nx + b] = Ft[a, b]
                    Q[i * nx + a] = qx[i, a] * dt[i, k]
        Pn = Phi @ P @ Phi.T
        for a in range(nxi):
            Pn[a, a] += Q[a]
        for a in range(p):
            for b in range(p):
                Pn[N * nx + a, N * nx + b] += Qt[a, b]
        P = 0.5 * (Pn + Pn.T)
    return X, TH, PTH, PD, INN, SS, NIS, NIS_TR, loglik, P, -1, 0


__all__ = ["SURGE", "MOMENTUM", "LOG2PI", "NUMBA_LINALG_KEY", "CACHE_VALID", "parallel_aekf", "rk4_aug"]
