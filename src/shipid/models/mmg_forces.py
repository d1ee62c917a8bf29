"""Force models of the MMG structures of :mod:`shipid.models.mmg`, each linear in its coefficients.

:func:`basis_esso` (the low-speed Esso Osaka model, mmg-1p1r-simulator), :func:`basis_yasukawa`
(Yasukawa & Yoshimura 2015, eqs. 8–12) and :func:`cubic_hull` (the cubic hull of eqs. 8) return
the regressors ``H`` and fixed parts ``F0`` of the three modes (``F = H θ + F0``), their columns
in the order of :data:`shipid.models.mmg.COEFS`; :func:`shipid.models.mmg.basis` picks one by the
model's structure and adds the wind forces of Fujiwara et al. (1998) (:func:`wind_forces` of the
apparent wind :func:`apparent_wind`). Sources and conventions: :mod:`shipid.models.mmg`.
"""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np


# Hachii's reverse-propeller side-force regimes (mmg-1p1r-simulator propellerforce.py).
_JSYN, _JSYN0 = -0.35, -0.06


# ----------------------------------------------------------------------------- wind
def apparent_wind(U_T, gamma_T, psi, u, v):
    """Relative wind speed and direction (from, clockwise from the bow) at midship.

    ``U_T, γ_T``: true wind speed and the earth-fixed direction it blows from
    (clockwise from x0). The air velocity is ``−U_T (cos γ_T, sin γ_T)`` in earth
    axes; in body axes minus the ship's velocity ``(u, v)`` it gives the apparent wind.
    """
    wx, wy = -U_T * np.cos(gamma_T), -U_T * np.sin(gamma_T)
    c, s = np.cos(psi), np.sin(psi)
    au = c * wx + s * wy - u
    av = -s * wx + c * wy - v
    return np.hypot(au, av), np.mod(np.arctan2(-av, -au), 2 * np.pi)


def fujiwara_coefficients(p: Mapping[str, float]) -> dict[str, float]:
    """Fujiwara et al. (1998) wind-force regression coefficients ``XX0 … NN3`` from hull geometry.

    Constants as coded in mmg-1p1r-simulator ``wind.py`` (``windCoeff``); ``p`` holds
    ``L, A_T, A_L, AOD, LCW, LCBR, HBR, HC, SBW``.
    """
    L, AT, AL, AOD = p["L"], p["A_T"], p["A_L"], p["AOD"]
    LCW, LCBR, HBR, HC, SBW = p["LCW"], p["LCBR"], p["HBR"], p["HC"], p["SBW"]
    XX0 = -0.330 + 0.293 * (SBW * HBR / AT) + 0.0193 * (LCW / HC) + 0.6820 * (AOD / L / L)
    XX1 = (-1.353 + 1.700 * (AL / L / SBW) + 2.8700 * (L * HC / AL) - 0.4630 * (L * HBR / AL)
           - 0.570 * (AOD / AL) - 6.640 * (AT / L / SBW) - 0.0123 * (L * L / AT) + 0.0202 * (L / HC))
    XX3 = (0.830 - 0.413 * (AL / L / HBR) - 0.0827 * (AL / AT) - 0.5630 * (L * HC / AL)
           + 0.804 * (AOD / AL) - 5.670 * (AOD / L / L) + 0.0401 * (LCW / HC) - 0.1320 * (LCBR / L))
    XX5 = 0.0372 - 0.0075 * (AL / AOD) - 0.1030 * (LCBR / L) + 0.0921 * (AL / L / SBW)
    YY1 = (0.684 + 0.717 * (LCBR / L) - 3.2200 * (LCW / L) + 0.0281 * (AL / AOD) + 0.0661 * (LCW / HC)
           + 0.2980 * (AT / (SBW * HBR)))
    YY3 = (-0.400 + 0.282 * (AL / (L * SBW)) + 0.3070 * (L * HC / AL) + 0.0519 * (LCBR / L)
           + 0.0526 * (SBW / HBR) - 0.0814 * (AOD / AL) + 0.0582 * (AT / (SBW * HBR)))
    YY5 = (0.122 - 0.166 * (AL / (L * SBW)) - 0.0054 * (L / HBR) - 0.0481 * (LCBR / L)
           - 0.0136 * (SBW ** 2 / AT) + 0.0864 * (LCW / L) - 0.0297 * (LCW * HC / AL))
    NN1 = (0.2990 + 1.710 * (LCW / L) + 0.183 * (L * HC / AL) - 1.09 * (AT / AL) - 0.0442 * (LCW / HC)
           - 0.289 * (AL / (L * SBW)) + 4.24 * (AT / L ** 2) - 0.0646 * (SBW ** 2 / AT) + 0.0306 * (LCBR / L))
    NN2 = (0.1170 + 0.123 * (LCBR / L) - 0.323 * (LCW / L) + 0.0041 * (AL / AOD) - 0.166 * (AT / SBW ** 2)
           - 0.0109 * (L / HBR) + 0.174 * (AT / (SBW * HBR)) + 0.214 * (AL / (L * SBW)) - 1.06 * (AL / L ** 2))
    NN3 = 0.0230 + 0.0385 * (LCBR / L) - 0.0339 * (AT / (SBW * HBR)) + 0.0023 * (AL / AT)
    return dict(XX0=XX0, XX1=XX1, XX3=XX3, XX5=XX5, YY1=YY1, YY3=YY3, YY5=YY5, NN1=NN1, NN2=NN2, NN3=NN3)


