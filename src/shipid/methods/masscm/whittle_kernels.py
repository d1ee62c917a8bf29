"""Compiled per-band kernels of the Whittle refinement (:mod:`shipid.methods.masscm.whittle`; Linder et al. 2015,
beyond the paper).

The band matrices of :meth:`shipid.methods.masscm.whittle._FSet.matrices` evaluated band by band in one compiled
loop instead of stacks of small numpy matrix products (the same formulas, see that module's docstring; the results
agree with the numpy form to round-off):

* :func:`ship_columns`: ``C (zI - Ad)^-1`` and the rudder / ship-transient columns ``3, 4, 8, 9`` of ``At``;
* :func:`noise_spectrum`: ``S = T T^H + R`` with ``T(z) = H (zI - F)^-1 G + J`` (``F = [[Ad, F12], [0, Aw]]``, by
  blocks) and ``Gam(z) = z H (zI - F)^-1`` (without waves ``S = R``, ``Gam = z C (zI - Ad)^-1``);
* :func:`transient_normal`: the normal equations ``Hm t = b`` of the profiled noise transient.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _inv4(a, out):
    """Inverse of a complex 4 x 4 matrix ``a`` by Gauss-Jordan elimination with partial pivoting (into ``out``;
    ``a`` is overwritten)."""
    for i in range(4):
        for j in range(4):
            out[i, j] = 1.0 if i == j else 0.0
    for col in range(4):
        piv, best = col, abs(a[col, col])
        for r in range(col + 1, 4):
            v = abs(a[r, col])
            if v > best:
                piv, best = r, v
        if piv != col:
            for j in range(4):
                t = a[col, j]
                a[col, j] = a[piv, j]
                a[piv, j] = t
                t = out[col, j]
                out[col, j] = out[piv, j]
                out[piv, j] = t
        inv_p = 1.0 / a[col, col]
        for j in range(4):
            a[col, j] *= inv_p
            out[col, j] *= inv_p
        for r in range(4):
            if r != col:
                f = a[r, col]
                if f != 0:
                    for j in range(4):
                        a[r, j] -= f * a[col, j]
                        out[r, j] -= f * out[col, j]


@njit(cache=True)
def ship_columns(z, Ad, b0, b1, C, d0, c):
    """``(At0 (nz, 3, 10), CR (nz, 3, 4))``: ``At`` without the noise transient (columns 5-7 zero) and
    ``CR = C (zI - Ad)^-1`` at each ``z``."""
    nz = z.shape[0]
    A = np.zeros((nz, 3, 10), dtype=np.complex128)
    CRo = np.empty((nz, 3, 4), dtype=np.complex128)
    M = np.empty((4, 4), dtype=np.complex128)
    Ra = np.empty((4, 4), dtype=np.complex128)
    CR = np.empty((3, 4), dtype=np.complex128)
    CR2 = np.empty((3, 4), dtype=np.complex128)
    for k in range(nz):
        zk = z[k]
        for i in range(4):
            for j in range(4):
                M[i, j] = (zk if i == j else 0.0) - Ad[i, j]
        _inv4(M, Ra)
        for i in range(3):
            for j in range(4):
                acc = 0j
                for l in range(4):
                    acc += C[i, l] * Ra[l, j]
                CR[i, j] = acc
                CRo[k, i, j] = acc
        for i in range(3):
            for j in range(4):
                acc = 0j
                for l in range(4):
                    acc += CR[i, l] * Ra[l, j]
                CR2[i, j] = acc
        for i in range(3):
            r0 = r1 = rc = q0 = q1 = qc = 0j
            for j in range(4):
                r0 += CR[i, j] * b0[j]
                r1 += CR[i, j] * b1[j]
                rc += CR[i, j] * c[j]
                q0 += CR2[i, j] * b0[j]
                q1 += CR2[i, j] * b1[j]
                qc += CR2[i, j] * c[j]
            A[k, i, i] = 1.0
            A[k, i, 3] = -(r0 + zk * r1 + d0[i])
            A[k, i, 4] = -zk * rc
            A[k, i, 8] = -1j * zk * (r1 - q0 - zk * q1)
            A[k, i, 9] = -1j * zk * (rc - zk * qc)
    return A, CRo


@njit(cache=True)
def noise_spectrum(z, CR, F12, H4, Aw, G, J, R, waves):
    """``(S (nz, 3, 3), Gam (nz, 3, ns))`` of the module docstring (``ns`` 6 with waves, else 4)."""
    nz = z.shape[0]
    ns = 6 if waves else 4
    S = np.empty((nz, 3, 3), dtype=np.complex128)
    Gam = np.empty((nz, 3, ns), dtype=np.complex128)
    HR = np.empty((3, 6), dtype=np.complex128)
    Tz = np.empty(3, dtype=np.complex128)
    Rw = np.empty((2, 2), dtype=np.complex128)
    for k in range(nz):
        zk = z[k]
        if waves:
            a, b_, c_, d_ = zk - Aw[0, 0], -Aw[0, 1], -Aw[1, 0], zk - Aw[1, 1]
            det = a * d_ - b_ * c_
            Rw[0, 0], Rw[0, 1], Rw[1, 0], Rw[1, 1] = d_ / det, -b_ / det, -c_ / det, a / det
            for i in range(3):
                for j in range(4):
                    HR[i, j] = CR[k, i, j]
                x0 = H4[i, 0] + 0j
                x1 = H4[i, 1] + 0j
                for l in range(4):
                    x0 += CR[k, i, l] * F12[l, 0]
                    x1 += CR[k, i, l] * F12[l, 1]
                HR[i, 4] = x0 * Rw[0, 0] + x1 * Rw[1, 0]
                HR[i, 5] = x0 * Rw[0, 1] + x1 * Rw[1, 1]
                acc = J[i] + 0j
                for j in range(6):
                    acc += HR[i, j] * G[j]
                Tz[i] = acc
                for j in range(6):
                    Gam[k, i, j] = zk * HR[i, j]
            for i in range(3):
                for j in range(3):
                    S[k, i, j] = Tz[i] * np.conj(Tz[j]) + R[i, j]
        else:
            for i in range(3):
                for j in range(4):
                    Gam[k, i, j] = zk * CR[k, i, j]
                for j in range(3):
                    S[k, i, j] = R[i, j]
    return S, Gam


@njit(cache=True)
def transient_normal(A, S, Gam, M):
    """``(Hm, b)``: ``b = Re sum_b (W Gam)^H A_b m_b`` (``m_b = Mt_b[:, 4]``, i.e. ``A_b sum_j Zt_j / sqrt(N)``),
    ``Hm = Re sum_b Mt_b[4, 4] Gam^H W Gam`` (``W = S^-1`` by the adjugate), as
    :meth:`~shipid.methods.masscm.whittle._FSet._noise_transient`."""
    nz, _, ns = Gam.shape
    b = np.zeros(ns)
    Hm = np.zeros((ns, ns))
    W = np.empty((3, 3), dtype=np.complex128)
    WG = np.empty((3, ns), dtype=np.complex128)
    e1 = np.empty(3, dtype=np.complex128)
    for k in range(nz):
        s = S[k]
        c00 = s[1, 1] * s[2, 2] - s[1, 2] * s[2, 1]
        c01 = s[1, 2] * s[2, 0] - s[1, 0] * s[2, 2]
        c02 = s[1, 0] * s[2, 1] - s[1, 1] * s[2, 0]
        det = s[0, 0] * c00 + s[0, 1] * c01 + s[0, 2] * c02
        W[0, 0], W[1, 0], W[2, 0] = c00 / det, c01 / det, c02 / det
        W[0, 1] = (s[0, 2] * s[2, 1] - s[0, 1] * s[2, 2]) / det
        W[1, 1] = (s[0, 0] * s[2, 2] - s[0, 2] * s[2, 0]) / det
        W[2, 1] = (s[0, 1] * s[2, 0] - s[0, 0] * s[2, 1]) / det
        W[0, 2] = (s[0, 1] * s[1, 2] - s[0, 2] * s[1, 1]) / det
        W[1, 2] = (s[0, 2] * s[1, 0] - s[0, 0] * s[1, 2]) / det
        W[2, 2] = (s[0, 0] * s[1, 1] - s[0, 1] * s[1, 0]) / det
        for i in range(3):
            for l in range(ns):
                acc = 0j
                for j in range(3):
                    acc += W[i, j] * Gam[k, j, l]
                WG[i, l] = acc
            acc = 0j
            for j in range(10):
                acc += A[k, i, j] * M[k, j, 4]
            e1[i] = acc
        m44 = M[k, 4, 4].real
        for l in range(ns):
            acc = 0j
            for i in range(3):
                acc += np.conj(WG[i, l]) * e1[i]
            b[l] += acc.real
            for q in range(ns):
                acc = 0j
                for i in range(3):
                    acc += np.conj(Gam[k, i, l]) * WG[i, q]
                Hm[l, q] += m44 * acc.real
    return Hm, b


__all__ = ["ship_columns", "noise_spectrum", "transient_normal"]
