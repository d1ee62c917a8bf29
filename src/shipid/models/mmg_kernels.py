"""Compiled (numba) simulation of the low-speed Esso Osaka MMG structures, row by row.

A compiled copy of the state derivative :func:`shipid.models.mmg.dynamics` for rows with
their own coefficients (:func:`shipid.methods.mmg.manoeuvres.rows_deriv`) and of its RK4
integration with the inputs held over each step
(:func:`shipid.methods.mmg.manoeuvres.rows_rk4`, the package's one RK4
:func:`shipid.numerics.integrate.rk4_propagate`), for the structures

* ``esso-lowspeed``: :func:`shipid.models.mmg_forces.basis_esso` (the low-speed model of
  Miyauchi et al. 2022, J Mar Sci Technol 27:1065, §2, as coded in
  NAOE-5thLab/mmg-1p1r-simulator c54ef807);
* ``esso-cubic-hull``: the same with the cubic hull of Yasukawa & Yoshimura (2015, eq. 8),
  :func:`shipid.models.mmg_forces.cubic_hull`;
* ``esso-lowspeed-asym``: with the propeller side force and rudder offset columns of
  :func:`shipid.models.mmg.basis`;
* ``esso-lowspeed-ext``: with the surge, rudder-drag, slipstream and wind-gain columns of
  :func:`shipid.models.mmg_esso_ext.ext_columns`;

each plus Fujiwara's wind forces (:func:`shipid.models.mmg_forces.wind_forces`) of the apparent
wind (:func:`shipid.models.mmg_forces.apparent_wind`) and the rigid-body equations of
:func:`shipid.models.mmg.accelerations` (Yasukawa & Yoshimura 2015, eq. 4).

The Python functions named stay the reference: every expression here is theirs, term by term,
in their order of evaluation, with the constants that do not depend on the state evaluated in
Python exactly as the reference evaluates them (:func:`pack`). The force of each mode is the
sum over the regressor columns times the row's coefficients plus the fixed part, as the
reference's ``einsum``; only that summation order and the transcendental functions' last bits
differ (``tests/models/test_mmg_kernels.py``: the predictions agree to ~1e-12 relative).
A state beyond 1e6 becomes NaN after each step, as :func:`~shipid.methods.mmg.manoeuvres.rows_rk4`.

Numerics: float64, no ``fastmath``, ``error_model="numpy"`` (a diverging row gives NaN, not an
exception). Rows are independent, so :func:`simulate_rows` splits a large batch into contiguous
blocks integrated in threads (the kernel releases the GIL): every row's numbers are the same with any
number of threads (:func:`threads`). Every compiled function is in this file, so numba's on-disk cache (keyed on this
file) is never stale.
"""

from __future__ import annotations

import math
import os
from concurrent.futures import ThreadPoolExecutor
from typing import Mapping

import numpy as np
from numba import njit

from shipid.models.mmg_forces import fujii_f_alpha

_JIT = dict(cache=True, nogil=True, error_model="numpy")

#: Structure codes of the compiled force model.
CODES = {"esso-lowspeed": 0, "esso-lowspeed-asym": 1, "esso-lowspeed-ext": 2, "esso-cubic-hull": 3}
_JSYN, _JSYN0 = -0.35, -0.06          # as shipid.models.mmg_forces
_WIND = ("XX0", "XX1", "XX3", "XX5", "YY1", "YY3", "YY5", "NN1", "NN2", "NN3")
NPACK = 53


def supported(structure: str) -> bool:
    """True when :func:`simulate_rows` has a compiled force model for ``structure``."""
    return structure in CODES


def pack(p: Mapping[str, float], structure: str, mass: tuple) -> tuple[int, np.ndarray]:
    """Structure code and the constants of the force model, evaluated as the reference evaluates them.

    ``p``: the particulars; ``mass``: :func:`shipid.models.mmg.mass_terms`.
    """
    L, d, rho, D = p["L"], p["d"], p["rho"], p["D_p"]
    mx, my, Iz, xGm, _ = mass
    h_R = math.sqrt(p["A_R"] * p["lambda_R"])
    c = np.zeros(NPACK)
    c[0:11] = (L, 0.5 * rho * L * d, 0.5 * rho * L * L * d, p["C_rY"], p["C_rN"], p["x_P"], p["w_P0"],
               p["tau_P"], p["C_P"], D, rho * D ** 4)
    c[11:20] = (1 - p["t_P"], p["k_0"], p["k_1"], p["k_2"], p["c_0"], p["c_1"], p["c_2"], p["XP_c3"],
                p["pitch_ratio"])
    c[20:31] = (D / h_R, p["l_R"] * L, p["kx_R"] / p["eps_R"], p["eps_R"], p["kx_R_reverse"], p["C_PR"],
                p["x_R"], p["gamma_R_plus"], p["gamma_R_minus"], 0.5 * rho * p["A_R"], fujii_f_alpha(p["lambda_R"]))
    c[31:36] = (mx, my, Iz, xGm, my * Iz - xGm * xGm)
    wind = "A_T" in p and "XX0" in p
    c[36] = 1.0 if wind else 0.0
    if wind:
        c[37:40] = (0.5 * p["rho_air"], p["A_T"], p["A_L"])
        c[40:50] = [p[k] for k in _WIND]
    c[50] = -0.5 * rho * p["A_R"]
    c[51], c[52] = L ** 2, L ** 3
    return CODES[structure], c