def wind_forces(p: Mapping[str, float], U_A, gamma_A):
    """Wind forces (N, N m) from the relative wind after Fujiwara's regression.

    Angle of attack ``AOA = 2π − γ_A`` (counter-clockwise), as in mmg-1p1r-simulator.
    Returns zeros when the particulars have no wind geometry.
    """
    if "A_T" not in p or "XX0" not in p:
        z = np.zeros_like(np.asarray(U_A, dtype=float))
        return z, z, z
    a = 2 * np.pi - gamma_A
    q = 0.5 * p["rho_air"] * U_A ** 2
    CX = p["XX0"] + p["XX1"] * np.cos(a) + p["XX3"] * np.cos(3 * a) + p["XX5"] * np.cos(5 * a)
    CY = p["YY1"] * np.sin(a) + p["YY3"] * np.sin(3 * a) + p["YY5"] * np.sin(5 * a)
    CN = p["NN1"] * np.sin(a) + p["NN2"] * np.sin(2 * a) + p["NN3"] * np.sin(3 * a)
    return CX * q * p["A_T"], CY * q * p["A_L"], CN * q * p["L"] * p["A_L"]


# ----------------------------------------------------------------------------- hull helpers
def crossflow_integrals(v, r, L, C_Y, C_N):
    """Cross-flow drag integrals of the low-speed hull model (Yoshimura; exact).

    ``I_Y = (1/L) ∫ |v + C_Y r x| (v + C_Y r x) dx`` and
    ``I_N = (1/L²) ∫ |v + C_N r x| (v + C_N r x) x dx`` over ``x ∈ [−L/2, L/2]``
    (mmg-1p1r-simulator integrates them by Simpson's rule on 100 points; here in
    closed form with the antiderivatives ``|s| s²/3`` and ``|s| s³/4``).
    """
    def parts(a, b):
        h = 0.5 * L
        nochange = np.abs(a) >= np.abs(b) * h        # no sign change along the hull
        bs = np.where(nochange, 1.0, b)             # safe divisor
        s1, s0 = a + bs * h, a - bs * h
        F2 = lambda s: np.abs(s) * s * s / 3.0     # noqa: E731  ∫|s|s ds
        F3 = lambda s: np.abs(s) * s ** 3 / 4.0    # noqa: E731  ∫|s|s² ds
        iy = np.where(nochange, np.sign(a) * (a * a * L + b * b * L ** 3 / 12.0), (F2(s1) - F2(s0)) / bs)
        i_n = np.where(nochange, np.sign(a) * a * b * L ** 3 / 6.0,
                       ((F3(s1) - F3(s0)) - a * (F2(s1) - F2(s0))) / (bs * bs))
        return iy, i_n
    iy, _ = parts(v, C_Y * r)
    _, i_n = parts(v, C_N * r)
    return iy / L, i_n / L ** 2


