"""The initial noise state of the prediction-error likelihood, concentrated out (Linder et al. 2015).

Beyond the paper, for :mod:`shipid.methods.masscm.pem` with a sensor floor (``PEMOptions.sensor_floor``): the
steady-state Kalman predictor starts from a zero noise state; with noise-free channels the predictor's error dynamics
``A = F - K H`` have slow modes (the zeros of the wave-to-output transfer), so a wrong start would weigh on the
innovations over minutes. :func:`without_initial_state` removes from the innovations their response to the initial
state that minimises the weighted sum of squares (Ljung 1999 §7.3: the initial state as parameters, eliminated in
closed form).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _initial_normal(A, H, Li, eps, M, b):
    """Normal equations ``M s0 = b`` of the initial noise state: ``M = sum Phi_k^T Li Phi_k``, ``b = sum Phi_k^T Li
    eps_k``, ``Phi_k = -H A^k`` the innovations' response to the predictor's initial state (``A = F - K H``); the
    sums stop where ``A^k`` has decayed below 1e-13."""
    ns, ny, n = A.shape[0], H.shape[0], eps.shape[0]
    Z = np.eye(ns)
    Zn = np.zeros((ns, ns))
    Phi = np.zeros((ny, ns))
    W = np.zeros((ny, ns))
    for k in range(n):
        for i in range(ny):
            for j in range(ns):
                acc = 0.0
                for l in range(ns):
                    acc -= H[i, l] * Z[l, j]
                Phi[i, j] = acc
        for i in range(ny):
            for j in range(ns):
                acc = 0.0
                for l in range(ny):
                    acc += Li[i, l] * Phi[l, j]
                W[i, j] = acc
        for i in range(ns):
            bi = 0.0
            for l in range(ny):
                bi += W[l, i] * eps[k, l]
            b[i] += bi
            for j in range(ns):
                acc = 0.0
                for l in range(ny):
                    acc += Phi[l, i] * W[l, j]
                M[i, j] += acc
        zmax = 0.0
        for i in range(ns):
            for j in range(ns):
                acc = 0.0
                for l in range(ns):
                    acc += A[i, l] * Z[l, j]
                Zn[i, j] = acc
                zmax = max(zmax, abs(acc))
        Z[:, :] = Zn
        if zmax < 1e-13:
            break


@njit(cache=True)
def _subtract_initial(A, H, s0, eps):
    """``eps_k - Phi_k s0`` in place (``Phi_k s0 = -H A^k s0``), until ``A^k s0`` has decayed."""
    ns, ny = A.shape[0], H.shape[0]
    z = s0.copy()
    zn = np.zeros(ns)
    z0 = max(np.max(np.abs(s0)), 1e-300)
    for k in range(eps.shape[0]):
        for i in range(ny):
            acc = 0.0
            for l in range(ns):
                acc += H[i, l] * z[l]
            eps[k, i] += acc
        zmax = 0.0
        for i in range(ns):
            acc = 0.0
            for l in range(ns):
                acc += A[i, l] * z[l]
            zn[i] = acc
            zmax = max(zmax, abs(acc))
        z[:] = zn
        if zmax < 1e-13 * z0:
            break


def without_initial_state(eps, F, K, H, Lam):
    """``eps`` less its response to the initial noise state that minimises ``sum eps^T Lam^-1 eps`` (weighted least
    squares): the likelihood with the initial state concentrated out (Ljung 1999 §7.3), used with the sensor floor,
    where the steady-state predictor's slow error modes would carry a start from zero over minutes."""
    ns = F.shape[0]
    A = np.ascontiguousarray(F - K @ H)
    Hc = np.ascontiguousarray(H)
    M, b = np.zeros((ns, ns)), np.zeros(ns)
    _initial_normal(A, Hc, np.ascontiguousarray(np.linalg.inv(Lam)), eps, M, b)
    d = np.sqrt(np.maximum(np.diag(M), 1e-300))
    s0 = np.linalg.lstsq(M / np.outer(d, d), b / d, rcond=1e-12)[0] / d
    out = eps.copy()
    _subtract_initial(A, Hc, s0, out)
    return out


__all__ = ["without_initial_state"]
