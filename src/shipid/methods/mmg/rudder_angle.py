"""Angle-dependent rudder terms for the KVLCC2: the candidate of ``identify mmg --selection rudder-angle``.

The optional terms are those of :mod:`shipid.models.mmg_forces`
(:data:`~shipid.models.mmg_forces.RUDDER_LARGE_ANGLE`): a stall per inflow side, the cross-flow part
per side, and a port/starboard effectiveness growing with the rudder angle; against them the
default rudder and the constant side gain ``rudder_side_gain``.

Candidates (:func:`candidates`, fixed a priori; every one on the free set and flow straightening
:data:`BASE`, ``linear-hull+rudder/symmetric-gamma_R``; ``C_Dc = 1`` after Hoerner, Fluid-Dynamic Lift
1985 ch. 3, not tuned):

* ``default`` — the standard ``f_α sin α_R``;
* ``cf`` — with the cross-flow part ``C_Dc sin α_R |sin α_R|``;
* ``cf/side-gain`` — and ``F_N (1 + s sign δ)``, ``s`` calibrated (the constant side gain);
* ``side-slope``, ``cf/side-slope`` — ``F_N (1 + k δ)``, ``k`` calibrated (the side difference grows
  with ``|δ|``);
* ``cf/crossflow-side`` — ``C_Dc (1 ± b)`` on the ``α_R ≷ 0`` side, ``b`` calibrated;
* ``cf/stall-plus`` — an effective stall angle on the ``α_R > 0`` (starboard-turn) side, calibrated.

A calibrated parameter is chosen on the training runs only, by the peak criterion of
:func:`shipid.methods.mmg.turning_selection.calibrate_folds` (RMS over the training zig-zags with switch
≥ 5° and both sides of the open-loop peak-yaw-rate error, %; the grid :data:`GRIDS` of the parameter
refined by a parabola's vertex). ``--selection rudder-angle`` fits :data:`CHOSEN`, ``cf/crossflow-side``,
the candidate a forward cross-validation by rudder angle chose on the HSVA zig-zags (trained on the
smaller angles, scored on the larger ones: peak-yaw-rate error per side and whole-run heading error of
open-loop replays); its table, the decision rule and what it showed: ``docs/validation/mmg.md``,
"KVLCC2 HSVA zig-zags", "Angle-dependent rudder terms".
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import turning_selection as TS
from shipid.methods.mmg.candidates import CANDIDATES
from shipid.models import mmg

#: Base candidate of every row (module docstring).
BASE = "linear-hull+rudder/symmetric-gamma_R"
#: Calibration grids per parameter: side slope k (1/rad), cross-flow side b, stall angle (rad).
SLOPE_GRID = (-0.4, -0.3, -0.2, -0.1, 0.0, 0.1, 0.2)
CROSSFLOW_SIDE_GRID = (-1.0, -0.75, -0.5, -0.25, 0.0, 0.25, 0.5)
STALL_GRID = tuple(np.deg2rad([10.0, 15.0, 20.0, 25.0, 30.0, 40.0, 60.0]).tolist())
GRIDS = {"rudder_side_gain": TS.SIDE_GAIN_GRID, "rudder_side_slope": SLOPE_GRID,
         "rudder_crossflow_side": CROSSFLOW_SIDE_GRID, "rudder_stall_plus": STALL_GRID}


def candidates(base_name: str = BASE) -> dict[str, dict]:
    """The candidates of the module docstring (``calibrate``: the particular calibrated on the training runs),
    on the frozen candidate ``base_name`` (default :data:`BASE`)."""
    base = CANDIDATES["yasukawa2015"][base_name]
    part = dict(base.get("particulars") or {})
    cf = dict(base, particulars=dict(part, rudder_crossflow=1.0))
    cal = TS.CALIBRATE
    return {"default": dict(base), "cf": cf, "cf/side-gain": dict(cf, **{cal: "rudder_side_gain"}),
            "side-slope": dict(base, **{cal: "rudder_side_slope"}), "cf/side-slope": dict(cf, **{cal: "rudder_side_slope"}),
            "cf/crossflow-side": dict(cf, **{cal: "rudder_crossflow_side"}),
            "cf/stall-plus": dict(cf, **{cal: "rudder_stall_plus"})}


#: The candidate ``shipid identify mmg --selection rudder-angle`` fits (module docstring).
CHOSEN = "cf/crossflow-side"


def resolve(trials, runs, prior: mmg.MmgModel, cand: Mapping, config: R.FitConfig = R.FitConfig()):
    """:func:`shipid.methods.mmg.turning_selection.resolve` on the grid of the calibrated particular
    (:data:`GRIDS`); the ``resolve`` of :func:`shipid.methods.mmg.pipeline.identify`."""
    par = cand.get(TS.CALIBRATE)
    return TS.resolve(trials, runs, prior, cand, config, grid=GRIDS[par] if par else TS.SIDE_GAIN_GRID)


__all__ = ["CHOSEN", "resolve", "BASE", "SLOPE_GRID", "CROSSFLOW_SIDE_GRID", "STALL_GRID", "GRIDS", "candidates"]
