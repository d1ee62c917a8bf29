"""Compiled (numba) rational filter from rest with the arithmetic of ``scipy.signal.lfilter``.

``y = B(q)/A(q) x`` by the direct form II transposed of ``lfilter`` (scipy's documented difference
equations, ``a`` and ``b`` padded with zeros to a common length ``N + 1`` and divided by ``a[0]``)::

    y[t]     = d[0][t-1] + b[0] x[t]
    d[j][t]  = (d[j+1][t-1] + x[t] b[j+1]) - y[t] a[j+1],     j = 0 .. N-2
    d[N-1][t] = x[t] b[N] - y[t] a[N]

Where ``a[j] = 0`` for every ``j > p`` (the prefilters of Algorithm 1: an AR numerator of 41 taps over a
denominator ``(1 - c q^-2)^k`` of at most 5), the states ``d[p] .. d[N-1]`` do not depend on ``y``: ``d[p][t]``
is the FIR sum ``sum_{j=p+1}^{N} b[j] x[t - (j - p - 1)]``, accumulated from ``j = N`` down as the recursion
accumulates it. :func:`_fir_tail` computes it for a block of samples at once (vectorised across samples, the
order of the additions of each sample unchanged), and only the ``p`` recursive states are updated sample by
sample (:func:`_filter_row`). Every product and sum of ``lfilter`` is formed in the same order, except the
terms ``y a[j]`` with ``a[j] = 0`` (and ``x b[j]`` with ``b[j] = 0`` before the tail starts), which add an exact
zero: the result equals ``lfilter`` bit for bit, except possibly the sign of a result that is exactly zero
(tests compare them with ``numpy.array_equal``). No fast-math flags: no reassociation, no fused multiply-add.

A denominator of length one is the FIR filter of ``lfilter``'s own ``numpy.convolve`` branch, computed the same
way here (:func:`lfilter`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: Samples per block of :func:`_fir_tail` (its buffer stays in the first-level cache).
BLOCK = 512


@njit(cache=True)
def _fir_tail(b, x, t0, m, N, p, S):
    """``S[i] = sum_{j=p+1}^{N} b[j] x[t0 + i - (j - p - 1)]``, ``i < m``, added from ``j = N`` down.

    Samples before the record are zero (the filter starts from rest). Four taps per pass over the block, on
    slices, so that the loop over samples is vectorised (no index wrap-around checks).
    """
    off = N - p - 1
    if t0 - off >= 0:
        x0 = x[t0 - off:t0 - off + m]
        bN = b[N]
        for i in range(m):
            S[i] = bN * x0[i]
        j = N - 1
        while j - 3 > p:
            b0, b1, b2, b3 = b[j], b[j - 1], b[j - 2], b[j - 3]
            s0 = t0 - (j - p - 1)
            x0 = x[s0:s0 + m]
            x1 = x[s0 + 1:s0 + 1 + m]
            x2 = x[s0 + 2:s0 + 2 + m]
            x3 = x[s0 + 3:s0 + 3 + m]
            for i in range(m):
                S[i] = (((S[i] + b0 * x0[i]) + b1 * x1[i]) + b2 * x2[i]) + b3 * x3[i]
            j -= 4
        while j > p:
            bj = b[j]
            s0 = t0 - (j - p - 1)
            x0 = x[s0:s0 + m]
            for i in range(m):
                S[i] = S[i] + bj * x0[i]
            j -= 1
    else:                                            # the first block: some taps reach before the record
        for i in range(m):
            u = t0 + i - off
            S[i] = b[N] * x[u] if u >= 0 else 0.0
        for j in range(N - 1, p, -1):
            o = j - p - 1
            bj = b[j]
            for i in range(m):
                u = t0 + i - o
                if u >= 0:
                    S[i] = S[i] + bj * x[u]


@njit(cache=True)
def _filter_row(b, a, p, x, y):
    """``y = B/A x`` from rest (module docstring): ``b``, ``a`` of equal length ``N + 1``, ``a[0] = 1``,
    ``a[j] = 0`` for ``j > p``; ``x`` and ``y`` contiguous of the same length."""
    n = x.size
    N = b.size - 1
    z = np.zeros(max(p, 1))
    S = np.zeros(BLOCK)
    sprev = 0.0                                      # d[p][t-1], the FIR tail at the previous sample
    b0 = b[0]
    for t0 in range(0, n, BLOCK):
        m = min(t0 + BLOCK, n) - t0
        if N > p:
            _fir_tail(b, x, t0, m, N, p, S)
        if p == 2:                                   # 1/(1 - c q^-2): the states in registers
            z0, z1 = z[0], z[1]
            b1, b2, a1, a2 = b[1], b[2], a[1], a[2]
            for i in range(m):
                xt = x[t0 + i]
                yt = z0 + b0 * xt
                z0 = (z1 + xt * b1) - yt * a1
                z1 = (sprev + xt * b2) - yt * a2
                y[t0 + i] = yt
                sprev = S[i]
            z[0], z[1] = z0, z1
        elif p == 4:                                 # 1/(1 - c q^-2)^2
            z0, z1, z2, z3 = z[0], z[1], z[2], z[3]
            b1, b2, b3, b4, a1, a2, a3, a4 = b[1], b[2], b[3], b[4], a[1], a[2], a[3], a[4]
            for i in range(m):
                xt = x[t0 + i]
                yt = z0 + b0 * xt
                z0 = (z1 + xt * b1) - yt * a1
                z1 = (z2 + xt * b2) - yt * a2
                z2 = (z3 + xt * b3) - yt * a3
                z3 = (sprev + xt * b4) - yt * a4
                y[t0 + i] = yt
                sprev = S[i]
            z[0], z[1], z[2], z[3] = z0, z1, z2, z3
        else:
            for i in range(m):
                xt = x[t0 + i]
                if p == 0:
                    yt = sprev + b0 * xt
                else:
                    yt = z[0] + b0 * xt
                    for j in range(p - 1):
                        z[j] = (z[j + 1] + xt * b[j + 1]) - yt * a[j + 1]
                    z[p - 1] = (sprev + xt * b[p]) - yt * a[p]
                y[t0 + i] = yt
                sprev = S[i]


def _coefficients(b, a) -> tuple[np.ndarray, np.ndarray, int]:
    """``b``, ``a`` padded to a common length and divided by ``a[0]`` (as ``lfilter``), and ``p``, the last
    index with ``a[p] != 0``."""
    b = np.asarray(b, dtype=float).ravel()
    a = np.asarray(a, dtype=float).ravel()
    if b.size == 0 or a.size == 0 or a[0] == 0.0:
        raise ValueError("filter coefficients: b and a must be non-empty with a[0] != 0")
    N = max(b.size, a.size)
    bb = np.zeros(N)
    aa = np.zeros(N)
    bb[:b.size] = b
    aa[:a.size] = a
    a0 = aa[0]
    bb, aa = bb / a0, aa / a0
    nz = np.flatnonzero(aa[1:])
    return bb, aa, int(nz[-1]) + 1 if nz.size else 0


def lfilter_into(b, a, x: np.ndarray, out: np.ndarray) -> np.ndarray:
    """``out[:] = lfilter(b, a, x)`` for one signal (1-D, from rest); ``out`` may be a row of a larger array.

    Returns ``out``. A denominator of length one is ``numpy.convolve(b / a[0], x)[:n]`` (``lfilter``'s own
    branch for it); otherwise the compiled recursion (module docstring).
    """
    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or out.shape != x.shape:
        raise ValueError("lfilter_into: x must be 1-D and out of its shape")
    if x.size == 0:
        return out
    a = np.atleast_1d(np.asarray(a, dtype=float))
    if a.size == 1:
        out[:] = np.convolve(np.atleast_1d(np.asarray(b, dtype=float)) / a[0], x)[:x.size]
        return out
    bb, aa, p = _coefficients(b, a)
    xc = np.ascontiguousarray(x)
    if out.flags.c_contiguous:
        _filter_row(bb, aa, p, xc, out)
    else:
        y = np.empty(x.size)
        _filter_row(bb, aa, p, xc, y)
        out[:] = y
    return out


def lfilter(b, a, x: np.ndarray) -> np.ndarray:
    """``scipy.signal.lfilter(b, a, x)`` of a 1-D signal from rest (no initial state), the same numbers
    (module docstring)."""
    x = np.asarray(x, dtype=float)
    return lfilter_into(b, a, x, np.empty(x.shape))


__all__ = ["BLOCK", "lfilter", "lfilter_into"]
