"""Compiled (numba) innovation log-likelihood of the DP models at fixed parameters (Fossen, Sagatun & Sørensen 1996).

Fossen, Sagatun & Sørensen (1996): with θ fixed, the state-augmented filter of Table 1 on the
momentum model (eqs. 35–38, ERRATA 001 readings) or on the surge model (eqs. 31–32 in momentum
form) reduces to a plain EKF on the trial state, and the trials of a parallel scheme
(eqs. 20–25) become independent. The Gaussian log-likelihood of its innovations,

    ℓ(θ, q) = Σ_trials Σ_k −½ (ν_kᵀ S_k⁻¹ ν_k + log det 2π S_k),

is the criterion of the prediction-error method around the filter; :mod:`shipid.methods.dp.pem`
maximises it over θ and the noise intensities and differentiates it for the observed
information. The filter here is the one :func:`shipid.estimate.ekf_augmented.augmented_ekf`
runs with a zero parameter covariance: the same RK4 map and its exact chain-rule Jacobian
(:func:`~shipid.estimate.ekf_augmented.rk4_map` of the continuous models of
:mod:`shipid.methods.dp.stage_models`; ``tests/methods/dp/test_rk4_kernels.py`` checks each compiled
step against it), the Joseph-form update, the symmetrised
covariance, the heading innovation wrapped to (−π, π]; ``tests/methods/dp/test_loglik.py``
checks the two agree.

Positive definiteness of the filtered covariance is checked by a Cholesky factorisation at
every sample (:func:`shipid.numerics.numba_linalg.cholesky_into`); on failure the kernels
return the failing step (the caller raises).

Cache. Everything compiled here lives in this one file except that Cholesky kernel. numba
keys the on-disk cache of a function on the file that defines it only, so this file carries
:data:`NUMBA_LINALG_KEY`, the hash of ``shipid/numerics/numba_linalg.py``: an edit there must
update the key here (``tests/methods/dp/test_loglik.py`` checks it). If the key does not match
the file found at import, the kernels are compiled without the disk cache, never run stale.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from shipid.numerics import numba_linalg
from shipid.numerics.numba_linalg import cholesky_into, source_key

#: First 16 hex digits of the SHA-256 of ``shipid/numerics/numba_linalg.py`` (see the module docstring).
NUMBA_LINALG_KEY = "355c3586dc6b4413"

#: True when the on-disk cache may be used: the compiled callee is the one the key names.
CACHE_VALID = source_key(numba_linalg) == NUMBA_LINALG_KEY
_JIT = dict(cache=CACHE_VALID, nogil=True, error_model="numpy")
LOG2PI = float(np.log(2.0 * np.pi))


@njit(**_JIT)
def _mom_f(x, tau, M, Minv, A, out):
    """Eqs. 35–37: ``ẋ`` of ``x = [h, η, b_h]`` with thrust force ``tau`` (bis)."""
    nu0 = Minv[0, 0] * x[0] + Minv[0, 1] * x[1] + Minv[0, 2] * x[2]
    nu1 = Minv[1, 0] * x[0] + Minv[1, 1] * x[1] + Minv[1, 2] * x[2]
    nu2 = Minv[2, 0] * x[0] + Minv[2, 1] * x[1] + Minv[2, 2] * x[2]
    m11, m22, m23 = M[0, 0], M[1, 1], M[1, 2]
    a = m22 * nu1 + m23 * nu2
    cn0 = -a * nu2
    cn1 = m11 * nu0 * nu2
    cn2 = a * nu0 - m11 * nu0 * nu1
    for i in range(3):
        out[i] = (A[i, 0] * x[0] + A[i, 1] * x[1] + A[i, 2] * x[2] + tau[i] + x[6 + i])
    out[0] -= cn0
    out[1] -= cn1
    out[2] -= cn2
    c, s = np.cos(x[5]), np.sin(x[5])
    out[3] = c * nu0 - s * nu1
    out[4] = s * nu0 + c * nu1
    out[5] = nu2
    out[6] = 0.0
    out[7] = 0.0
    out[8] = 0.0


@njit(**_JIT)
def _mom_jac(x, M, Minv, A, F):
    """∂ẋ/∂x of :func:`_mom_f` (the ``Fx`` of :func:`shipid.models.dp.momentum_jacobian`)."""
    F[:, :] = 0.0
    u = Minv[0, 0] * x[0] + Minv[0, 1] * x[1] + Minv[0, 2] * x[2]
    v = Minv[1, 0] * x[0] + Minv[1, 1] * x[1] + Minv[1, 2] * x[2]
    r = Minv[2, 0] * x[0] + Minv[2, 1] * x[1] + Minv[2, 2] * x[2]
    m11, m22, m23 = M[0, 0], M[1, 1], M[1, 2]
    a = m22 * v + m23 * r
    J00, J01, J02 = 0.0, -m22 * r, -a - m23 * r
    J10, J11, J12 = m11 * r, 0.0, m11 * u
    J20, J21, J22 = a - m11 * v, (m22 - m11) * u, m23 * u
    for j in range(3):
        F[0, j] = A[0, j] - (J00 * Minv[0, j] + J01 * Minv[1, j] + J02 * Minv[2, j])
        F[1, j] = A[1, j] - (J10 * Minv[0, j] + J11 * Minv[1, j] + J12 * Minv[2, j])
        F[2, j] = A[2, j] - (J20 * Minv[0, j] + J21 * Minv[1, j] + J22 * Minv[2, j])
    for i in range(3):
        F[i, 6 + i] = 1.0
    c, s = np.cos(x[5]), np.sin(x[5])
    for j in range(3):
        F[3, j] = c * Minv[0, j] - s * Minv[1, j]
        F[4, j] = s * Minv[0, j] + c * Minv[1, j]
        F[5, j] = Minv[2, j]
    F[3, 5] = -s * u - c * v
    F[4, 5] = c * u - s * v


@njit(**_JIT)
def _matmul_into(A, B, out, n):
    """``out = A @ B`` for n × n matrices (explicit loops: no BLAS call for a 9 × 9 product)."""
    for i in range(n):
        for j in range(n):
            acc = 0.0
            for l in range(n):
                acc += A[i, l] * B[l, j]
            out[i, j] = acc


@njit(**_JIT)
def _mom_rk4(x, tau, M, Minv, A, dt, Phi):
    """One RK4 step of eqs. 35–37 and its exact Jacobian into ``Phi``.

    The compiled twin of ``rk4_map`` on :func:`shipid.methods.dp.stage_models.momentum_model`
    (without current states); ``tests/methods/dp/test_rk4_kernels.py`` checks they agree.
    """
    n = 9
    k1 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    k4 = np.empty(n)
    Aj = np.empty((n, n))
    S = np.empty((n, n))
    Kc = np.empty((n, n))
    Ks = np.empty((n, n))
    _mom_f(x, tau, M, Minv, A, k1)
    _mom_jac(x, M, Minv, A, Aj)
    for i in range(n):
        for j in range(n):
            Ks[i, j] = Aj[i, j]
            S[i, j] = (1.0 if i == j else 0.0) + 0.5 * dt * Aj[i, j]
    x2 = x + 0.5 * dt * k1
    _mom_f(x2, tau, M, Minv, A, k2)
    _mom_jac(x2, M, Minv, A, Aj)
    _matmul_into(Aj, S, Kc, n)                       # K2 = A2 (I + dt/2 A1)
    for i in range(n):
        for j in range(n):
            Ks[i, j] += 2.0 * Kc[i, j]
            S[i, j] = (1.0 if i == j else 0.0) + 0.5 * dt * Kc[i, j]
    x3 = x + 0.5 * dt * k2
    _mom_f(x3, tau, M, Minv, A, k3)
    _mom_jac(x3, M, Minv, A, Aj)
    _matmul_into(Aj, S, Kc, n)                       # K3 = A3 (I + dt/2 K2)
    for i in range(n):
        for j in range(n):
            Ks[i, j] += 2.0 * Kc[i, j]
            S[i, j] = (1.0 if i == j else 0.0) + dt * Kc[i, j]
    x4 = x + dt * k3
    _mom_f(x4, tau, M, Minv, A, k4)
    _mom_jac(x4, M, Minv, A, Aj)
    _matmul_into(Aj, S, Kc, n)                       # K4 = A4 (I + dt K3)
    for i in range(n):
        for j in range(n):
            Phi[i, j] = (1.0 if i == j else 0.0) + dt / 6.0 * (Ks[i, j] + Kc[i, j])
    return x + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


@njit(**_JIT)
def _propagate(Phi, P, q, W, n):
    """``P = sym(Φ P Φᵀ + diag(q))`` in place (W: n × n work)."""
    _matmul_into(Phi, P, W, n)
    for i in range(n):
        for j in range(i, n):
            acc = 0.0
            for l in range(n):
                acc += W[i, l] * Phi[j, l]
            if i == j:
                P[i, i] = acc + q[i]
            else:
                P[i, j] = acc
    for i in range(n):
        for j in range(i + 1, n):
            P[j, i] = P[i, j]


@njit(**_JIT)
def _surge_rk4(x, tau, Ac, h):
    """One RK4 step of eqs. 31–32 (momentum form), the linear ``ẋ = Ac x + [τ, 0, 0]``, and its Φ.

    Returns ``(x_next, Φ)``: the compiled twin of ``rk4_map`` on
    :func:`shipid.methods.dp.stage_models.surge_model`; ``tests/methods/dp/test_rk4_kernels.py``
    checks they agree.
    """
    I = np.eye(3)
    c = np.array([tau, 0.0, 0.0])
    k1 = Ac @ x + c
    k2 = Ac @ (x + 0.5 * h * k1) + c
    k3 = Ac @ (x + 0.5 * h * k2) + c
    k4 = Ac @ (x + h * k3) + c
    K2 = Ac @ (I + 0.5 * h * Ac)
    K3 = Ac @ (I + 0.5 * h * K2)
    K4 = Ac @ (I + h * K3)
    Phi = I + h / 6.0 * (Ac + 2.0 * K2 + 2.0 * K3 + K4)
    return x + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4), Phi


@njit(**_JIT)
def _update(x, P, nu, Hidx, R, nis_ll):
    """Joseph-form update with measurements ``x[Hidx] + v``; adds (NIS, log det 2πS) to nis_ll.

    ``P⁺ = (I − KH) P (I − KH)ᵀ + K R Kᵀ`` with ``K = P Hᵀ S⁻¹`` (through the Cholesky factor of
    S), written out for a selection matrix H, symmetrised. Returns False when S or the updated
    P is not positive definite.
    """
    n = x.size
    m = Hidx.size
    S = np.empty((m, m))
    for i in range(m):
        for j in range(m):
            S[i, j] = 0.5 * (P[Hidx[i], Hidx[j]] + P[Hidx[j], Hidx[i]]) + (R[i] if i == j else 0.0)
    L = np.zeros((m, m))
    if not cholesky_into(S, m, L):
        return False
    # Kᵀ = S⁻¹ H P by forward and back substitution
    Kt = np.empty((m, n))
    for c in range(n):
        for a in range(m):
            v = P[Hidx[a], c]
            for b in range(a):
                v -= L[a, b] * Kt[b, c]
            Kt[a, c] = v / L[a, a]
        for a in range(m - 1, -1, -1):
            v = Kt[a, c]
            for b in range(a + 1, m):
                v -= L[b, a] * Kt[b, c]
            Kt[a, c] = v / L[a, a]
    w = np.empty(m)
    for a in range(m):
        v = nu[a]
        for b in range(a):
            v -= L[a, b] * w[b]
        w[a] = v / L[a, a]
    ld = 0.0
    for a in range(m):
        nis_ll[0] += w[a] * w[a]
        ld += 2.0 * np.log(L[a, a])
    nis_ll[1] += ld + m * LOG2PI
    nis_ll[2] += m
    for i in range(n):
        acc = 0.0
        for a in range(m):
            acc += Kt[a, i] * nu[a]
        x[i] += acc
    # M1 = (I − KH) P ; P⁺ = M1 (I − KH)ᵀ + K R Kᵀ = M1 − M1 Hᵀ Kᵀ + K R Kᵀ
    M1 = P.copy()
    for i in range(n):
        for j in range(n):
            acc = 0.0
            for a in range(m):
                acc += Kt[a, i] * P[Hidx[a], j]
            M1[i, j] -= acc
    Pn = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            acc = M1[i, j]
            for a in range(m):
                acc += -M1[i, Hidx[a]] * Kt[a, j] + Kt[a, i] * R[a] * Kt[a, j]
            Pn[i, j] = acc
    for i in range(n):
        for j in range(n):
            P[i, j] = 0.5 * (Pn[i, j] + Pn[j, i])
    for i in range(n):
        if not P[i, i] > 0.0:
            return False
    return cholesky_into(P, n, Pn)         # positive definiteness (Pn, no longer needed, holds the factor)


@njit(**_JIT)
def momentum_loglik(Z, dt, tau, M, Minv, A, qh, qb, R, x0, P0):
    """Innovation log-likelihood of one trial of the momentum model at fixed θ.

    Parameters
    ----------
    Z : (n, 3) measured x'', y'', ψ (NaN rows: no fix)
    dt : (n−1,) bis sample intervals
    tau : (n, 3) thrust force T(α) K u of each sample (bis), held over the step
    M, Minv, A : (3, 3) M'', its inverse and A_h
    qh, qb : (3,) intensities of w_h and w_b per component (bis)
    R : (3,) measurement variances
    x0, P0 : prior of ``[h, η, b_h]``

    Returns
    -------
    (loglik, nis_sum, n_channels_used, failed_step) ; failed_step = −1 when all went well.
    """
    n = Z.shape[0]
    x = x0.copy()
    P = P0.copy()
    Phi = np.empty((9, 9))
    W = np.empty((9, 9))
    Hidx = np.array([3, 4, 5])
    acc = np.zeros(3)
    Q = np.zeros(9)
    for k in range(n):
        if np.isfinite(Z[k, 0]) and np.isfinite(Z[k, 1]) and np.isfinite(Z[k, 2]):
            nu = np.empty(3)
            nu[0] = Z[k, 0] - x[3]
            nu[1] = Z[k, 1] - x[4]
            d = Z[k, 2] - x[5]
            nu[2] = np.arctan2(np.sin(d), np.cos(d))
            if not _update(x, P, nu, Hidx, R, acc):
                return -np.inf, acc[0], acc[2], k
        if k == n - 1:
            break
        xn = _mom_rk4(x, tau[k], M, Minv, A, dt[k], Phi)
        for i in range(3):
            Q[i] = qh[i] * dt[k]
            Q[6 + i] = qb[i] * dt[k]
        _propagate(Phi, P, Q, W, 9)
        x = xn
        if not np.all(np.isfinite(x)):
            return -np.inf, acc[0], acc[2], k
    return -0.5 * (acc[0] + acc[1]), acc[0], acc[2], -1


@njit(**_JIT)
def surge_loglik(Z, dt, tau, m11, a11, qh, qb, R, x0, P0):
    """Innovation log-likelihood of one surge trial (eqs. 31–32, momentum form) at fixed θ.

    State ``[h_u, s, b_u]``, ``ḣ_u = θ1 h_u + τ_u + b_u``, ``ṡ = h_u / m11``; ``Z`` (n,) the
    distance run s'' (NaN: no fix), ``tau`` (n,) the thrust force, ``a11`` = θ1, ``qh, qb``
    scalars, ``R`` the variance of s''. Returns as :func:`momentum_loglik`.
    """
    n = Z.shape[0]
    x = x0.copy()
    P = P0.copy()
    Hidx = np.array([1])
    Rv = np.array([R])
    acc = np.zeros(3)
    Ac = np.zeros((3, 3))
    Ac[0, 0] = a11
    Ac[0, 2] = 1.0
    Ac[1, 0] = 1.0 / m11
    for k in range(n):
        if np.isfinite(Z[k]):
            nu = np.array([Z[k] - x[1]])
            if not _update(x, P, nu, Hidx, Rv, acc):
                return -np.inf, acc[0], acc[2], k
        if k == n - 1:
            break
        h = dt[k]
        x, Phi = _surge_rk4(x, tau[k], Ac, h)
        Pn = Phi @ P @ Phi.T
        Pn[0, 0] += qh * h
        Pn[2, 2] += qb * h
        P = 0.5 * (Pn + Pn.T)
    return -0.5 * (acc[0] + acc[1]), acc[0], acc[2], -1


__all__ = ["NUMBA_LINALG_KEY", "CACHE_VALID", "momentum_loglik", "surge_loglik", "LOG2PI"]