@njit(**_JIT)
def _sign(a):
    if a > 0.0:
        return 1.0
    if a < 0.0:
        return -1.0
    return a                          # 0 (with its sign) or NaN, as np.sign


@njit(**_JIT)
def _b(flag):
    return 1.0 if flag else 0.0


@njit(**_JIT)
def _cross_parts(a, b, L, L3):
    """``parts`` of :func:`shipid.models.mmg_forces.crossflow_integrals` (before the 1/L, 1/L² scaling)."""
    h = 0.5 * L
    if abs(a) >= abs(b) * h:
        iy = _sign(a) * (a * a * L + b * b * L3 / 12.0)
        i_n = _sign(a) * a * b * L3 / 6.0
        return iy, i_n
    s1, s0 = a + b * h, a - b * h
    F2s1 = abs(s1) * s1 * s1 / 3.0
    F2s0 = abs(s0) * s0 * s0 / 3.0
    F3s1 = abs(s1) * math.pow(s1, 3.0) / 4.0
    F3s0 = abs(s0) * math.pow(s0, 3.0) / 4.0
    return (F2s1 - F2s0) / b, ((F3s1 - F3s0) - a * (F2s1 - F2s0)) / (b * b)


@njit(**_JIT)
def _pymod(a, b):
    """``np.mod`` of floats (the result has the sign of ``b``)."""
    m = np.fmod(a, b)
    if m != 0.0:
        if (b < 0.0) != (m < 0.0):
            m += b
    else:
        m = math.copysign(0.0, b)
    return m


