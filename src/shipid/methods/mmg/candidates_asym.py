"""Port/starboard variants of the Esso candidate structures (structure ``esso-lowspeed-asym``).

The training runs' 60-s restarted horizons of the straight approach of the turning runs
(rudder near zero, propeller ahead) drift to starboard in the simulation of the regression +
output-error model, in nearly every run (4-fold CV on the 32 training runs of the 9-run split,
:mod:`shipid.methods.mmg.study_oe`): a yaw moment at zero rudder that the low-speed model
lacks. Two physical sources, each one pair of terms of
:data:`shipid.models.mmg.COEFS` ``["esso-lowspeed-asym"]`` (zero in the published model):

``prop-side``
    the side force and moment of the single ahead-turning propeller, ``∝ ρ n² D⁴``
    (``YP_n``, ``NP_n``);
``rudder-offset``
    a constant offset of the rudder's zero or of the inflow angle at the rudder, i.e. the
    normal-force slope times a constant angle (``YR_0``, ``NR_0``).

:func:`asym_variants` adds one, the other or both to a candidate of
:data:`shipid.methods.mmg.candidates.CANDIDATES` ``["esso-lowspeed"]``; which (if any) is
kept is chosen by the training-run CV of :func:`shipid.methods.mmg.study_oe.cv_refinement`.
"""

from __future__ import annotations

from typing import Mapping

from shipid.models import mmg

STRUCTURE = "esso-lowspeed-asym"
#: The extra free coefficients of each variant, per mode.
ASYM_TERMS: dict[str, dict[str, tuple[str, ...]]] = {
    "prop-side": {"X": (), "Y": ("YP_n",), "N": ("NP_n",)},
    "rudder-offset": {"X": (), "Y": ("YR_0",), "N": ("NR_0",)},
    "prop-side+rudder-offset": {"X": (), "Y": ("YP_n", "YR_0"), "N": ("NP_n", "NR_0")},
}


def asym_variant(cand: Mapping, terms: str) -> dict:
    """``cand`` on the ``esso-lowspeed-asym`` structure with the free coefficients of ``ASYM_TERMS[terms]`` added."""
    if cand.get("structure", "esso-lowspeed") != "esso-lowspeed":
        raise ValueError(f"asymmetry variants are defined for the esso-lowspeed hull, not {cand.get('structure')}")
    out = dict(cand)
    for m in mmg.MODES:
        out[m] = tuple(cand[m]) + ASYM_TERMS[terms][m]
    out["structure"] = STRUCTURE
    return out


def asym_variants(name: str, cand: Mapping) -> dict[str, dict]:
    """``{name + "+" + terms: variant}`` for every entry of :data:`ASYM_TERMS`."""
    return {f"{name}+{t}": asym_variant(cand, t) for t in ASYM_TERMS}


__all__ = ["STRUCTURE", "ASYM_TERMS", "asym_variant", "asym_variants"]
