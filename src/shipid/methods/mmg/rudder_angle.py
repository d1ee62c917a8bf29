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

:func:`select_manoeuvres` is the structure selection of ``identify mmg --selection manoeuvres`` (the
default for the Yasukawa-2015 structure): a forward cross-validation by rudder angle on the training runs
among :data:`MANOEUVRE_ROWS` (the horizon selection's choice, this module's :data:`CHOSEN`, each also
with the integral step-2 form), decided by the rule of its docstring.
"""

from __future__ import annotations

import math
from typing import Mapping, Sequence

import numpy as np

from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import turning_selection as TS
from shipid.io.trial import Trial
from shipid.methods.mmg.candidates import CANDIDATES
from shipid.methods.mmg.pipeline import horizon_method, select_structure
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


# ----------------------------------------------------------------------------- selection for manoeuvres
#: Least number of distinct rudder angles among the scored runs for the forward CV (rule 2).
MIN_ANGLES = 3
#: Most forward folds (rule 3): the cuts at the largest scored angles.
MAX_FOLDS = 3
#: Least number of distinct scored angles below a cut (rule 3).
MIN_BELOW = 2
#: Row names of the forward CV (rule 5): ``H`` stands for the horizon selection's choice.
INTEGRAL = "/integral"
RA_NAME = f"{BASE}/{CHOSEN}"
MANOEUVRE_ROWS = ("H", "H" + INTEGRAL, RA_NAME, RA_NAME + INTEGRAL)
CRITERION = "manoeuvres: forward CV by rudder angle"
RULE = ("forward CV by rudder angle on the training runs: each fold trains on the runs below a cut angle and "
        "scores the runs (switch >= 5 deg) at and above it, open-loop replay from execute with the measured "
        "rudder and propeller; fold score = RMS peak-yaw-rate error per side (%) + RMS whole-run heading RMS "
        "(deg); the lowest mean fold score wins if it is the horizon choice H or beats H in at least 2/3 of the "
        "folds (rounded up), else H; guard: >= 3 distinct rudder angles among the scored runs")


def manoeuvre_candidates(equation_given: bool = False, structure: str = "yasukawa2015") -> dict[str, dict]:
    """The candidates :func:`select_manoeuvres` chooses among: the frozen ones of the horizon selection, each
    with ``/integral`` (the integral step-2 form), and :data:`CHOSEN` (also with ``/integral``); without the
    integral rows where the step-2 form is given."""
    out = dict(CANDIDATES[structure])
    out[RA_NAME] = candidates()[CHOSEN]
    if not equation_given:
        for k in list(out):
            out[k + INTEGRAL] = dict(out[k], equation="integral")
    return out


def run_angles(trials: Sequence[Trial]) -> list[tuple[float, float | None]]:
    """``(rudder, switch)`` in deg per run (rule 1): from the file name, else the largest |δ| to the nearest
    degree and None."""
    out = []
    for tr in trials:
        a = TS.trial_angles(tr)
        if a is not None:
            out.append((round(float(np.degrees(a[0])), 6), float(np.degrees(a[1]))))
        else:
            d = np.asarray(tr["delta"], float)
            out.append((float(np.round(np.degrees(np.nanmax(np.abs(d))))), None))
    return out


def forward_folds(trials: Sequence[Trial]) -> tuple[list[tuple[float, list[int], list[int]]], str]:
    """The folds of rule 3 ``(cut angle, training indices, scored indices)`` (empty where the guard of rule 2
    fails) and a line saying what the runs hold."""
    ang = run_angles(trials)
    use = TS.peak_runs(trials)
    scored = sorted({a for (a, _), u in zip(ang, use) if u})
    why = (f"{sum(use)} runs with switch >= {TS.MIN_SWITCH_DEG:g} deg at {len(scored)} rudder angle(s) "
           f"({', '.join(f'{a:g}' for a in scored)} deg; needs {MIN_ANGLES})")
    if len(scored) < MIN_ANGLES:
        return [], why
    cuts = [a for i, a in enumerate(scored) if i >= MIN_BELOW][-MAX_FOLDS:]
    folds = [(a, [i for i, (b, _) in enumerate(ang) if b < a], [i for i, (b, _) in enumerate(ang) if b >= a and use[i]])
             for a in cuts]
    return folds, why


def _fold_row(res: Sequence[Mapping]) -> dict:
    pk = TS._peak_rms(res)
    psi = np.array([r["psi_rms"] for r in res], float)
    psi_rms = float(np.sqrt(np.mean(psi ** 2))) if psi.size and np.all(np.isfinite(psi)) else float("inf")
    sc = pk + psi_rms
    return {"score": float(sc) if np.isfinite(sc) else float("inf"), "r_peak_rms": pk, "psi_rms": psi_rms,
            "r_peak_stbd_mean_pct": float(np.mean([r["r_peak_stbd_err_pct"] for r in res])),
            "r_peak_port_mean_pct": float(np.mean([r["r_peak_port_err_pct"] for r in res]))}


def select_manoeuvres(trials: Sequence[Trial], runs: Sequence[R.SmoothedRun], prior: mmg.MmgModel,
                      candidates: Mapping[str, Mapping] | None = None, config: R.FitConfig = R.FitConfig(),
                      folds: int | None = None) -> tuple[str, dict, str, dict]:
    """Structure selection for standard manoeuvres (``docs/validation/mmg.md``, "Selection for manoeuvres"):

    1. the horizon selection (:func:`~shipid.methods.mmg.pipeline.select_structure`, ``folds``) over the
       frozen candidates in ``candidates`` chooses ``H``;
    2. where the training runs' zig-zags with switch ≥ 5° hold at least :data:`MIN_ANGLES` rudder angles
       (:func:`forward_folds`), the rows :data:`MANOEUVRE_ROWS` present in ``candidates`` are scored by a
       forward CV by rudder angle: each fold fits every row on the runs below its cut angle (a calibrated
       parameter calibrated on them only, :func:`~shipid.methods.mmg.turning_selection.calibrate_folds`) and
       replays the runs at and above it open loop from execute; fold score = RMS peak-yaw-rate error over
       runs and sides (%) + RMS whole-run heading RMS (deg);
    3. the row with the lowest mean fold score is chosen if it is ``H`` or scores lower than ``H`` in at least
       ⌈2k/3⌉ of the k folds; else ``H``.

    A ``selector`` of :func:`shipid.methods.mmg.pipeline.identify`; returns the chosen name, the table (per row
    the mean fold score, the folds better than ``H``), the method line and what else
    ``diagnostics["structure_selection"]`` records (criterion, rule, folds, horizon table, why)."""
    cands = candidates or manoeuvre_candidates(structure=prior.structure)
    frozen = {k: v for k, v in CANDIDATES[prior.structure].items() if k in cands}
    h, htable = select_structure(trials, runs, prior, frozen, config=config, folds=folds)
    fl, why_runs = forward_folds(trials)
    extra = {"criterion": CRITERION, "rule": RULE, "horizon_choice": h, "horizon_table": htable,
             "horizon_method": horizon_method(folds)}
    if not fl:
        extra.update(note=f"forward CV by rudder angle not run: {why_runs}; the horizon selection decides",
                     why=f"horizon selection (guard not met): {h}")
        return h, htable, horizon_method(folds) + " (forward CV by rudder angle not run)", extra
    names = {"H": h, "H" + INTEGRAL: h + INTEGRAL, RA_NAME: RA_NAME, RA_NAME + INTEGRAL: RA_NAME + INTEGRAL}
    rows = [(r, names[r]) for r in MANOEUVRE_ROWS if names[r] in cands]
    data = [TS.replay_data(tr) for tr in trials]
    use = TS.peak_runs(trials)
    sets = [tr_idx for _, tr_idx, _ in fl]
    reps, owner, cal = [], [], {}
    for r, cname in rows:
        cand = cands[cname]
        par = cand.get(TS.CALIBRATE)
        if par:
            cal[r] = [v for v, _ in TS.calibrate_folds(runs, data, use, prior, cand, sets, config=config,
                                                        grid=GRIDS[par], parameter=par)]
        for f, (_, tr_idx, sc_idx) in enumerate(fl):
            c = TS.with_asymmetry(cand, cal[r][f], par) if par else cand
            m = TS._fit([runs[i] for i in tr_idx], prior, c, config)
            for i in sc_idx:
                if m is not None:
                    reps.append((m, i))
                owner.append((r, f, m is not None))
    out = iter(TS.batch_replay(reps, data))
    per: dict = {}
    for r, f, ok in owner:
        per.setdefault((r, f), []).append(next(out) if ok else {"psi_rms": float("inf"),
                                                                "r_peak_stbd_err_pct": float("inf"),
                                                                "r_peak_port_err_pct": float("inf")})
    ftable = []
    ang = run_angles(trials)
    for f, (a, tr_idx, sc_idx) in enumerate(fl):
        ftable.append({"cut_deg": a, "train_angles_deg": sorted({ang[i][0] for i in tr_idx}),
                       "scored_angles_deg": sorted({ang[i][0] for i in sc_idx}),
                       "scored_runs": [str(trials[i].meta.get("source", i)) for i in sc_idx],
                       "rows": {names[r]: dict(_fold_row(per[(r, f)]), **({"calibrated": cal[r][f]} if r in cal else {}))
                                for r, _ in rows}})
    k = len(fl)
    need = math.ceil(2 * k / 3)
    table = {}
    for r, cname in rows:
        sc = [ft["rows"][cname]["score"] for ft in ftable]
        better = sum(1 for ft in ftable if ft["rows"][cname]["score"] < ft["rows"][h]["score"])
        table[cname] = {"score": float(np.mean(sc)), "fold_scores": sc, "folds_better_than_H": better,
                        "row": r}
    best = min(table, key=lambda c: table[c]["score"])
    chosen = best if best == h or table[best]["folds_better_than_H"] >= need else h
    hs = table[h]["score"]
    if chosen == h and best == h:
        why = f"lowest mean fold score {hs:.2f}: the horizon choice '{h}'"
    elif chosen == h:
        why = (f"lowest mean fold score {table[best]['score']:.2f} ('{best}') beats the horizon choice '{h}' "
               f"({hs:.2f}) in {table[best]['folds_better_than_H']} of {k} folds, fewer than {need}: '{h}' kept")
    else:
        why = (f"lowest mean fold score {table[best]['score']:.2f} ('{best}') against {hs:.2f} for the horizon "
               f"choice '{h}', lower in {table[best]['folds_better_than_H']} of {k} folds (needs {need})")
    extra.update(folds=ftable, why=why, runs=why_runs)
    cuts = ", ".join(f"{ft['cut_deg']:g}" for ft in ftable)
    method = (f"forward CV by rudder angle on the training runs ({k} folds, cuts at {cuts} deg); "
              f"H = {horizon_method(folds)}")
    return chosen, table, method, extra


__all__ = ["select_manoeuvres", "manoeuvre_candidates", "run_angles", "forward_folds", "MIN_ANGLES", "MAX_FOLDS",
           "MIN_BELOW", "MANOEUVRE_ROWS", "RA_NAME", "INTEGRAL", "CRITERION", "RULE", "CHOSEN", "resolve", "BASE", "SLOPE_GRID", "CROSSFLOW_SIDE_GRID", "STALL_GRID", "GRIDS", "candidates"]
