"""Compiled (numba) inner search of Algorithm 1 (Linder et al. 2015, eqs. 40–41): the map (33), its Jacobian,
the weighted IV residuals, Gauss–Newton and a bounded Levenberg–Marquardt search.

Step B(a) of Algorithm 1 minimises ``sum_i ||R_i g_i(theta) - r_i||^2 / lam_i`` (the compressed criterion of
:func:`shipid.estimate.iv.iv_compress`) over the physical parameters. The problem is tiny (5 residuals per
dataset, at most 9 unknowns), so in Python the time goes into interpreter and scipy overhead, not arithmetic;
these kernels do the same arithmetic compiled.

* :func:`g_and_jac` — the map (22), (33) and its exact Jacobian: the compiled form of
  :func:`shipid.models.roll_reduced.discrete_coeffs` (the reference; tests compare them, and the Jacobian with
  complex-step derivatives of it). Both paths of the estimator evaluate the map of real arguments by this kernel.
* :func:`gauss_newton` — the warm-start Gauss–Newton of :func:`shipid.methods.masscm.criterion.gauss_newton`
  (same acceptance and convergence rules; tests compare them).
* :func:`levenberg_marquardt` — the cold-start search of the first iteration: Levenberg–Marquardt with
  Marquardt's scaling (``diag(J^T J)``, like ``x_scale="jac"``), iterates kept strictly inside the bounds,
  the same tolerances as the ``trf`` search it replaces (``xtol = ftol = gtol = 1e-10``). The caller polishes
  its result with :func:`gauss_newton` and falls back to scipy's ``trf`` from the original start whenever
  either does not converge cleanly, so a run can only differ from the ``trf`` path by where, within the
  tolerances, the first search stopped (the study test compares them run by run).

Compiled with ``cache=True`` (the machine code is stored next to this file and reused by every process);
without a cache, compiling all the mass-cm kernels costs about 27 s once per machine (no
``np.linalg`` inside: its numba implementations compile slowly), which
:func:`shipid.methods.masscm.study.warm_up` pays before a campaign starts its workers.
"""

from __future__ import annotations

import types

import numpy as np
from numba import njit

from shipid.numerics import numba_linalg
from shipid.numerics.numba_linalg import cho_solve_inplace, cholesky_into, source_key

#: First 16 hex digits of the SHA-256 of ``shipid/numerics/numba_linalg.py``: :func:`spd_solve` (and
#: :func:`levenberg_marquardt`, which calls it) compile its kernels in, and numba keys their disk cache on this
#: file only. An edit there must update the key (``tests/methods/masscm/test_masscm_compiled.py`` checks it).
NUMBA_LINALG_KEY = "355c3586dc6b4413"

#: True when the on-disk cache of those two may be used (else they compile without it, never run stale).
CACHE_VALID = source_key(numba_linalg) == NUMBA_LINALG_KEY

#: Layout of the ``kc`` array of known constants used by the kernels.
KC_FIELDS = ("M", "g", "zg_bar", "zs_bar", "m_c", "zc_bar", "U")


def known_array(known) -> np.ndarray:
    """The known parameters (§4.3) the kernels need, as a float array in :data:`KC_FIELDS` order."""
    return np.array([getattr(known, f) for f in KC_FIELDS], dtype=np.float64)


@njit(cache=True)
def _load_moment(c, m_c, zc_bar, z_f, q, zm):
    """Load moment about the roll axis and the load's height bar of one dataset, by condition code:
    nominal (0) none, calibration (1) the known ``m_c`` at ``zc_bar``, loaded (2) the unknown ``q = m zm``
    at ``zm`` (moment parameterisation of (27)/(30))."""
    if c == 0:
        return 0.0, 0.0
    if c == 1:
        return m_c * (zc_bar + z_f), zc_bar
    return q, zm


