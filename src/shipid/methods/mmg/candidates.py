"""Candidate structures of the MMG step-2 regression, chosen among by cross-validation.

A candidate is a set of free coefficients per mode (the rest stay at the prior model's
values), optionally a different hull structure (``structure``), a regression weighting
(``weighting``, :func:`shipid.methods.mmg.estimator.row_weights`) and particular
overrides (``particulars``, e.g. a symmetric flow-straightening γ_R). The lists are full
factorial designs over axes fixed a priori; the reasons for each axis are in
``docs/validation/mmg.md``. For the Esso low-speed structure the default selection also scores the
port/starboard (:mod:`shipid.methods.mmg.candidates_asym`) and surge
(:mod:`shipid.methods.mmg.candidates_surge`) variants of the best (:mod:`shipid.methods.mmg.staged`).
"""

from __future__ import annotations

from dataclasses import replace as _replace
from typing import TYPE_CHECKING, Mapping

from shipid.models import mmg

if TYPE_CHECKING:
    from shipid.methods.mmg.estimator import FitConfig

# The candidate lists below were fixed a priori from physics and training-run evidence only;
# see docs/validation/mmg.md ("Frozen held-out studies") for the reasons of each axis. They are full factorial designs over their axes, so that
# no combination is in or out because of how it scored on a test run.
_ESSO_FREE = {
    # hull only: propeller and rudder stay at the published values (identified by their
    # authors from runs of this data set)
    "hull-only": {"X": ("X_0F", "X_0A", "X_vr"), "Y": ("Y_v", "Y_r", "CD_Y"), "N": ("N_v", "N_r", "CD_N")},
    # hull + ahead thrust (K_T polynomial) + rudder force gain and lever arm; the astern
    # (Hachii) thrust and Ueno side-force polynomials stay fixed: rarely excited
    "hull+rudder+thrust": {"X": ("X_0F", "X_0A", "X_vr", "XP_k0", "XP_k1", "XP_k2", "XR_gain"),
                           "Y": ("Y_v", "Y_r", "CD_Y", "YR_gain"), "N": ("N_v", "N_r", "CD_N", "NR_arm")},
    # every coefficient of the structure free (4-quadrant propeller included)
    "hull+rudder+4-quadrant-propeller": dict(mmg.COEFS["esso-lowspeed"]),
}
_CUBIC_HULL = {"X": ("R_0", "X_vv", "X_vr", "X_rr", "X_vvvv"),
               "Y": ("Y_v", "Y_r", "Y_vvv", "Y_vvr", "Y_vrr", "Y_rrr"),
               "N": ("N_v", "N_r", "N_vvv", "N_vvr", "N_vrr", "N_rrr")}


def _esso_candidates() -> dict[str, dict]:
    """Hull structure (low-speed | cubic) x free set (3) x regression weighting (2): 12 candidates."""
    out: dict[str, dict] = {}
    for weighting in ("none", "nondimensional"):
        for hull in ("lowspeed", "cubic"):
            for free_name, free in _ESSO_FREE.items():
                if hull == "lowspeed":
                    cand: dict = dict(free)
                    name = free_name
                else:
                    # same propeller/rudder coefficients free, the hull replaced by the cubic expansion
                    nh = {"X": 3, "Y": 3, "N": 3}
                    cand = {m: _CUBIC_HULL[m] + tuple(free[m][nh[m]:]) for m in mmg.MODES}
                    cand["structure"] = "esso-cubic-hull"
                    name = "cubic-" + free_name
                if weighting != "none":
                    cand["weighting"] = weighting
                    name += "/" + weighting
                out[name] = cand
    # the default (first) candidate: the structure of the published set with its own free set
    first = "hull+rudder+thrust"
    return {first: out.pop(first), **out}


def _yasukawa_candidates() -> dict[str, dict]:
    """Free set (3) x flow-straightening gamma_R (prior's asymmetric | symmetric mean): 6 candidates."""
    base = {
        "full": {m: mmg.COEFS["yasukawa2015"][m] for m in mmg.MODES},
        "linear-hull+rudder": {"X": ("R_0", "X_vv", "X_vr", "X_rr", "XP_gain", "XR_gain"),
                               "Y": ("Y_v", "Y_r", "YR_gain"), "N": ("N_v", "N_r", "NR_arm")},
        "hull-only": dict(_CUBIC_HULL),
    }
    out = dict(base)
    for name, cand in base.items():
        out[name + "/symmetric-gamma_R"] = dict(cand, particulars={"gamma_R": "symmetric"})
    return out


#: Candidate structures (sets of free coefficients, hull structure, regression weighting,
#: particular overrides) per prior structure; the first is the default.
CANDIDATES: dict[str, dict[str, dict]] = {"esso-lowspeed": _esso_candidates(),
                                          "yasukawa2015": _yasukawa_candidates()}


def candidate_config(config: "FitConfig", cand: Mapping) -> "FitConfig":
    """The fit settings of a candidate: its ``weighting``, ``equation`` and ``window_s``, where it has them,
    replace the default's."""
    over = {k: cand[k] for k in ("weighting", "equation", "window_s") if k in cand}
    return _replace(config, **over) if over else config


def apply_candidate(prior: mmg.MmgModel, cand: Mapping) -> tuple[mmg.MmgModel, dict[str, tuple[str, ...]]]:
    """The prior with a candidate's particular overrides applied, and its free coefficients per mode."""
    free = {m: tuple(cand[m]) for m in mmg.MODES}
    st = cand.get("structure")
    if st and st != prior.structure:
        # change of hull structure: every hull coefficient of the new one is free; the values
        # needed to build the model are zeros until the regression sets them
        coef = {c: prior.coef.get(c, 0.0) for m in mmg.MODES for c in mmg.COEFS[st][m]}
        prior = _replace(prior, structure=st, coef=coef, name=f"{prior.name} ({st})")
    over = cand.get("particulars") or {}
    if not over:
        return prior, free
    p = dict(prior.particulars)
    for k, v in over.items():
        if k == "gamma_R" and v == "symmetric":
            g = 0.5 * (p["gamma_R_minus"] + p["gamma_R_plus"])
            p["gamma_R_minus"] = p["gamma_R_plus"] = g
        elif k == "gamma_R_asymmetry":              # fraction of the prior's asymmetry kept about the mean
            g, h = 0.5 * (p["gamma_R_minus"] + p["gamma_R_plus"]), 0.5 * (p["gamma_R_plus"] - p["gamma_R_minus"])
            p["gamma_R_minus"], p["gamma_R_plus"] = g - float(v) * h, g + float(v) * h
        else:
            p[k] = float(v)
    return _replace(prior, particulars=p), free


__all__ = ["CANDIDATES", "apply_candidate", "candidate_config"]
