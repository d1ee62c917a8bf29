"""Units of the numbers a report prints outside the estimates table, and bis → SI.

:func:`unit_of` finds the SI unit of a model / particulars / diagnostics entry from
its key (``particulars.L`` → ``m``, ``known.M`` → ``kg``), first in the vessel file
of the result's vessel (``shipid.vessels``: every value there carries its unit),
then in :data:`KNOWN_UNITS`. :func:`bis_to_si` converts the DP parameters θ1…θ9
of Fossen, Sagatun & Sørensen (1996) from the bis system (eqs. 26–29, see
:mod:`shipid.models.bis`) to SI: A_h entries are rates (1/s) or rate ratios and
the thrust coefficients K are forces (N).
"""

from __future__ import annotations

import functools
import math
import re
from typing import Any

from shipid.models.bis import Bis
from shipid.vessels import load_vessel

#: SI unit of common model and particulars keys (last dotted component), "-" = dimensionless.
KNOWN_UNITS: dict[str, str] = {
    "L": "m", "Lpp": "m", "B": "m", "d": "m", "draft": "m", "D_p": "m", "x_G": "m", "xG": "m",
    "x_R": "m", "x_P": "m", "x_H": "m", "l_R": "m", "z_f": "m", "zg_bar": "m", "zc_bar": "m",
    "zs_bar": "m", "zm_bar": "m", "LCW": "m", "LCBR": "m", "HBR": "m", "HC": "m", "SBW": "m",
    "rho": "kg/m³", "rho_air": "kg/m³", "m": "kg", "M": "kg", "m_c": "kg", "m_x": "kg", "m_y": "kg",
    "J_z": "kg·m²", "I_zG": "kg·m²", "I_z": "kg·m²", "A_R": "m²", "A_T": "m²", "A_L": "m²", "AOD": "m²",
    "g": "m/s²", "U": "m/s", "U0": "m/s", "U_ref": "m/s", "u0": "m/s", "n": "1/s", "n_prop": "1/s",
    "seconds": "s", "duration_s": "s", "dt_s": "s", "t0_s": "s", "T": "s",
    "sigma_pos": "m", "sigma_psi": "rad", "sigma_uv": "m/s", "sigma_r": "rad/s",
    "trim_s": "s", "length_s": "s", "stride_s": "s", "horizon": "s",
    "x": "m", "y": "m", "psi": "rad", "u": "m/s", "v": "m/s", "r": "rad/s",
    "lambda_R": "-", "pitch_ratio": "-", "t_P": "-", "w_P0": "-", "tau_P": "-", "C_P": "-", "t_R": "-",
    "a_H": "-", "eps_R": "-", "kx_R": "-", "kx_R_reverse": "-", "gamma_R_minus": "-", "gamma_R_plus": "-",
    "C_rY": "-", "C_rN": "-", "C_PR": "-", "k_0": "-", "k_1": "-", "k_2": "-", "c_0": "-", "c_1": "-",
    "c_2": "-", "R2": "-", "kappa": "-", "Cp": "-",
    # DP options and diagnostics (Fossen, Sagatun & Sørensen 1996 eqs. 35-38; methods.dp.DPOptions)
    "q_h": "bis force²·bis time", "q_b": "bis force²/bis time", "yaw_arm": "L", "q_theta": "1/bis time",
    "h0_std": "bis momentum", "b0_std": "bis force", "current0_std": "m/s", "q_c": "(m/s)²/s",
    "nis_mean": "-", "loglik": "-", "max_late_deviation_sigma": "σ", "noise_log_scales": "ln(scale)",
}

#: Keys whose value is never a physical quantity (counts, flags, names).
UNITLESS_KEYS = {"iterations", "n", "p", "count", "folds", "samples", "n_samples", "seed", "max_iter",
                 "min_iter", "ar_order", "decimate", "k", "nis_dof", "passes"}


@functools.lru_cache(maxsize=16)
def _vessel_units(vessel: str) -> dict[str, str]:
    """key → unit of every value in the vessel file ``vessel`` (empty if there is none)."""
    try:
        v = load_vessel(vessel)
    except Exception:  # noqa: BLE001 - an unknown vessel just has no file units
        return {}
    out: dict[str, str] = {}
    for sec in getattr(v, "sections", {}).values():
        for key, item in sec.items():
            u = getattr(item, "unit", None)
            if u and u != "-":  # "-" there also marks matrices in the bis system: keep the defaults
                out.setdefault(str(key), str(u))
    return out