@njit(cache=True)
def g_and_jac(th, code, Ts, kc, jac):
    """``g_i(theta)`` (33) in the moment parameterisation for condition codes (0 nominal, 1 calibration,
    2 loaded), shape (n, 5), and when ``jac`` its Jacobian (n, 5, 9): (22), (33) as in
    :func:`shipid.models.roll_reduced.discrete_coeffs`."""
    k, A_x, d, K_r, K_v, K_d, z_f, q, zm = th[0], th[1], th[2], th[3], th[4], th[5], th[6], th[7], th[8]
    M, g, zgb, zsb, m_c, zc_bar = kc[0], kc[1], kc[2], kc[3], kc[4], kc[5]
    zg, zs = zgb + z_f, zsb + z_f
    kp = k - K_v * g
    n = code.size
    G = np.empty((n, 5))
    J = np.zeros((n, 5, 9)) if jac else np.zeros((0, 5, 9))
    dA2 = np.zeros(9)
    dB = np.zeros(9)
    row = np.empty(5)
    for i in range(n):
        c, T = code[i], Ts[i]
        qi, zb = _load_moment(c, m_c, zc_bar, z_f, q, zm)
        A2 = A_x + M * zg * (zgb - zsb) + qi * (zb - zsb) - K_v * zs
        B = K_v + M * zg + qi
        den = 2 * d * T + kp * T * T + 4 * A2
        row[0] = (2 * kp * T * T - 8 * A2) / den
        row[1] = (-2 * d * T + kp * T * T + 4 * A2) / den
        row[2] = -2 * T * B / den
        row[3] = 2 * T * K_r / den
        row[4] = 2 * T * K_d / den
        for r in range(5):
            G[i, r] = row[r]
        if jac:
            dA2[:] = 0.0
            dB[:] = 0.0
            dA2[1] = 1.0
            dA2[4] = -zs
            dA2[6] = M * (zgb - zsb) + (m_c * (zb - zsb) if c == 1 else 0.0) - K_v
            dA2[7] = (zb - zsb) if c == 2 else 0.0
            dA2[8] = qi if c == 2 else 0.0
            dB[4] = 1.0
            dB[6] = M + (m_c if c == 1 else 0.0)
            dB[7] = 1.0 if c == 2 else 0.0
            TT = T * T
            for p in range(9):
                dkp = 1.0 if p == 0 else (-g if p == 4 else 0.0)
                ddp = 1.0 if p == 2 else 0.0
                dden = 2 * T * ddp + TT * dkp + 4 * dA2[p]
                J[i, 0, p] = ((2 * TT * dkp - 8 * dA2[p]) - row[0] * dden) / den
                J[i, 1, p] = ((-2 * T * ddp + TT * dkp + 4 * dA2[p]) - row[1] * dden) / den
                J[i, 2, p] = ((-2 * T * dB[p]) - row[2] * dden) / den
                J[i, 3, p] = ((2 * T * (1.0 if p == 3 else 0.0)) - row[3] * dden) / den
                J[i, 4, p] = ((2 * T * (1.0 if p == 5 else 0.0)) - row[4] * dden) / den
    return G, J


@njit(cache=True)
def sim_terms(th, code, Ts, kc):
    """Per dataset ``[A1, d, k1, Kyaw, K_delta, z_s, g, U, T]``: the terms of
    :func:`shipid.models.roll_reduced.roll_terms` (moment parameterisation) that the closed-loop
    instrument simulation (46)–(47) needs (:func:`shipid.methods.masscm.step.dataset_step`)."""
    k, A_x, d, K_r, K_v, K_d, z_f, q, zm = th[0], th[1], th[2], th[3], th[4], th[5], th[6], th[7], th[8]
    M, g, zgb, zsb, m_c, zc_bar, U = kc[0], kc[1], kc[2], kc[3], kc[4], kc[5], kc[6]
    zg, zs = zgb + z_f, zsb + z_f
    n = code.size
    out = np.empty((n, 9))
    for i in range(n):
        qi, zb = _load_moment(code[i], m_c, zc_bar, z_f, q, zm)
        B = K_v + M * zg + qi
        out[i, 0] = A_x + M * zg ** 2 + qi * (zb + z_f)
        out[i, 1] = d
        out[i, 2] = k + M * g * zg + qi * g
        out[i, 3] = K_r + U * B
        out[i, 4] = K_d
        out[i, 5] = zs
        out[i, 6] = g
        out[i, 7] = U
        out[i, 8] = Ts[i]
    return out