@njit(**_JIT)
def _deriv(x, delta, n, UT, cgT, sgT, sd, cd, c, code, thX, thY, thN, out):
    """The state derivative of one row (the reference functions of the module docstring) into ``out``.

    ``cgT, sgT, sd, cd``: cos and sin of the true wind direction and of the rudder angle ``delta`` (held over
    the step, so evaluated once per step).
    """
    psi, u, v, r = x[2], x[3], x[4], x[5]
    L, qX, qN, D, rhoD4, omt = c[0], c[1], c[2], c[9], c[10], c[11]
    eps = 2.220446049250313e-16
    # apparent wind (apparent_wind)
    wx, wy = -UT * cgT, -UT * sgT
    cp, sp = math.cos(psi), math.sin(psi)
    au = cp * wx + sp * wy - u
    av = -sp * wx + cp * wy - v
    UA = math.hypot(au, av)
    gA = _pymod(math.atan2(-av, -au), 2 * np.pi)
    # wind forces (wind_forces)
    XA = YA = NA = 0.0
    if c[36] != 0.0:
        a = 2 * np.pi - gA
        q = c[37] * (UA * UA)
        CX = c[40] + c[41] * math.cos(a) + c[42] * math.cos(3 * a) + c[43] * math.cos(5 * a)
        CY = c[44] * math.sin(a) + c[45] * math.sin(3 * a) + c[46] * math.sin(5 * a)
        CN = c[47] * math.sin(a) + c[48] * math.sin(2 * a) + c[49] * math.sin(3 * a)
        XA, YA, NA = CX * q * c[38], CY * q * c[39], CN * q * L * c[39]
    # hull (basis_esso)
    U = math.sqrt(u * u + v * v)
    small = U < 1e-5
    Us = 1.0 if small else U
    v_nd = 1e-7 if small else v / Us
    r_nd = 1e-7 if small else r * L / Us
    U = 1e-7 if small else U
    beta = math.atan2(v, u)
    ab = abs(beta) / np.pi
    iy, _ = _cross_parts(v, c[3] * r, L, c[52])
    _, i_n = _cross_parts(v, c[4] * r, L, c[52])
    # propeller
    s = v_nd + c[5] * r_nd
    wP = c[6] - c[7] * abs(s) - c[8] * s * s
    omw = 1.0 - wP if u > 0 else 1.0
    if omw < eps:
        omw = eps
    elif omw > 1.0:
        omw = 1.0
    if abs(n) < eps:
        Js = _sign(u) * 1e4
    elif abs(u) < eps:
        Js = eps
    else:
        Js = u / (D * n)
    J = Js * omw if u >= 0 else Js
    T4 = rhoD4 * n * n
    pos = n >= 0
    neg = not pos
    hi = Js >= c[18]
    KT_fixed = c[12] + c[13] * J + c[14] * J * J
    if pos:
        XP_nominal = T4 * omt * KT_fixed
    elif hi:
        XP_nominal = T4 * (c[16] + c[17] * Js)
    else:
        XP_nominal = T4 * c[15]
    nP2 = (n * D * c[19]) ** 2
    nD2 = (n * D) ** 2
    aa = _b(pos and u < 0)
    lo = Js < _JSYN
    r1 = _b(neg and lo)
    r2 = _b(neg and not lo and Js > _JSYN0)
    r0 = _b(neg and not lo and not Js > _JSYN0)
    # rudder
    eta, lR, kappa, eps_R = c[20], c[21], c[22], c[23]
    omwR = eps_R * omw
    uprop = u * omw
    T4s = T4 if abs(n) > eps else 1.0
    if n > eps:
        KT = XP_nominal / (T4s * omt)
    elif abs(n) > eps:
        KT = XP_nominal / T4s
    else:
        KT = 0.0
    if n >= 0 and KT > 0:
        sl = uprop ** 2 + 8 * KT * n * n * D * D / np.pi
        if sl < 0.0:
            sl = 0.0
        slip = math.sqrt(sl)
        uR = eps_R * math.sqrt(eta * (uprop + kappa * (slip - uprop)) ** 2 + (1 - eta) * uprop ** 2)
    elif u >= 0:
        urpr1 = u * omwR + n * D * c[24] * math.sqrt(8 * abs(KT) / np.pi)
        urpr2 = u * omwR
        ursq = eta * _sign(urpr1) * urpr1 ** 2 + (1 - eta) * urpr2 ** 2 + c[25] * u * u
        uR = _sign(ursq) * math.sqrt(abs(ursq))
    else:
        uR = u
    if v + c[26] * r >= 0:
        vR = -c[27] * (v + lR * r)
    else:
        vR = -c[28] * (v + lR * r)
    UR2 = uR * uR + vR * vR
    aR = delta - math.atan2(vR, uR)
    f_alpha = c[30]
    FN = c[29] * UR2 * f_alpha * math.sin(aR)
    fr_x = -FN * sd
    fr_y = -FN * cd
    bp, bn = _b(pos), _b(neg)
    qYP, qNP = qX, qN
    sc0, sc1, sc2, sc3, sc4 = r0 * nD2, r0 * nD2 * Js, r1 * nD2, r1 * nD2 * Js, r2 * nD2
    sc5, sc6, sc7 = aa * nP2 * Js * Js, aa * nP2 * Js, aa * nP2
    # X, Y, N: the columns times the row's coefficients, in the column order of mmg.COEFS
    if code == 3:       # cubic hull (cubic_hull)
        Uc = math.sqrt(u * u + v * v)
        smc = Uc < 1e-6
        Ucs = 1.0 if smc else Uc
        vp = 0.0 if smc else v / Ucs
        rp = 0.0 if smc else r * L / Ucs
        qc = qX * Uc * Uc
        X = (-qc) * thX[0] + qc * vp * vp * thX[1] + qc * vp * rp * thX[2] + qc * rp * rp * thX[3] \
            + qc * math.pow(vp, 4.0) * thX[4]
        Y = qc * vp * thY[0] + qc * rp * thY[1] + qc * math.pow(vp, 3.0) * thY[2] + qc * (vp * vp * rp) * thY[3] \
            + qc * (vp * rp * rp) * thY[4] + qc * math.pow(rp, 3.0) * thY[5]
        qcL = qc * L
        N = qcL * vp * thN[0] + qcL * rp * thN[1] + qcL * math.pow(vp, 3.0) * thN[2] + qcL * (vp * vp * rp) * thN[3] \
            + qcL * (vp * rp * rp) * thN[4] + qcL * math.pow(rp, 3.0) * thN[5]
        jx, jy = 5, 6
    else:
        X = qX * u * U * (1 - ab) * thX[0] + qX * u * U * ab * thX[1] + qX * v * r * L * thX[2]
        Y = qX * v * abs(u) * thY[0] + qX * r * L * u * thY[1] + (-qX) * (iy / L) * thY[2]
        N = qN * v * u * thN[0] + qN * r * L * abs(u) * thN[1] + (-qN) * (i_n / c[51]) * thN[2]
        jx, jy = 3, 3
    X += bp * T4 * thX[jx] + bp * T4 * J * thX[jx + 1] + bp * T4 * J * J * thX[jx + 2] \
        + _b(neg and not hi) * T4 * thX[jx + 3] + _b(neg and hi) * T4 * thX[jx + 4] \
        + _b(neg and hi) * T4 * Js * thX[jx + 5] + fr_x * thX[jx + 6]
    Y += qYP * sc0 * thY[jy] + qYP * sc1 * thY[jy + 1] + qYP * sc2 * thY[jy + 2] + qYP * sc3 * thY[jy + 3] \
        + qYP * sc4 * thY[jy + 4] + qYP * sc5 * thY[jy + 5] + qYP * sc6 * thY[jy + 6] + qYP * sc7 * thY[jy + 7] \
        + fr_y * thY[jy + 8]
    N += qNP * sc0 * thN[jy] + qNP * sc1 * thN[jy + 1] + qNP * sc2 * thN[jy + 2] + qNP * sc3 * thN[jy + 3] \
        + qNP * sc4 * thN[jy + 4] + qNP * sc5 * thN[jy + 5] + qNP * sc6 * thN[jy + 6] + qNP * sc7 * thN[jy + 7] \
        + fr_y * thN[jy + 8]
    if code == 1 or code == 2:        # port/starboard columns (mmg.basis, esso-lowspeed-asym)
        T4a = _b(n > 0) * rhoD4 * n * n
        U_R = math.sqrt(UR2)
        dFN = c[29] * U_R ** 2 * f_alpha * math.cos(aR) * cd
        ky = jy + 9
        Y += T4a * thY[ky] + dFN * thY[ky + 1]
        N += T4a * L * thN[ky] + dFN * L * thN[ky + 1]
        if code == 2:                 # mmg_esso_ext.ext_columns
            u_R = U_R * math.cos(delta - aR)
            if n > 0 and u > 0 and U_R > 1e-6:
                uP = J * n * D
                phi = 1.0 - (eps_R * uP / U_R) ** 2
                if phi < 0.0:
                    phi = 0.0
                elif phi > 1.0:
                    phi = 1.0
            else:
                phi = 0.0
            kx = jx + 7
            X += qX * v * v * thX[kx] + qX * (r * L) ** 2 * thX[kx + 1] + c[50] * U_R * u_R * thX[kx + 2] \
                + fr_x * phi * thX[kx + 3] + XA * thX[kx + 4]
            Y += fr_y * phi * thY[ky + 2] + YA * thY[ky + 3]
            N += fr_y * phi * thN[ky + 2] + NA * thN[ky + 3]
    X += XA
    Y += YA
    N += NA
    # rigid-body equations (accelerations)
    mx, my, Iz, xGm, det = c[31], c[32], c[33], c[34], c[35]
    out[0] = u * cp - v * sp
    out[1] = u * sp + v * cp
    out[2] = r
    out[3] = (X + my * v * r + xGm * r * r) / mx
    A = Y - mx * u * r
    B = N - xGm * u * r
    out[4] = (A * Iz - xGm * B) / det
    out[5] = (my * B - xGm * A) / det


