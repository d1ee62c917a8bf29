"""An MMG model in the parameter objects of shipmmg (the MMG simulator on PyPI, optional extra ``shipmmg``).

shipmmg (``shipmmg.mmg_3dof``, version 0.0.11) codes the MMG standard method of Yasukawa & Yoshimura
(2015) with two dataclasses, ``Mmg3DofBasicParams`` (particulars, propeller and rudder constants) and
``Mmg3DofManeuveringParams`` (``K_T`` polynomial and hull coefficients ``R_0'``, ``X_vv'`` …
``N_rrr'``). Only shipid's ``yasukawa2015`` structure shares that form. The mapping:

* hull coefficients one to one (``Y_v`` → ``Y_v_dash`` …; ``R_0`` → ``R_0_dash``);
* the identified gains of the propeller and rudder forces (Yasukawa & Yoshimura eqs. 9, 11):
  ``XP_gain = 1 − t_P`` → ``t_P``, ``XR_gain = 1 − t_R`` → ``t_R``, ``YR_gain = 1 + a_H`` → ``a_H``,
  ``NR_arm = x_R + a_H x_H`` → ``x_R = NR_arm − a_H x_H`` (``x_H`` kept: in shipmmg ``x_R`` enters only
  ``N_R``), so every force shipmmg computes equals shipid's for the same flow;
* particulars and constants by name (``L`` → ``L_pp``, ``eps_R`` → ``ϵ``, ``kappa_R`` → ``κ``,
  ``f_alpha`` → ``f_α``, ``η = D_p / H_R``); the density is shipmmg's ``ρ`` argument.

Where the two codes differ, :attr:`ShipmmgExport.differences` names the term:

* the wake fraction at the propeller in a turn: shipid uses Yasukawa & Yoshimura's eq. 15
  (``1 − w_P = (1 − w_P0)(1 + (1 − exp(−C_1 |β_P|))(C_2 − 1))``), shipmmg ``w_P0 exp(−4 β_P²)``; the
  two agree only in a straight run;
* the drift angle and speed: shipmmg computes ``U`` and ``β`` from ``v − x_G r`` while its hull forces
  and equations of motion take ``v`` at midship; shipid uses the midship ``v`` throughout (they agree
  when ``x_G = 0``);
* terms shipmmg lacks: the optional sub-models of the particulars (rudder cross-flow, stall, side gain
  and slope, wind), each named when it is non-zero.
"""

from __future__ import annotations

import unicodedata
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from shipid.errors import InputError, ShipidError
from shipid.export.params import load
from shipid.export.source import Source
from shipid.models import mmg

#: shipid particular -> shipmmg basic parameter (copied unchanged).
BASIC_NAMES = {"L": "L_pp", "B": "B", "d": "d", "x_G": "x_G", "D_p": "D_p", "m": "m", "I_zG": "I_zG", "A_R": "A_R",
               "m_x": "m_x", "m_y": "m_y", "J_z": "J_z", "f_alpha": "f_α", "eps_R": "ϵ", "x_H": "x_H",
               "gamma_R_minus": "γ_R_minus", "gamma_R_plus": "γ_R_plus", "l_R": "l_R", "kappa_R": "κ",
               "w_P0": "w_P0", "x_P": "x_P"}
#: shipid hull coefficient -> shipmmg manoeuvring parameter.
HULL_NAMES = {"R_0": "R_0_dash", **{f"{m}_{s}": f"{m}_{s}_dash" for m in "XYN"
                                    for s in ("vv", "vr", "rr", "vvvv", "v", "r", "vvv", "vvr", "vrr", "rrr")}}
#: Optional sub-models of shipid's MMG particulars that shipmmg has no term for: key -> what it is.
OPTIONAL_TERMS = {"rudder_crossflow": "rudder cross-flow drag C_Dc in the normal force",
                  "rudder_crossflow_side": "rudder cross-flow drag differing per side",
                  "rudder_stall_plus": "rudder stall (alpha_R >= 0)", "rudder_stall_minus": "rudder stall (alpha_R < 0)",
                  "rudder_side_gain": "port/starboard rudder effectiveness F_N (1 + s sign(delta))",
                  "rudder_side_slope": "port/starboard rudder effectiveness F_N (1 + k delta)",
                  "A_T": "wind forces (Fujiwara regression)"}


