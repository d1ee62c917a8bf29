"""Butterworth band-pass in second-order sections and its zero-phase application, with the arithmetic of
``scipy.signal.butter(..., btype="bandpass", output="sos", fs=fs)`` and ``scipy.signal.sosfiltfilt``.

Design (:func:`butter_bandpass_sos`): the analogue prototype's poles ``-exp(i pi m / (2N))``,
``m = -N+1, -N+3, .., N-1`` (Butterworth 1930), pre-warped band edges ``4 tan(pi W / 2)`` (``W`` the edges over
the Nyquist frequency), the low-pass to band-pass substitution ``s -> (s^2 + wo^2) / (bw s)``, the bilinear
transform at ``fs = 2`` and the pairing of poles and zeros into sections nearest the unit circle first (scipy's
``zpk2sos`` with ``pairing="nearest"``): the same numpy operations in the same order as scipy's functions, so the
same doubles (``tests/numerics/test_butter.py`` compares them bit for bit).

Filtering (:func:`sosfiltfilt`): scipy's default ``padtype="odd"`` extension by ``3 (2 n_sections + 1 - z)``
samples, the steady-state initial conditions of ``sosfilt_zi`` scaled by the first sample, the cascade in the
direct form II transposed (:func:`_sosfilt`, compiled, no fast-math) forward and backward. Importing
``scipy.signal`` (which imports ``scipy.stats`` and ``scipy.optimize``) is thereby avoided where only this
filter is needed.
"""

from __future__ import annotations

import numpy as np
from numba import njit


def _cplxreal(z):
    """Complex-conjugate pairs (positive imaginary part) and real values of ``z``, as scipy's ``_cplxreal``."""
    z = np.atleast_1d(z)
    if z.size == 0:
        return z, z
    tol = 100 * np.finfo((1.0 * z).dtype).eps
    z = z[np.lexsort((abs(z.imag), z.real))]
    real_indices = abs(z.imag) <= tol * abs(z)
    zr = z[real_indices].real
    if len(zr) == len(z):
        return np.array([]), zr
    z = z[~real_indices]
    zp = z[z.imag > 0]
    zn = z[z.imag < 0]
    if len(zp) != len(zn):
        raise ValueError("array contains a complex value with no matching conjugate")
    same_real = np.diff(zp.real) <= tol * abs(zp[:-1])
    diffs = np.diff(np.concatenate(([0], same_real, [0])))
    run_starts = np.nonzero(diffs > 0)[0]
    run_stops = np.nonzero(diffs < 0)[0]
    for i in range(len(run_starts)):
        start = run_starts[i]
        stop = run_stops[i] + 1
        for chunk in (zp[start:stop], zn[start:stop]):
            chunk[...] = chunk[np.lexsort([abs(chunk.imag)])]
    if any(abs(zp - zn.conj()) > tol * abs(zn)):
        raise ValueError("array contains a complex value with no matching conjugate")
    return (zp + zn.conj()) / 2, zr


def _poly(zeros) -> np.ndarray:
    """Coefficients of ``prod (x - z)`` by repeated convolution, real when the roots are conjugate pairs."""
    zeros = np.atleast_1d(np.asarray(zeros))
    if zeros.shape[0] == 0:
        return np.asarray(1.0, dtype=np.real(zeros).dtype)
    a = np.ones((1,), dtype=zeros.dtype)
    one = np.ones_like(zeros[0])
    for zero in zeros:
        a = np.convolve(a, np.stack((one, -zero)), mode="full")
    if np.iscomplexobj(a):
        roots = np.asarray(zeros, dtype=np.complex128)
        if np.all(np.sort(np.imag(roots)) == np.sort(np.imag(np.conj(roots)))):
            a = np.array(np.real(a), copy=True)
    return a


def _section(z, p) -> np.ndarray:
    """One second-order section ``[b, a]`` (6,) of unit gain from two zeros and two poles."""
    z, p = np.asarray(z), np.asarray(p)
    k = np.asarray(1, dtype=np.result_type(np.real(z), np.real(p), 1))
    if np.issubdtype(k.dtype, np.integer):
        k = k.astype(np.float64)
    b = np.multiply(np.atleast_1d(k), _poly(z))
    a = np.atleast_1d(_poly(p))
    sos = np.zeros(6)
    sos[3 - len(b):3] = b
    sos[6 - len(a):6] = a
    return sos