@njit(**_JIT)
def rows_rk4_kernel(c, code, ThX, ThY, ThN, x0, U, h, substeps, out):
    """RK4 of every row with its inputs ``U`` (B, L, 4) held over each step into ``out`` (B, L, 6).

    The compiled twin of :func:`shipid.numerics.integrate.rk4_propagate` on
    :func:`shipid.methods.mmg.manoeuvres.rows_dynamics`: ``substeps`` RK4 steps of length ``h`` (B, L − 1)
    per sample, then states beyond 1e6 → NaN (as :func:`shipid.models.mmg.simulate_batch`).
    """
    B, L = U.shape[0], U.shape[1]
    x = np.empty(6)
    xt = np.empty(6)
    k1 = np.empty(6)
    k2 = np.empty(6)
    k3 = np.empty(6)
    k4 = np.empty(6)
    for b in range(B):
        thX, thY, thN = ThX[b], ThY[b], ThN[b]
        for i in range(6):
            x[i] = x0[b, i]
            out[b, 0, i] = x[i]
        for k in range(L - 1):
            delta, n, UT, gT = U[b, k, 0], U[b, k, 1], U[b, k, 2], U[b, k, 3]
            hs = h[b, k]
            cgT, sgT, sd, cd = math.cos(gT), math.sin(gT), math.sin(delta), math.cos(delta)
            for _ in range(substeps):
                _deriv(x, delta, n, UT, cgT, sgT, sd, cd, c, code, thX, thY, thN, k1)
                for i in range(6):
                    xt[i] = x[i] + 0.5 * hs * k1[i]
                _deriv(xt, delta, n, UT, cgT, sgT, sd, cd, c, code, thX, thY, thN, k2)
                for i in range(6):
                    xt[i] = x[i] + 0.5 * hs * k2[i]
                _deriv(xt, delta, n, UT, cgT, sgT, sd, cd, c, code, thX, thY, thN, k3)
                for i in range(6):
                    xt[i] = x[i] + hs * k3[i]
                _deriv(xt, delta, n, UT, cgT, sgT, sd, cd, c, code, thX, thY, thN, k4)
                for i in range(6):
                    x[i] = x[i] + (hs / 6.0) * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            for i in range(6):
                x[i] = x[i] if abs(x[i]) < 1e6 else np.nan
                out[b, k + 1, i] = x[i]