def unit_of(key: str, value: Any = None, *, vessel: str | None = None) -> str:
    """SI unit of the entry ``key`` (dotted path) or "" when none is known / it is not a quantity."""
    if isinstance(value, (bool, str)) or value is None:
        return ""
    last = str(key).split(".")[-1]
    base = re.sub(r"\[.*\]$", "", last)
    if base in UNITLESS_KEYS:
        return ""
    if vessel:
        u = _vessel_units(str(vessel)).get(base)
        if u:
            return pretty_unit(u)
    return pretty_unit(KNOWN_UNITS.get(base, ""))


def pretty_unit(u: str | None) -> str:
    """``kg*m^2`` → ``kg·m²`` (readable, same meaning)."""
    if not u:
        return ""
    if str(u).strip() in ("- (bis)", "(bis)", "-(bis)"):
        return "bis"  # dimensionless in the bis system; the report gives the SI values beside
    s = str(u).replace("*", "·").replace("^2", "²").replace("^3", "³").replace("^-1", "⁻¹")
    return s


# -- bis → SI for the DP parameters (Fossen, Sagatun & Sørensen 1996) -------------------------------

#: θ index → (kind, A_h row, A_h col) ; kind "Ah" or "K".
_DP_THETA = {"theta1": ("Ah", 0, 0), "theta2": ("Ah", 1, 1), "theta3": ("Ah", 1, 2), "theta4": ("Ah", 2, 1),
             "theta5": ("Ah", 2, 2), "theta6": ("K", 0, 0), "theta7": ("K", 0, 0), "theta8": ("K", 0, 0),
             "theta9": ("K", 0, 0)}
#: SI unit of A_h[i, j] (h = M ν: N·s, N·s, N·m·s): ḣ_i = A_h[i, j] h_j.
_AH_UNITS = {(0, 0): "1/s", (1, 1): "1/s", (1, 2): "1/(m·s)", (2, 1): "m/s", (2, 2): "1/s"}


def bis_to_si(name: str, value: float, std: float, L: float, m: float, g: float = 9.81):
    """(value, std, unit, note) of the DP parameter ``name`` (θ1…θ9, bis) in SI, or None.

    A_h (eq. 35) scales as ``H A_h'' H⁻¹ / Th`` with ``H = diag(m g Th, m g Th, m g L Th)`` and
    ``Th = sqrt(L/g)`` (:meth:`shipid.models.bis.Bis.Ah_from_bis`); a diagonal entry is a rate in
    1/s whose inverse is the time constant. K (eq. 6) is a force: ``m g K''`` in N.
    """
    spec = _DP_THETA.get(name)
    if spec is None or not all(math.isfinite(float(x)) and float(x) > 0 for x in (L, m, g)):
        return None
    th = math.sqrt(L / g)
    kind, i, j = spec
    if kind == "K":
        f = m * g
        return value * f, std * f, "N", "thrust per unit command, m g K''"
    h = [m * g * th, m * g * th, m * g * L * th]
    f = h[i] / h[j] / th
    v, s = value * f, std * f
    note = ""
    if i == j and v != 0:
        note = f"time constant −1/A_h = {(-1.0 / v):.4g} s" if v < 0 else f"unstable: 1/A_h = {1.0 / v:.4g} s"
    return v, s, _AH_UNITS[(i, j)], note


#: Units of M (ν̇ → force) and D (ν → force) in SI, row = force/moment, column = u, v, r.
_M_UNITS = [["kg", "kg", "kg·m"], ["kg", "kg", "kg·m"], ["kg·m", "kg·m", "kg·m²"]]
_D_UNITS = [["N·s/m", "N·s/m", "N·s"], ["N·s/m", "N·s/m", "N·s"], ["N·s", "N·s", "N·m·s"]]


def dp_si_matrices(model) -> list[tuple[str, list, list]]:
    """(title, 3 × 3 SI matrix, units) for the bis M'' and D'' of a DP result's model (eqs. 27–28)."""
    import numpy as np

    try:
        b = Bis(L=float(model["L"]), m=float(model["m"]), g=float(model.get("g", 9.81)))
    except (KeyError, TypeError, ValueError):
        return []
    out = []
    for key, conv, units, title in (("M", b.M_from_bis, _M_UNITS, "inertia matrix M (rigid body + added mass)"),
                                    ("D", b.D_from_bis, _D_UNITS, "linear damping matrix D")):
        try:
            a = np.asarray(model[key], dtype=float)
        except (KeyError, TypeError, ValueError):
            continue
        if a.shape == (3, 3) and np.isfinite(a).all():
            out.append((f"{key} — {title}", conv(a).tolist(), units))
    return out