def _nearest(fro, to, which: str) -> int:
    """Index of the element of ``fro`` nearest ``to`` among the real, complex or all elements."""
    order = np.argsort(np.abs(fro - to))
    if which == "any":
        return order[0]
    mask = np.isreal(fro[order])
    if which == "complex":
        mask = ~mask
    return order[np.nonzero(mask)[0][0]]


def _zpk2sos(z, p, k) -> np.ndarray:
    """Second-order sections of a digital filter from its zeros, poles and gain (equal numbers of zeros and poles,
    pairing nearest the unit circle first), as scipy's ``zpk2sos(z, p, k)``."""
    z, p, k = np.asarray(z), np.asarray(p), np.asarray(k)
    p = np.concatenate((p, np.zeros(max(len(z) - len(p), 0))))
    z = np.concatenate((z, np.zeros(max(len(p) - len(z), 0))))
    n_sections = (max(len(p), len(z)) + 1) // 2
    if len(p) % 2 == 1:
        p = np.concatenate((p, [0.]))
        z = np.concatenate((z, [0.]))
    z = np.concatenate(_cplxreal(z))
    p = np.concatenate(_cplxreal(p))
    k = k.real

    def idx_worst(q):
        return np.argmin(np.abs(1 - np.abs(q)))

    sos = np.zeros((n_sections, 6))
    for si in range(n_sections - 1, -1, -1):
        p1_idx = idx_worst(p)
        p1 = p[p1_idx]
        p = np.delete(p, p1_idx)
        if np.isreal(p1) and np.isreal(p).sum() == 0:
            z1_idx = _nearest(z, p1, "real")
            z1 = z[z1_idx]
            z = np.delete(z, z1_idx)
            sos[si] = _section([z1, 0], [p1, 0])
        elif (len(p) + 1 == len(z) and not np.isreal(p1) and np.isreal(p).sum() == 1
              and np.isreal(z).sum() == 1):
            z1_idx = _nearest(z, p1, "complex")
            z1 = z[z1_idx]
            z = np.delete(z, z1_idx)
            sos[si] = _section([z1, z1.conj()], [p1, p1.conj()])
        else:
            if np.isreal(p1):
                prealidx = np.flatnonzero(np.isreal(p))
                p2_idx = prealidx[idx_worst(p[prealidx])]
                p2 = p[p2_idx]
                p = np.delete(p, p2_idx)
            else:
                p2 = p1.conj()
            if len(z) > 0:
                z1_idx = _nearest(z, p1, "any")
                z1 = z[z1_idx]
                z = np.delete(z, z1_idx)
                if not np.isreal(z1):
                    sos[si] = _section([z1, z1.conj()], [p1, p2])
                elif len(z) > 0:
                    z2_idx = _nearest(z, p1, "real")
                    z2 = z[z2_idx]
                    z = np.delete(z, z2_idx)
                    sos[si] = _section([z1, z2], [p1, p2])
                else:
                    sos[si] = _section([z1], [p1, p2])
            else:
                sos[si] = _section([], [p1, p2])
    sos[0][:3] *= k
    return sos