# ----------------------------------------------------------------------------- structures
def fujii_f_alpha(lambda_R):
    """Rudder normal-force slope coefficient ``f_α = 6.13 Λ / (2.25 + Λ)`` of aspect ratio ``Λ`` (Fujii's formula,
    the low-speed Esso model's rudder)."""
    return 6.13 * lambda_R / (2.25 + lambda_R)


def basis_esso(p, u, v, r, delta, n):
    """Regressors of the low-speed Esso Osaka model (hull after Yoshimura, four-quadrant propeller,
    low-speed rudder; mmg-1p1r-simulator c54ef807), as :func:`shipid.models.mmg.basis` returns them."""
    L, d, rho, D = p["L"], p["d"], p["rho"], p["D_p"]
    U = np.sqrt(u * u + v * v)
    small = U < 1e-5
    Us = np.where(small, 1.0, U)
    v_nd = np.where(small, 1e-7, v / Us)
    r_nd = np.where(small, 1e-7, r * L / Us)
    U = np.where(small, 1e-7, U)
    beta = np.arctan2(v, u)
    qX = 0.5 * rho * L * d
    qN = 0.5 * rho * L * L * d
    # --- hull (hullForceYoshimuraSimpson)
    ab = np.abs(beta) / np.pi
    iy, i_n = crossflow_integrals(v, r, L, p["C_rY"], p["C_rN"])
    # --- propeller (get_propellerforce, switch_prop_x = 1, switch_prop_y = switch_prop_n = 1)
    s = v_nd + p["x_P"] * r_nd
    wP = p["w_P0"] - p["tau_P"] * np.abs(s) - p["C_P"] * s * s
    omw = np.where(u > 0, 1.0 - wP, 1.0)
    omw = np.clip(omw, np.finfo(float).eps, 1.0)
    eps = np.finfo(float).eps
    n_safe = np.where(np.abs(n) < eps, 1.0, n)
    Js = np.where(np.abs(n) < eps, np.sign(u) * 1e4,
                  np.where(np.abs(u) < eps, eps, u / (D * n_safe)))
    J = np.where(u >= 0, Js * omw, Js)
    T4 = rho * D ** 4 * n * n
    pos = n >= 0
    neg = ~pos
    hi = Js >= p["XP_c3"]
    # thrust coefficient of the open-water curve (fixed: drives the rudder slipstream)
    KT_fixed = p["k_0"] + p["k_1"] * J + p["k_2"] * J * J
    XP_nominal = np.where(pos, T4 * (1 - p["t_P"]) * KT_fixed,
                          np.where(hi, T4 * (p["c_1"] + p["c_2"] * Js), T4 * p["c_0"]))
    qYP = 0.5 * rho * L * d
    qNP = 0.5 * rho * L * L * d
    nP2 = (n * D * p["pitch_ratio"]) ** 2
    nD2 = (n * D) ** 2
    astern_ahead = pos & (u < 0)
    r1 = neg & (Js < _JSYN)
    r2 = neg & ~(Js < _JSYN) & (Js > _JSYN0)
    r0 = neg & ~(Js < _JSYN) & ~(Js > _JSYN0)
    side = [r0 * nD2, r0 * nD2 * Js, r1 * nD2, r1 * nD2 * Js, r2 * nD2,
            astern_ahead * nP2 * Js * Js, astern_ahead * nP2 * Js, astern_ahead * nP2]
    # --- rudder (get_rudderforce, switch_rudder = 1, switch_fn = 1 Fujii, switch_ur = 1)
    h_R = math.sqrt(p["A_R"] * p["lambda_R"])
    eta = D / h_R
    lR = p["l_R"] * L
    kappa = p["kx_R"] / p["eps_R"]
    omwR = p["eps_R"] * omw
    uprop = u * omw
    T4s = np.where(np.abs(n) > eps, T4, 1.0)
    KT = np.where(n > eps, XP_nominal / (T4s * (1 - p["t_P"])),
                  np.where(np.abs(n) > eps, XP_nominal / T4s, 0.0))
    urpr1 = u * omwR + n * D * p["kx_R_reverse"] * np.sqrt(8 * np.abs(KT) / np.pi)
    urpr2 = u * omwR
    ursq = eta * np.sign(urpr1) * urpr1 ** 2 + (1 - eta) * urpr2 ** 2 + p["C_PR"] * u * u
    slip = np.sqrt(np.maximum(uprop ** 2 + 8 * KT * n * n * D * D / np.pi, 0.0))
    uR_ahead = p["eps_R"] * np.sqrt(eta * (uprop + kappa * (slip - uprop)) ** 2 + (1 - eta) * uprop ** 2)
    uR = np.where((n >= 0) & (KT > 0), uR_ahead,
                  np.where(u >= 0, np.sign(ursq) * np.sqrt(np.abs(ursq)), u))
    vR = np.where(v + p["x_R"] * r >= 0, -p["gamma_R_plus"] * (v + lR * r), -p["gamma_R_minus"] * (v + lR * r))
    UR2 = uR * uR + vR * vR
    aR = delta - np.arctan2(vR, uR)
    f_alpha = fujii_f_alpha(p["lambda_R"])
    FN = 0.5 * rho * p["A_R"] * UR2 * f_alpha * np.sin(aR)
    HX = np.stack([qX * u * U * (1 - ab), qX * u * U * ab, qX * v * r * L,
                   pos * T4, pos * T4 * J, pos * T4 * J * J,
                   neg * ~hi * T4, neg * hi * T4, neg * hi * T4 * Js,
                   -FN * np.sin(delta)], axis=-1)
    HY = np.stack([qX * v * np.abs(u), qX * r * L * u, -qX * iy] + [qYP * c for c in side]
                  + [-FN * np.cos(delta)], axis=-1)
    HN = np.stack([qN * v * u, qN * r * L * np.abs(u), -qN * i_n] + [qNP * c for c in side]
                  + [-FN * np.cos(delta)], axis=-1)
    zero = np.zeros_like(u)
    aux = {"U_R": np.sqrt(UR2), "alpha_R": aR, "J": J, "F_N": FN, "beta": beta}
    return {"X": (HX, zero), "Y": (HY, zero.copy()), "N": (HN, zero.copy()), "aux": aux}


