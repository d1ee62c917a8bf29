"""Port/starboard variants of the Esso candidate structures (structure ``esso-lowspeed-asym``).

The training runs' 60-s restarted horizons of the straight approach of the turning runs
(rudder near zero, propeller ahead) drift to starboard in the simulation of the regression +
output-error model, in nearly every run (4-fold CV on the 32 training runs of the Esso Osaka 9-run split,
``docs/validation/mmg.md``): a yaw moment at zero rudder that the low-speed model
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
kept is chosen by the staged training-run CV of :func:`shipid.methods.mmg.staged.select_staged`.
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


def with_terms(cand: Mapping, extra: Mapping[str, tuple[str, ...]], structure: str,
               bases: tuple[str, ...] = ("esso-lowspeed",)) -> dict:
    """``cand`` moved to ``structure`` with the free coefficients ``extra[mode]`` added to each mode;
    ``cand`` must be on one of the ``bases`` structures (default ``esso-lowspeed``)."""
    st = cand.get("structure", "esso-lowspeed")
    if st not in bases:
        raise ValueError(f"{structure} variants are defined for the {' / '.join(bases)} hull, not {st}")
    out = dict(cand)
    for m in mmg.MODES:
        out[m] = tuple(cand[m]) + tuple(extra[m])
    out["structure"] = structure
    return out


def asym_variant(cand: Mapping, terms: str) -> dict:
    """``cand`` on the ``esso-lowspeed-asym`` structure with the free coefficients of ``ASYM_TERMS[terms]`` added."""
    return with_terms(cand, ASYM_TERMS[terms], STRUCTURE)


def asym_variants(name: str, cand: Mapping) -> dict[str, dict]:
    """``{name + "+" + terms: variant}`` for every entry of :data:`ASYM_TERMS`."""
    return {f"{name}+{t}": asym_variant(cand, t) for t in ASYM_TERMS}


__all__ = ["STRUCTURE", "ASYM_TERMS", "with_terms", "asym_variant", "asym_variants"]
