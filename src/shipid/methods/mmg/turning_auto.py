"""An automatic structure selection for turning (KVLCC2): ``identify mmg --selection turning-auto``.

:func:`select_auto` is a ``selector`` of :func:`shipid.methods.mmg.pipeline.identify`:

1. **Guard for few runs.** The peak-yaw-rate criterion of
   :func:`shipid.methods.mmg.turning_selection.select_for_turning` is used only when the training
   runs hold at least :data:`MIN_PEAK_RUNS` runs whose peaks enter it (switch heading ≥
   :data:`~shipid.methods.mmg.turning_selection.MIN_SWITCH_DEG`, or angles unknown) at at least
   :data:`MIN_PEAK_ANGLES` distinct rudder angles; otherwise the default selection
   (:func:`shipid.methods.mmg.pipeline.select_structure`: 60-s restarted horizons over the
   candidates :data:`shipid.methods.mmg.candidates.CANDIDATES`) is returned unchanged. (Four runs
   give eight left-out side peaks; two angles are the least that show how the turn grows with the
   rudder.)
2. **Default first.** The default selection is made on the same runs (``d``, its choice among the
   candidates by the horizon criterion).
3. **Peak criterion under a heading constraint.** Among
   :data:`~shipid.methods.mmg.turning_selection.TURNING_CANDIDATES`, scored by the same leave-one-run-out
   open-loop replays (``select_for_turning``, criterion ``"peak"``), the candidate with the lowest RMS
   peak-yaw-rate error is chosen among those whose pooled whole-run heading RMS is at most
   :data:`PSI_TOLERANCE` times that of ``d`` in the same table (``d`` itself always qualifies): a better
   turn is not bought with more than half again the heading error of the default over the whole record.

Whether this should be the default for turning-capable data was tested by a nested cross-validation by
rudder angle on HSVA zig-zags; it was not adopted (``docs/validation/mmg.md``, "KVLCC2 HSVA
zig-zags", "Automatic selection, nested CV by rudder angle").
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from shipid.io.trial import Trial
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import turning_selection as TS
from shipid.methods.mmg.candidates import CANDIDATES
from shipid.methods.mmg.pipeline import horizon_method, select_structure
from shipid.methods.mmg.turning_selection import MIN_SWITCH_DEG
from shipid.models import mmg

#: Least number of training runs whose peak yaw rates enter the criterion (guard, rule 1).
MIN_PEAK_RUNS = 4
#: Least number of distinct rudder angles among them (guard, rule 1).
MIN_PEAK_ANGLES = 2
#: Largest ratio of a candidate's inner-CV heading RMS to the default choice's (rule 3).
PSI_TOLERANCE = 1.5


def guard(trials: Sequence[Trial]) -> tuple[bool, str]:
    """Rule 1: may the peak criterion decide on these runs? ``(ok, reason)``."""
    use = TS.peak_runs(trials)
    rudder = [None if a is None else float(np.degrees(a[0])) for a in map(TS.trial_angles, trials)]
    ang = {a for a, u in zip(rudder, use) if u and a is not None}
    n = int(sum(use))
    unknown = sum(1 for a, u in zip(rudder, use) if u and a is None)
    k = len(ang) + (1 if unknown else 0)
    ok = n >= MIN_PEAK_RUNS and k >= MIN_PEAK_ANGLES
    return ok, (f"{n} runs with switch >= {MIN_SWITCH_DEG:g} deg at {k} rudder angle(s) (needs {MIN_PEAK_RUNS} "
                f"at {MIN_PEAK_ANGLES})")


def select_auto(trials: Sequence[Trial], runs: Sequence[R.SmoothedRun], prior: mmg.MmgModel,
                candidates: Mapping[str, Mapping] | None = None, config: R.FitConfig = R.FitConfig(),
                folds: int | None = None) -> tuple[str, dict[str, dict], str]:
    """The automatic selection (module docstring, rules 1–3); ``selector`` of
    :func:`shipid.methods.mmg.pipeline.identify`. ``candidates`` default the turning candidates of the
    prior's structure; the default selection uses those of them in :data:`~shipid.methods.mmg.candidates.CANDIDATES`. Returns name, table, method line."""
    cands = TS.TURNING_CANDIDATES[prior.structure] if candidates is None else candidates
    frozen = {k: v for k, v in CANDIDATES[prior.structure].items() if k in cands}
    d, dtable = select_structure(trials, runs, prior, frozen, config=config, folds=folds)
    ok, why = guard(trials)
    hmethod = horizon_method(folds)
    if not ok:
        return d, dtable, f"{hmethod} (turning criterion not used: {why})"
    best, table, method = TS.select_for_turning(trials, runs, prior, cands, config, folds, criterion="peak")
    limit = PSI_TOLERANCE * table[d]["psi_rms"]
    for c, row in table.items():
        row["horizon_score"] = dtable[c]["score"] if c in dtable else float("nan")
        row["within_heading_limit"] = bool(row["psi_rms"] <= limit)
    ok_c = [c for c in table if table[c]["within_heading_limit"] and np.isfinite(table[c]["score"])] or [d]
    chosen = min(ok_c, key=lambda c: table[c]["score"])
    return chosen, table, (f"{method}; among candidates with heading RMS <= {PSI_TOLERANCE:g} x that of the "
                           f"horizon-CV choice '{d}' ({limit:.2f} deg); {why}")


__all__ = ["MIN_PEAK_RUNS", "MIN_PEAK_ANGLES", "PSI_TOLERANCE", "guard", "select_auto"]