def cubic_hull(p, u, v, r):
    """Hull regressors of Yasukawa & Yoshimura (2015) eqs. 8: X, Y, N columns (forces ∝ U²)."""
    L, d, rho = p["L"], p["d"], p["rho"]
    U = np.sqrt(u * u + v * v)
    small = U < 1e-6
    Us = np.where(small, 1.0, U)
    vp = np.where(small, 0.0, v / Us)
    rp = np.where(small, 0.0, r * L / Us)
    qX = 0.5 * rho * L * d * U * U
    HX = np.stack([-qX, qX * vp * vp, qX * vp * rp, qX * rp * rp, qX * vp ** 4], axis=-1)
    hull = [vp, rp, vp ** 3, vp * vp * rp, vp * rp * rp, rp ** 3]
    HY = np.stack([qX * h for h in hull], axis=-1)
    HN = np.stack([qX * L * h for h in hull], axis=-1)
    return HX, HY, HN


# ----------------------------------------------------------------------------- rudder at large angles
#: Particulars of the optional angle-dependent rudder terms (:func:`rudder_lift_and_crossflow`,
#: :func:`rudder_side_slope`); each absent or 0 leaves the standard method's forces unchanged, each may be a
#: scalar or one value per row of a batch.
RUDDER_LARGE_ANGLE = ("rudder_stall_plus", "rudder_stall_minus", "rudder_crossflow_side", "rudder_side_slope")