@njit(cache=True)
def residual(x, free_idx, th_fixed, Rs, rs, code, Ts, kc, prior, jac):
    """Weighted IV residuals ``R_i g_i - r_i`` (stacked) and, when ``jac``, their Jacobian w.r.t. ``x``.

    ``x`` are the free entries (``free_idx``) of theta; ``Rs``, ``rs`` are already weighted by
    ``lam_i^-1/2``; ``prior = [flag, mean, std, column]`` adds the row ``(z_f - mean)/std``.
    """
    th = th_fixed.copy()
    nf = free_idx.size
    for j in range(nf):
        th[free_idx[j]] = x[j]
    G, Jg = g_and_jac(th, code, Ts, kc, jac)
    n = code.size
    has_prior = prior[0] != 0.0
    m = 5 * n + (1 if has_prior else 0)
    res = np.empty(m)
    J = np.zeros((m, nf)) if jac else np.zeros((0, nf))
    for i in range(n):
        for a in range(5):
            s = 0.0
            for b in range(5):
                s += Rs[i, a, b] * G[i, b]
            res[5 * i + a] = s - rs[i, a]
            if jac:
                for j in range(nf):
                    p = free_idx[j]
                    s2 = 0.0
                    for b in range(5):
                        s2 += Rs[i, a, b] * Jg[i, b, p]
                    J[5 * i + a, j] = s2
    if has_prior:
        res[m - 1] = (th[6] - prior[1]) / prior[2]
        if jac:
            J[m - 1, int(prior[3])] = 1.0 / prior[2]
    return res, J


@njit(cache=True)
def _inside(x, lo, hi):
    for j in range(x.size):
        if not (np.isfinite(x[j]) and x[j] > lo[j] and x[j] < hi[j]):
            return False
    return True


@njit(cache=True)
def _off_bounds(x, lo, hi):
    """True when no entry is within 1e-3 (relative to the bound) of a finite bound: an interior point."""
    for j in range(x.size):
        if np.isfinite(lo[j]) and x[j] - lo[j] <= 1e-3 * max(1.0, abs(lo[j])):
            return False
        if np.isfinite(hi[j]) and hi[j] - x[j] <= 1e-3 * max(1.0, abs(hi[j])):
            return False
    return True


@njit(cache=True)
def _norm(x):
    return np.sqrt(np.sum(x * x))


@njit(cache=CACHE_VALID)
def spd_solve(H, b):
    """``H x = b`` for symmetric positive definite ``H`` by Cholesky; ``(ok, x)``.

    :func:`shipid.numerics.numba_linalg.cholesky_into` and ``cho_solve_inplace``; ``ok`` False (and x zero)
    when ``H`` is not positive definite.
    """
    n = b.size
    L = np.zeros((n, n))
    if not cholesky_into(H, n, L):
        return False, np.zeros(n)
    x = b.copy().reshape((n, 1))
    cho_solve_inplace(L, n, x)
    return True, x.reshape(n)


@njit(cache=True)
def lstsq_qr(J, b):
    """Least-squares solution of ``J x = b`` (full column rank, m >= n) by Householder QR.

    What ``np.linalg.lstsq`` returns for a full-rank ``J`` (the Gauss-Newton steps here: 15 x 8), without
    its SVD and workspace queries. Returns ``(ok, x)``; ``ok`` False when a column is (numerically) zero
    or the triangular factor has a (relatively) vanishing pivot.
    """
    m, n = J.shape
    A = J.copy()
    y = b.copy()
    for c in range(n):
        norm = 0.0
        for i in range(c, m):
            norm += A[i, c] * A[i, c]
        norm = np.sqrt(norm)
        if norm == 0.0:
            return False, np.zeros(n)
        alpha = -norm if A[c, c] >= 0 else norm
        v0 = A[c, c] - alpha
        vtv = v0 * v0
        for i in range(c + 1, m):
            vtv += A[i, c] * A[i, c]
        for cc in range(c + 1, n):
            dot = v0 * A[c, cc]
            for i in range(c + 1, m):
                dot += A[i, c] * A[i, cc]
            f = 2.0 * dot / vtv
            A[c, cc] -= f * v0
            for i in range(c + 1, m):
                A[i, cc] -= f * A[i, c]
        dot = v0 * y[c]
        for i in range(c + 1, m):
            dot += A[i, c] * y[i]
        f = 2.0 * dot / vtv
        y[c] -= f * v0
        for i in range(c + 1, m):
            y[i] -= f * A[i, c]
        A[c, c] = alpha
    x = np.empty(n)
    for i in range(n - 1, -1, -1):
        v = y[i]
        for k in range(i + 1, n):
            v -= A[i, k] * x[k]
        if A[i, i] == 0.0 or not np.isfinite(A[i, i]):
            return False, np.zeros(n)
        x[i] = v / A[i, i]
    # rank check as lstsq's default cut-off: |R_ii| must not vanish against the largest
    rmax = 0.0
    for i in range(n):
        rmax = max(rmax, abs(A[i, i]))
    for i in range(n):
        if abs(A[i, i]) <= max(m, n) * 2.220446049250313e-16 * rmax:
            return False, np.zeros(n)
    return True, x


