"""Surge and slipstream-rudder variants of the Esso candidate structures (structure ``esso-lowspeed-ext``).

Diagnosis from the 4-fold CV residuals of the 32 training runs of the Esso Osaka 9-run split
(``docs/validation/mmg.md``; regression + output error of
``hull+rudder+thrust/nondimensional+prop-side``): the 60-s position error grows with the
propeller rate, from 0.3–0.7 m at n ≤ 10 1/s to 1.0–2.8 m in the four zig-zags at
n ≈ 14–16 1/s; there it is partly along-track (a surge-speed error, 0.8–1.6 m) and mostly
cross-track, from heading errors of 12–17° (yaw-rate RMS 0.7–0.9°/s against 0.2–0.4°/s at
n ≈ 10). Both point at forces that the low-speed model scales with the hull speed but that
grow with the propeller rate: the rudder in the slipstream and its drag, and the surge
hull terms of drift and turning. The terms are those of
:data:`shipid.models.mmg_esso_ext.EXT_COEFS` (zero in the published model):

``surge-hull``
    ``X_vv``, ``X_rr``: speed loss in drift and turning;
``rudder-drag``
    ``XR_D``: the rudder's profile drag in its own inflow;
``rudder-slipstream``
    ``XR_s``, ``YR_s``, ``NR_s``: the rudder force gain on the slipstream share of the
    rudder inflow (a propeller-rate-dependent rudder inflow);
``wind-gain``
    ``XW_g``, ``YW_g``, ``NW_g``: gains on the three components of the fixed air force
    (the runs are in 1.5–2.4 m/s mean wind at 0.2–0.35 m/s ship speed; added after the
    first five variants scored within 0.01 of the base).

:func:`surge_variants` adds them (alone and combined, a fixed list) to a candidate of
``esso-lowspeed`` or ``esso-lowspeed-asym``; which (if any) is kept is chosen by the
staged training-run CV of :func:`shipid.methods.mmg.staged.select_staged`.
"""

from __future__ import annotations

from typing import Mapping

from shipid.methods.mmg.candidates_asym import with_terms
from shipid.models import mmg

STRUCTURE = "esso-lowspeed-ext"
#: The structures whose candidates :func:`surge_variant` extends.
BASE_STRUCTURES = ("esso-lowspeed", "esso-lowspeed-asym")
_TERMS = {
    "surge-hull": {"X": ("X_vv", "X_rr"), "Y": (), "N": ()},
    "rudder-drag": {"X": ("XR_D",), "Y": (), "N": ()},
    "rudder-slipstream": {"X": ("XR_s",), "Y": ("YR_s",), "N": ("NR_s",)},
    "wind-gain": {"X": ("XW_g",), "Y": ("YW_g",), "N": ("NW_g",)},
}


def _combine(*names: str) -> dict[str, tuple[str, ...]]:
    return {m: sum((_TERMS[k][m] for k in names), ()) for m in mmg.MODES}


#: The extra free coefficients of each variant (fixed list: each term alone, surge hull with the
#: slipstream rudder, all three; the wind gains alone and with the surge hull).
SURGE_TERMS: dict[str, dict[str, tuple[str, ...]]] = {
    "surge-hull": _combine("surge-hull"),
    "rudder-drag": _combine("rudder-drag"),
    "rudder-slipstream": _combine("rudder-slipstream"),
    "surge-hull+rudder-slipstream": _combine("surge-hull", "rudder-slipstream"),
    "surge-hull+rudder-drag+rudder-slipstream": _combine("surge-hull", "rudder-drag", "rudder-slipstream"),
    "wind-gain": _combine("wind-gain"),
    "surge-hull+wind-gain": _combine("surge-hull", "wind-gain"),
}


def surge_variant(cand: Mapping, terms: str) -> dict:
    """``cand`` on the ``esso-lowspeed-ext`` structure with the free coefficients of ``SURGE_TERMS[terms]`` added."""
    return with_terms(cand, SURGE_TERMS[terms], STRUCTURE, BASE_STRUCTURES)


def surge_variants(name: str, cand: Mapping) -> dict[str, dict]:
    """``{name + "+" + terms: variant}`` for every entry of :data:`SURGE_TERMS`."""
    return {f"{name}+{t}": surge_variant(cand, t) for t in SURGE_TERMS}


__all__ = ["STRUCTURE", "BASE_STRUCTURES", "SURGE_TERMS", "surge_variant", "surge_variants"]