def stalled_sine(sa, alpha_s):
    """Saturating lift part ``g(α) = s tanh(sin α / s)``, ``s = sin α_s`` (``α_s > 0``; ``α_s ≤ 0``: no stall, ``g = sin α``).

    ``g`` is odd, increases monotonically with ``sin α``, equals ``sin α`` to first order and never exceeds
    ``s`` in magnitude: the linear slope and the ceiling meet at the effective stall angle ``α_s``, a smooth
    stand-in for the normal-force plateau of a rudder past stall (Molland & Turnock, Marine Rudders and
    Control Surfaces, 2007, ch. 3: behind a propeller the plateau sets in later and more gently than in free
    stream, which a soft saturation rather than a drop represents).
    """
    a = np.asarray(alpha_s, float)
    on = a > 0
    s = np.where(on, np.sin(np.where(on, a, 1.0)), 1.0)
    return np.where(on, s * np.tanh(sa / s), sa)


def rudder_lift_and_crossflow(p, alpha_R, sa):
    """Lift part ``g(α_R)`` and cross-flow coefficient of the rudder normal force, per inflow side.

    ``F_N = ½ ρ A_R U_R² (f_α g(α_R) + C_Dc,± sin α_R |sin α_R|)`` (Yasukawa & Yoshimura 2015 eq. 23 with
    ``g = sin α_R`` and ``C_Dc = 0``; the cross-flow part after Hoerner 1985 ch. 3). Optional particulars
    (all absent or 0 by default: ``g = sin α_R``, ``C_Dc,± = rudder_crossflow``, bit-identical):

    * ``rudder_stall_plus`` / ``rudder_stall_minus``: effective stall angle (rad) for ``α_R ≥ 0`` / ``α_R < 0``
      (:func:`stalled_sine`);
    * ``rudder_crossflow_side`` ``b``: ``C_Dc,± = C_Dc (1 ± b)``, the cross-flow part larger on one side
      (``b < 0``: on the ``α_R < 0`` side).

    Returns ``(g, C_Dc,±)``.
    """
    lift = sa
    sp, sm = p.get("rudder_stall_plus", 0.0), p.get("rudder_stall_minus", 0.0)
    if np.any(sp) or np.any(sm):
        lift = stalled_sine(sa, np.where(alpha_R >= 0, sp, sm))
    cdc = p.get("rudder_crossflow", 0.0)
    b = p.get("rudder_crossflow_side", 0.0)
    if np.any(b):
        cdc = cdc * (1.0 + b * np.sign(alpha_R))
    return lift, cdc


def rudder_side_slope(p, FN, delta):
    """``F_N (1 + k δ)``: a port/starboard rudder effectiveness that grows with the rudder angle.

    ``rudder_side_slope`` ``k`` (1/rad; absent or 0: ``F_N`` unchanged) makes the relative difference between
    the sides proportional to ``|δ|`` (``k < 0``: the ``δ < 0`` side stronger), where ``rudder_side_gain``
    makes it constant. The factor is clipped at 0.
    """
    k = p.get("rudder_side_slope", 0.0)
    if not np.any(k):
        return FN
    return FN * np.maximum(1.0 + k * delta, 0.0)