@njit(cache=True)
def gauss_newton(x0, lo, hi, free_idx, th_fixed, Rs, rs, code, Ts, kc, prior, max_steps, xtol, floor):
    """Undamped Gauss–Newton of :func:`shipid.methods.masscm.criterion.gauss_newton` (``max_steps = 20``,
    ``xtol = 1e-10``, ``floor = 1e-9`` there), the step by :func:`lstsq_qr` (a rank-deficient Jacobian
    returns not ok, where the reference would take a minimum-norm step); returns ``(ok, x)``. No default
    arguments: numba's dispatcher takes its slow path (~0.3 ms) for omitted ones."""
    x = x0.copy()
    r, _ = residual(x, free_idx, th_fixed, Rs, rs, code, Ts, kc, prior, False)
    cost = r @ r
    for _k in range(max_steps):
        _, J = residual(x, free_idx, th_fixed, Rs, rs, code, Ts, kc, prior, True)
        ok, dx = lstsq_qr(J, -r)
        if not ok:                       # rank-deficient Jacobian: not converged here (caller: trf)
            return False, x
        xn = x + dx
        if not _inside(xn, lo, hi):
            return False, x
        rn, _ = residual(xn, free_idx, th_fixed, Rs, rs, code, Ts, kc, prior, False)
        cn = rn @ rn
        small = _norm(dx) <= xtol * (xtol + _norm(x))
        if not np.isfinite(cn) or cn > cost * (1 + 1e-12) + 1e-300:
            return _norm(dx) <= floor * _norm(x), x
        x, r, cost = xn, rn, cn
        if small:
            return True, x
    return False, x