@dataclass(frozen=True)
class ShipmmgExport:
    """An MMG model mapped onto shipmmg's parameters.

    Attributes
    ----------
    basic, maneuvering : dict of str to float
        Keyword arguments of ``Mmg3DofBasicParams`` and ``Mmg3DofManeuveringParams``.
    rho : float
        Water density for shipmmg's ``ρ`` argument.
    differences : tuple of str
        The terms that make shipmmg's forces differ from shipid's (module docstring).
    """

    basic: dict
    maneuvering: dict
    rho: float
    differences: tuple = ()
    model: str = ""
    notes: tuple = field(default_factory=tuple)

    def objects(self) -> tuple[Any, Any]:
        """``(Mmg3DofBasicParams, Mmg3DofManeuveringParams)`` (needs ``pip install shipid[shipmmg]``)."""
        try:
            from shipmmg.mmg_3dof import Mmg3DofBasicParams, Mmg3DofManeuveringParams
        except ImportError:
            raise ShipidError("shipmmg is not installed: pip install 'shipid[shipmmg]' (or pip install shipmmg)") from None
        return Mmg3DofBasicParams(**self.basic), Mmg3DofManeuveringParams(**self.maneuvering)

    def simulate(self, t: np.ndarray, delta: np.ndarray, rps: np.ndarray, speed: float, **kw) -> np.ndarray:
        """shipmmg's ``simulate_mmg_3dof`` on the grid ``t``: ``(n, 6)`` states ``[x, y, ψ, u, v, r]``.

        Inputs on the grid (rad, rev/s), start from the straight run at ``speed``; ``solve_ivp`` with
        ``rtol`` 1e-8, ``atol`` 1e-10 and a step no longer than the grid's unless ``kw`` says otherwise.
        """
        from shipmmg.mmg_3dof import simulate_mmg_3dof
        basic, man = self.objects()
        kw.setdefault("rtol", 1e-8)
        kw.setdefault("atol", 1e-10)
        # shipmmg integrates δ and n as states driven by the spline's derivative: a step longer than the
        # grid can step over a rudder ramp that starts from rest (an equilibrium) and never see it
        kw.setdefault("max_step", float(np.min(np.diff(t))))
        sol = simulate_mmg_3dof(basic, man, list(t), list(delta), list(rps), u0=float(speed), ρ=self.rho, **kw)
        u, v, r, x, y, psi = sol.sol(np.asarray(t))[:6]
        return np.column_stack([x, y, psi, u, v, r])

    def summary(self) -> str:
        """The parameters and the differing terms (what ``shipid export shipmmg`` prints)."""
        lines = [f"{self.model}: shipmmg.mmg_3dof parameters (rho {self.rho:g} kg/m^3)", "Mmg3DofBasicParams:"]
        lines += [f"  {k:10s} {v: .6g}" for k, v in self.basic.items()]
        lines.append("Mmg3DofManeuveringParams:")
        lines += [f"  {k:12s} {v: .6g}" for k, v in self.maneuvering.items()]
        if self.differences:
            lines.append("terms where shipmmg differs from shipid:")
            lines += [f"  - {d}" for d in self.differences]
        else:
            lines.append("no term differs: shipmmg computes the same forces")
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        return {"model": self.model, "basic": dict(self.basic), "maneuvering": dict(self.maneuvering), "rho": self.rho,
                "differences": list(self.differences), "notes": list(self.notes)}


def _ident(name: str) -> str:
    """``name`` as Python spells it as an identifier (NFKC: shipmmg's ``ϵ`` is the field ``ε``)."""
    return unicodedata.normalize("NFKC", name)


def to_shipmmg(spec: Any) -> ShipmmgExport:
    """The shipmmg parameters of an MMG model of the ``yasukawa2015`` structures (module docstring).

    Raises
    ------
    InputError
        For a model of another family or structure (shipmmg codes only the MMG standard method).
    """
    src: Source = load(spec)
    if src.family != "mmg":
        raise InputError(f"{src.name!r} is a model of the {src.family} family; shipmmg takes MMG models")
    model = src.model
    if model.structure != "yasukawa2015":
        raise InputError(f"MMG structure {model.structure!r} has no shipmmg form: shipmmg codes the MMG standard "
                         "method (shipid structure yasukawa2015); the low-speed Esso hull, its propeller and "
                         "rudder sub-models have no counterpart there")
    p, c = model.particulars, model.coef
    basic = {_ident(dst): float(p[k]) for k, dst in BASIC_NAMES.items()}
    basic[_ident("η")] = float(p["D_p"] / p["H_R"])
    basic["t_P"] = float(1.0 - c["XP_gain"])
    basic["t_R"] = float(1.0 - c["XR_gain"])
    basic["a_H"] = float(c["YR_gain"] - 1.0)
    basic["x_R"] = float(c["NR_arm"] - basic["a_H"] * p["x_H"])
    man = {"k_0": float(p["k_0"]), "k_1": float(p["k_1"]), "k_2": float(p["k_2"])}
    man.update({dst: float(c[k]) for k, dst in HULL_NAMES.items() if k in c})
    diff = []
    if not (p.get("C_2_plus", 1.0) == 1.0 and p.get("C_2_minus", 1.0) == 1.0) and p["w_P0"] != 0:
        diff.append("wake fraction in a turn: shipid 1 - w_P = (1 - w_P0)(1 + (1 - exp(-C_1|beta_P|))(C_2 - 1)) "
                    f"(Yasukawa & Yoshimura 2015 eq. 15; C_1 {p.get('C_1', float('nan')):g}, C_2 "
                    f"{p.get('C_2_plus', float('nan')):g}/{p.get('C_2_minus', float('nan')):g}); shipmmg "
                    "w_P = w_P0 exp(-4 beta_P^2)")
    if p["x_G"] != 0:
        diff.append(f"drift angle and speed: shipmmg takes U and beta from v - x_G r (x_G {p['x_G']:g} m), its hull "
                    "forces from the midship v; shipid uses the midship v throughout")
    for k, what in OPTIONAL_TERMS.items():
        v = p.get(k)
        if v is not None and np.any(np.asarray(v, dtype=float) != 0):
            diff.append(f"{k}: {what}, not in shipmmg")
    notes = ("shipmmg interpolates the rudder and propeller inputs with a cubic spline and integrates with "
             "solve_ivp; shipid holds them over each step and integrates with RK4",)
    return ShipmmgExport(basic, man, float(p["rho"]), tuple(diff), src.name, notes)


__all__ = ["ShipmmgExport", "to_shipmmg", "BASIC_NAMES", "HULL_NAMES", "OPTIONAL_TERMS"]