def basis_yasukawa(p, u, v, r, delta, n):
    """Regressors of the MMG standard method (Yasukawa & Yoshimura 2015, eqs. 8–12, 15, 23–28),
    as :func:`shipid.models.mmg.basis` returns them."""
    L, d, rho, D = p["L"], p["d"], p["rho"], p["D_p"]
    U = np.sqrt(u * u + v * v)
    small = U < 1e-6
    Us = np.where(small, 1.0, U)
    vp = np.where(small, 0.0, v / Us)
    rp = np.where(small, 0.0, r * L / Us)
    beta = np.arctan2(-v, u)
    qX = 0.5 * rho * L * d * U * U
    qN = qX * L
    # propeller (eqs. 9-10); wake after Yasukawa & Yoshimura 2015 eq. 15
    beta_P = beta - p["x_P"] * rp
    C2 = np.where(beta_P > 0, p["C_2_plus"], p["C_2_minus"])
    omw = (1 - p["w_P0"]) * (1 + (1 - np.exp(-p["C_1"] * np.abs(beta_P))) * (C2 - 1))
    n_safe = np.where(np.abs(n) < 1e-9, 1.0, n)
    J = np.where(np.abs(n) < 1e-9, 0.0, u * omw / (n_safe * D))
    KT = p["k_0"] + p["k_1"] * J + p["k_2"] * J * J
    T = rho * n * n * D ** 4 * KT
    # rudder (eqs. 11-12, 23-28)
    eta = D / p["H_R"]
    Jsafe = np.where(np.abs(J) < 1e-9, 1e-9, J)
    uP = u * omw
    slip = np.sqrt(np.maximum(1 + 8 * KT / (np.pi * Jsafe * Jsafe), 0.0))
    uR = p["eps_R"] * uP * np.sqrt(eta * (1 + p["kappa_R"] * (slip - 1)) ** 2 + (1 - eta))
    beta_R = beta - p["l_R"] * rp
    gam = np.where(beta_R < 0, p["gamma_R_minus"], p["gamma_R_plus"])
    vR = U * gam * beta_R
    UR2 = uR * uR + vR * vR
    aR = delta - np.arctan2(vR, uR)
    sa = np.sin(aR)
    # optional cross-flow drag part of the normal force (Hoerner 1965: C_N = f_a sin a + C_Dc sin a |sin a|);
    # "rudder_crossflow" = C_Dc, absent or 0 for the standard method; optional angle-dependent terms per side
    # (stall, cross-flow per side, side gain growing with the angle): rudder_large_angle, all off by default
    lift, cdc = rudder_lift_and_crossflow(p, aR, sa)
    FN = 0.5 * rho * p["A_R"] * UR2 * (p["f_alpha"] * lift + cdc * sa * np.abs(sa))
    # optional port/starboard rudder effectiveness (propeller swirl): F_N (1 + s sign(delta)), "rudder_side_gain" = s
    # (a scalar, or one value per row of a batch)
    sg = p.get("rudder_side_gain", 0.0)
    if np.any(sg):
        FN = FN * (1.0 + sg * np.sign(delta))
    FN = rudder_side_slope(p, FN, delta)
    HX = np.stack([-qX, qX * vp * vp, qX * vp * rp, qX * rp * rp, qX * vp ** 4, T, -FN * np.sin(delta)], axis=-1)
    hull = [vp, rp, vp ** 3, vp * vp * rp, vp * rp * rp, rp ** 3]
    HY = np.stack([qX * h for h in hull] + [-FN * np.cos(delta)], axis=-1)
    HN = np.stack([qN * h for h in hull] + [-FN * np.cos(delta)], axis=-1)
    zero = np.zeros_like(u)
    aux = {"U_R": np.sqrt(UR2), "alpha_R": aR, "J": J, "F_N": FN, "beta": beta, "T": T, "FN_cos": -FN * np.cos(delta)}
    return {"X": (HX, zero), "Y": (HY, zero.copy()), "N": (HN, zero.copy()), "aux": aux}


__all__ = ["apparent_wind", "fujiwara_coefficients", "wind_forces", "crossflow_integrals", "fujii_f_alpha", "basis_esso",
           "cubic_hull", "RUDDER_LARGE_ANGLE", "stalled_sine", "rudder_lift_and_crossflow", "rudder_side_slope",
           "basis_yasukawa"]