def butter_bandpass_sos(order: int, low: float, high: float, fs: float) -> np.ndarray:
    """``scipy.signal.butter(order, [low, high], btype="bandpass", fs=fs, output="sos")``: the digital
    Butterworth band-pass of ``order`` (``2 order`` poles) between ``low`` and ``high`` (Hz, ``0 < low < high <
    fs / 2``) as ``(order, 6)`` second-order sections ``[b0, b1, b2, 1, a1, a2]`` (module docstring)."""
    if int(order) != order or order < 1:
        raise ValueError("filter order must be a positive integer")
    fs = float(fs)
    Wn = np.asarray([low, high], dtype=np.float64) / (fs / 2)
    if np.any(Wn <= 0) or np.any(Wn >= 1) or not Wn[0] < Wn[1]:
        raise ValueError(f"band edges must satisfy 0 < low < high < fs/2 (fs={fs})")
    m = np.arange(-order + 1, order, 2, dtype=np.float64)
    p = -np.exp(1j * np.pi * m / (2 * order))                  # analogue prototype, no zeros, gain 1
    fs_d = 2.0
    warped = 2 * fs_d * np.tan(np.pi * Wn / fs_d)
    bw = float(warped[1] - warped[0])
    wo = float(np.sqrt(warped[0] * warped[1]))
    # low-pass -> band-pass
    z = np.asarray([], dtype=np.complex128)
    degree = p.shape[0]
    p_lp = (p * bw / 2).astype(np.complex128)
    p_bp = np.concatenate((p_lp + np.sqrt(p_lp ** 2 - wo ** 2), p_lp - np.sqrt(p_lp ** 2 - wo ** 2)))
    z_bp = np.concatenate((z, np.zeros(degree)))
    k_bp = 1.0 * bw ** degree
    # bilinear transform
    fs2 = 2.0 * fs_d
    deg = p_bp.shape[0] - z_bp.shape[0]
    z_z = np.concatenate(((fs2 + z_bp) / (fs2 - z_bp), -np.ones(deg)))
    p_z = (fs2 + p_bp) / (fs2 - p_bp)
    k_z = k_bp * np.real(np.prod(fs2 - z_bp) / np.prod(fs2 - p_bp))
    return _zpk2sos(z_z, p_z, k_z)


def sosfilt_zi(sos: np.ndarray) -> np.ndarray:
    """``scipy.signal.sosfilt_zi``: the section states (n_sections, 2) of the steady state of a unit step."""
    zi = np.empty((sos.shape[0], 2))
    scale = 1.0
    for s in range(sos.shape[0]):
        b, a = sos[s, :3], sos[s, 3:]
        if a[0] != 1.0:
            b, a = b / a[0], a / a[0]
        companion = np.zeros((2, 2))
        companion[0] = -a[1:] / (1.0 * a[0])
        companion[1, 0] = 1
        zi[s] = scale * np.linalg.solve(np.eye(2) - companion.T, b[1:] - a[1:] * b[0])
        scale *= np.sum(b) / np.sum(a)
    return zi


@njit(cache=True)
def _sosfilt(sos, x, zi):
    """Cascade of second-order sections over ``x`` in place (direct form II transposed), states ``zi`` updated
    in place: per sample and section ``y = b0 x + z0``, ``z0 = b1 x - a1 y + z1``, ``z1 = b2 x - a2 y``."""
    n_sections = sos.shape[0]
    for n in range(x.shape[0]):
        x_cur = x[n]
        for s in range(n_sections):
            x_new = sos[s, 0] * x_cur + zi[s, 0]
            zi[s, 0] = sos[s, 1] * x_cur - sos[s, 4] * x_new + zi[s, 1]
            zi[s, 1] = sos[s, 2] * x_cur - sos[s, 5] * x_new
            x_cur = x_new
        x[n] = x_cur


def sosfiltfilt(sos: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``scipy.signal.sosfiltfilt(sos, x)`` of a 1-D signal (odd extension, default pad length): the same
    doubles (module docstring). Returns a new array."""
    sos = np.ascontiguousarray(sos, dtype=np.float64)
    x = np.asarray(x, dtype=np.float64)
    if x.ndim != 1:
        raise ValueError("sosfiltfilt: x must be 1-D")
    ns = sos.shape[0]
    edge = 3 * (2 * ns + 1 - min(int((sos[:, 2] == 0).sum()), int((sos[:, 5] == 0).sum())))
    if x.shape[0] <= edge:
        raise ValueError(f"the length of the input vector x must be greater than padlen, which is {edge}")
    n = x.shape[0]
    ext = np.empty(n + 2 * edge)                      # odd extension: 2 x[0] - x[edge:0:-1], x, 2 x[-1] - ...
    ext[:edge] = 2 * x[0:1] - x[edge:0:-1]
    ext[edge:edge + n] = x
    ext[edge + n:] = 2 * x[-1:] - x[-2:-(edge + 2):-1]
    zi = sosfilt_zi(sos)
    _sosfilt(sos, ext, zi * ext[0:1])
    rev = ext[::-1].copy()
    del ext
    _sosfilt(sos, rev, zi * rev[0:1])
    return rev[::-1][edge:edge + n].copy()


__all__ = ["butter_bandpass_sos", "sosfilt_zi", "sosfiltfilt"]