#: Fewest rows per thread of :func:`simulate_rows` (below, one thread: a thread's start costs more).
MIN_ROWS_PER_THREAD = 64
#: Most threads :func:`threads` uses unless ``SHIPID_THREADS`` says otherwise.
MAX_THREADS = 4
_POOL: dict[int, ThreadPoolExecutor] = {}
if hasattr(os, "register_at_fork"):       # a forked child has none of the parent's threads: it starts its own pools
    os.register_at_fork(after_in_child=_POOL.clear)


def threads(rows: int) -> int:
    """Threads for a batch of ``rows``: ``SHIPID_THREADS`` if set, else the CPUs this process may use (at most
    :data:`MAX_THREADS`), and no more than one per :data:`MIN_ROWS_PER_THREAD` rows."""
    env = os.environ.get("SHIPID_THREADS", "").strip()
    if env.isdigit() and int(env) > 0:
        n = int(env)
    else:
        try:
            n = min(len(os.sched_getaffinity(0)), MAX_THREADS)
        except AttributeError:  # pragma: no cover - not Linux
            n = min(os.cpu_count() or 1, MAX_THREADS)
    return max(1, min(n, rows // MIN_ROWS_PER_THREAD))


def simulate_rows(structure: str, particulars: Mapping[str, float], mass: tuple, Th: Mapping[str, np.ndarray],
                  x0: np.ndarray, U: np.ndarray, h: np.ndarray, substeps: int = 1) -> np.ndarray:
    """(B, L, 6) predictions of rows with coefficients ``Th[mode]`` (B, p), starts ``x0`` (B, 6), inputs
    ``U`` (B, L, 4) (rudder, propeller, true wind speed and direction) and RK4 steps ``h`` (B, L − 1),
    ``substeps`` of them per sample."""
    code, c = pack(particulars, structure, mass)
    x0 = np.ascontiguousarray(x0, dtype=float)
    U = np.ascontiguousarray(U, dtype=float)
    h = np.ascontiguousarray(h, dtype=float)
    B, L = U.shape[:2]
    out = np.empty((B, L, 6))
    Tx, Ty, Tn = (np.ascontiguousarray(np.broadcast_to(Th[m], (B, np.shape(Th[m])[-1])), dtype=float)
                  for m in ("X", "Y", "N"))
    nt = threads(B)
    if nt == 1:
        rows_rk4_kernel(c, code, Tx, Ty, Tn, x0, U, h, int(substeps), out)
        return out
    pool = _POOL.get(nt)
    if pool is None:
        pool = _POOL[nt] = ThreadPoolExecutor(max_workers=nt, thread_name_prefix="shipid-rows")
    edges = np.linspace(0, B, nt + 1).astype(int)
    jobs = [pool.submit(rows_rk4_kernel, c, code, Tx[a:b], Ty[a:b], Tn[a:b], x0[a:b], U[a:b], h[a:b],
                        int(substeps), out[a:b]) for a, b in zip(edges[:-1], edges[1:])]
    for j in jobs:
        j.result()
    return out


__all__ = ["CODES", "MIN_ROWS_PER_THREAD", "MAX_THREADS", "supported", "pack", "threads", "rows_rk4_kernel",
           "simulate_rows"]
