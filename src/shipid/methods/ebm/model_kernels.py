"""The 17-state EBM model of :mod:`shipid.models.ebm_state` as numba kernels (Yoon & Rhee 2003, eqs. 4–8).

:class:`shipid.models.ebm_state.EbmModel` is the one statement of the equations (``f`` eq. 6,
``F = ∂f/∂x``, ``h`` eq. 8, ``H = ∂h/∂x``); the kernels here compute the same values without
allocating, on the parameter vector of :meth:`~shipid.models.ebm_state.EbmModel.kernel_params`
``p = [m, x_G, Minv (row-major, 9), x_D, y_D, y_S, absolute (0/1)]``.
``tests/methods/ebm/test_kernels.py`` checks them equal to ``EbmModel`` on random states and
parameters (to rounding). Each ``*_into(t, x, p, out)`` writes its result into ``out``; the
allocating wrappers :func:`ebm_f`, :func:`ebm_F`, :func:`ebm_h`, :func:`ebm_H` are for tests
and scripts.

:mod:`shipid.methods.ebm.kernels` links these functions into its compiled filter, so it keys
its on-disk numba cache on this file's contents (:data:`shipid.methods.ebm.kernels.MODEL_KERNELS_KEY`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

_JIT = dict(cache=True, nogil=True, error_model="numpy")  # no ZeroDivisionError checks


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


__all__ = ["ebm_f_into", "ebm_F_into", "ebm_h_into", "ebm_H_into", "ebm_f", "ebm_F", "ebm_h", "ebm_H"]