@njit(cache=CACHE_VALID)
def levenberg_marquardt(x0, lo, hi, free_idx, th_fixed, Rs, rs, code, Ts, kc, prior, max_iter, xtol, ftol, gtol, mu0):
    """Bounded Levenberg–Marquardt (Marquardt scaling, Nielsen's damping update), iterates strictly
    inside ``(lo, hi)`` (a component that would cross a bound stops 0.995 of the way to it). Returns
    ``(status, x, nfev)``: status 1 converged at an interior point (step, cost or gradient tolerance),
    2 converged next to a bound, 0 not converged (iteration limit, non-finite values); the caller
    accepts only 1. ``mu0``: the initial damping (the caller tries 1e-3, then the more cautious 1e2)."""
    nf = x0.size
    x = x0.copy()
    r, J = residual(x, free_idx, th_fixed, Rs, rs, code, Ts, kc, prior, True)
    cost = r @ r
    nfev = 1
    if not np.isfinite(cost):
        return 0, x, nfev
    A = J.T @ J
    gr = J.T @ r
    D = np.empty(nf)
    for j in range(nf):
        D[j] = max(np.sqrt(A[j, j]), 1e-300)
    mu = mu0                                  # initial damping relative to Marquardt's scaling
    nu = 2.0
    for _it in range(max_iter):
        gs = 0.0
        for j in range(nf):
            gs = max(gs, abs(gr[j]) / D[j])
        if gs <= gtol * max(np.sqrt(cost), 1e-300):
            return (1 if _off_bounds(x, lo, hi) else 2), x, nfev
        H = A.copy()
        rhs = -gr
        for j in range(nf):
            H[j, j] += mu * D[j] * D[j]
        # active set: a component pressed against its bound (within 1e-6) with the gradient pushing it
        # out stays where it is for this step; the others move (it is released once the gradient turns)
        for j in range(nf):
            out_hi = np.isfinite(hi[j]) and hi[j] - x[j] <= 1e-6 * max(1.0, abs(hi[j])) and gr[j] < 0
            out_lo = np.isfinite(lo[j]) and x[j] - lo[j] <= 1e-6 * max(1.0, abs(lo[j])) and gr[j] > 0
            if out_hi or out_lo:
                for k in range(nf):
                    H[j, k] = 0.0
                    H[k, j] = 0.0
                H[j, j] = 1.0
                rhs[j] = 0.0
        ok, dx = spd_solve(H, rhs)
        if not ok:                        # not positive definite (rounding): more damping
            mu *= nu
            nu *= 2.0
            if mu > 1e30:
                return 0, x, nfev
            continue
        # components that would leave the box stop short of the bound (0.995 of the way, as trf's
        # step-back ratio); the others keep their step (a projected step: no stall at a bound)
        for j in range(nf):
            if x[j] + dx[j] >= hi[j]:
                dx[j] = 0.995 * (hi[j] - x[j])
            elif x[j] + dx[j] <= lo[j]:
                dx[j] = 0.995 * (lo[j] - x[j])
        xn = x + dx
        if not _inside(xn, lo, hi):
            mu *= nu
            nu *= 2.0
            if mu > 1e30:
                return 0, x, nfev
            continue
        rn, Jn = residual(xn, free_idx, th_fixed, Rs, rs, code, Ts, kc, prior, True)
        nfev += 1
        cn = rn @ rn
        # predicted decrease of the linear model: -2 g^T dx - dx^T A dx
        pred = -2.0 * (gr @ dx) - dx @ (A @ dx)
        if np.isfinite(cn) and cn < cost:
            rho = (cost - cn) / pred if pred > 0 else 0.0
            dcost = cost - cn
            x, r, J, cost = xn, rn, Jn, cn
            A = J.T @ J
            gr = J.T @ r
            for j in range(nf):
                D[j] = max(D[j], np.sqrt(A[j, j]))
            t = 2.0 * rho - 1.0
            mu *= max(1.0 / 3.0, 1.0 - t * t * t)
            nu = 2.0
            if _norm(dx) <= xtol * (xtol + _norm(x)) or (dcost <= ftol * cost and rho > 0.25):
                return (1 if _off_bounds(x, lo, hi) else 2), x, nfev
        else:
            # a rejected step below the step tolerance ends the search as in trf (rounding floor)
            if _norm(dx) <= xtol * (xtol + _norm(x)):
                return (1 if _off_bounds(x, lo, hi) else 2), x, nfev
            mu *= nu
            nu *= 2.0
            if mu > 1e30:
                return 0, x, nfev
    return 0, x, nfev



def interpreted(kernel, **callees):
    """The Python source of the compiled ``kernel`` run by the interpreter, the compiled functions it calls
    replaced by ``callees`` (their Python sources, ``.py_func``).

    The same IEEE double arithmetic (``njit`` without ``fastmath``: no reassociation, no fused multiply-add), so
    the same numbers (``tests/methods/masscm/test_search_interpreted.py``), without numba's first-call start-up
    (LLVM: about 40 MB of memory and 0.3 s), for a caller that evaluates a small kernel a few hundred times.
    Differs where the compiled kernel raises: a float division by zero gives inf/nan here.
    """
    f = kernel.py_func
    return types.FunctionType(f.__code__, {**f.__globals__, **callees}, f.__name__, f.__defaults__, f.__closure__)


#: :func:`g_and_jac` run by the interpreter (:func:`interpreted`): what the residual functions of
#: :mod:`shipid.methods.masscm.criterion` evaluate, so that the numpy path never starts numba.
g_and_jac_py = interpreted(g_and_jac, _load_moment=_load_moment.py_func)

__all__ = ["NUMBA_LINALG_KEY", "CACHE_VALID", "sim_terms", "lstsq_qr", "spd_solve", "g_and_jac", "interpreted", "g_and_jac_py", "residual", "gauss_newton", "levenberg_marquardt", "known_array", "KC_FIELDS"]
