"""Angle-dependent rudder terms for the KVLCC2 at large rudder angles, chosen by a CV that only extrapolates in angle.

Question: which rudder normal-force model, fitted on small-angle zig-zags, predicts the larger-angle
ones best on each side? The optional terms are those of :mod:`shipid.models.mmg_forces`
(:data:`~shipid.models.mmg_forces.RUDDER_LARGE_ANGLE`): a stall per inflow side, the cross-flow part
per side, and a port/starboard effectiveness growing with the rudder angle; against them the
default rudder and the constant side gain of :mod:`shipid.methods.mmg.side_calibration`.

Candidates (:func:`candidates`, fixed a priori; every one on the free set and flow straightening the
default selection chose in five of the six folds of :mod:`shipid.methods.mmg.turning_nested`,
``linear-hull+rudder/symmetric-gamma_R``; ``C_Dc = 1`` after Hoerner 1985 ch. 3, not tuned):

* ``default`` — the standard ``f_α sin α_R``;
* ``cf`` — with the cross-flow part ``C_Dc sin α_R |sin α_R|``;
* ``cf/side-gain`` — and ``F_N (1 + s sign δ)``, ``s`` calibrated (the constant side gain);
* ``side-slope``, ``cf/side-slope`` — ``F_N (1 + k δ)``, ``k`` calibrated (the side difference grows
  with ``|δ|``);
* ``cf/crossflow-side`` — ``C_Dc (1 ± b)`` on the ``α_R ≷ 0`` side, ``b`` calibrated;
* ``cf/stall-plus`` — an effective stall angle on the ``α_R > 0`` (starboard-turn) side, calibrated.

A calibrated parameter is chosen on the fold's TRAINING runs only, by the criterion of
:func:`shipid.methods.mmg.side_calibration.calibrate` (RMS over the training zig-zags with switch ≥ 5°
and both sides of the open-loop peak-yaw-rate error, %; a grid refined by a parabola's vertex;
:func:`shipid.methods.mmg.turning_selection.calibrate_folds`).

Cross-validation (stated, with the rule below, before any score was computed): forward folds over the
HSVA zig-zags by rudder angle (:data:`FOLDS`), each trained on all runs below an angle and scored on
all runs above it, so that every prediction extrapolates in angle: train 10°–15° → score 20°–35°;
train 10°–20° → score 25°–35°; train 10°–25° → score 30°–35°. (The 5°/1° run is not used: its turn is
set by the switching.) Each scored run is replayed open loop from execute with the measured rudder and
propeller (:func:`shipid.methods.mmg.turning_selection.batch_replay`). Fold score = RMS over the scored
runs and sides of the peak-yaw-rate error (%) + RMS over the scored runs of the whole-run heading RMS
(deg), the large-angle score of :mod:`shipid.methods.mmg.turning_nested`.

Decision rule: the candidate with the lowest mean fold score wins if that mean is lower than the
default's and its fold score is lower than the default's in at least :data:`MIN_FOLDS_BETTER` of the
three folds; otherwise the default stays.

Result (``shipid study kvlcc2-rudder-angle``, about 6 min on 2 shared cores; value: the calibrated
parameter, ``s`` / ``k`` 1/rad / ``b`` / stall angle rad; mean peak yaw-rate error per side over the
scored runs, %; heading RMS deg)::

    fold   candidate            value   score  r_pk%   stbd%   port%   psi°
    10-15  default                      18.91   6.56   +2.79   -7.35  12.35
    10-15  cf                           16.85   5.66   +5.37   -4.85  11.19
    10-15  cf/side-gain       -0.01438  13.52   4.50   +3.62   -3.84   9.02
    10-15  side-slope         -0.07009  17.56   5.19   -1.73   -4.68  12.37
    10-15  cf/side-slope      -0.07029  13.46   3.37   +1.81   -2.62  10.09
    10-15  cf/crossflow-side   -0.2116  13.72   3.75   +2.34   -3.15   9.97
    10-15  cf/stall-plus         1.047  15.87   3.96   +0.85   -3.63  11.91
    10-20  default                      24.27   7.79   +1.26  -10.64  16.47
    10-20  cf                           21.95   6.44   +3.76   -7.99  15.52
    10-20  cf/side-gain       -0.02381  13.67   4.84   +0.95   -6.26   8.83
    10-20  side-slope           -0.101  21.91   6.56   -6.10   -6.60  15.35
    10-20  cf/side-slope          -0.1  16.30   3.81   -2.19   -4.41  12.49
    10-20  cf/crossflow-side   -0.2931  14.81   4.26   -0.94   -5.44  10.55
    10-20  cf/stall-plus        0.6981  29.82   6.21   -6.40   -5.73  23.61
    10-25  default                      28.38   8.30   +2.62  -11.30  20.07
    10-25  cf                           26.13   7.08   +4.96   -8.58  19.05
    10-25  cf/side-gain       -0.02547  13.08   5.22   +2.34   -6.85   7.85
    10-25  side-slope         -0.08625  13.01   6.09   -3.43   -7.71   6.91
    10-25  cf/side-slope      -0.08911   9.45   3.86   -0.08   -5.31   5.59
    10-25  cf/crossflow-side   -0.2755   9.03   4.52   +0.89   -6.19   4.50
    10-25  cf/stall-plus         1.047  10.36   5.13   -0.17   -7.12   5.23

    fold 10-15 per scored run: peak error stbd/port %, heading RMS deg
    candidate          20/5            20/10P          20/10S          25/5            30/5            35/5
    default            +2.4/-7.9  2.2  +4.7/-0.1  2.3  +6.5/-4.2  3.0  -0.8/-8.0  2.1  +2.0/-10.1 16.5  +1.9/-13.9 24.9
    cf/side-gain       +1.9/-4.7  8.7  +4.6/+1.7  4.8  +6.1/-2.8  7.1  +0.3/-3.8  6.7  +4.1/-5.2   7.9  +4.7/-8.2  15.2
    cf/side-slope      +0.3/-3.4 13.5  +4.0/+2.3  8.4  +5.4/-2.4 10.7  -2.1/-2.4 14.5  +1.5/-3.5   4.5  +1.9/-6.2   3.9
    cf/crossflow-side  +0.6/-3.8 13.5  +4.3/+2.0  8.4  +5.7/-2.8 10.7  -1.6/-3.0 13.6  +2.3/-4.2   3.5  +2.8/-7.0   5.7

    mean fold score (folds better than the default): default 23.85, cf 21.64 (3), cf/side-gain 13.42 (3),
    side-slope 17.49 (3), cf/side-slope 13.07 (3), cf/crossflow-side 12.52 (3), cf/stall-plus 18.68 (2)

By the rule ``cf/crossflow-side`` is chosen (:data:`CHOSEN`); the three best (cross-flow per side,
side slope, constant side gain) lie within 0.9 of each other, well inside the spread over folds. The
angle-dependent terms halve the port deficit at 30°/35° and cut the heading RMS of those runs from
16–25° to 3.5–6°, but, like the constant side gain, they raise the whole-run heading RMS of the
20°/25° runs (2° → 13–14°). The calibrated stall angle lies at the grid's end (60°) in two folds:
the training runs show no stall. Fitted on all 13 HSVA zig-zags (``--selection rudder-angle``,
``b = −0.360``), ``shipid imo MODEL.json --samples 100`` gives for the 35° circles advance /
tactical diameter 3.11 / 3.15 L (starboard) and 3.23 / 3.38 L (port), against 3.24 / 3.67 and
3.44 / 4.03 for the default selection; the bands (±2 std 0.04–0.07 L) hold the parameter covariance
only, not the calibrated ``b``.

Why the heading RMS of the 20°/25° runs grows (:func:`heading_drift` of the fold 10-15 models: mean
yaw-rate error deg/s, final heading error deg, of the open-loop replay; computed after the table)::

    candidate          20/5          20/10P        20/10S        25/5          30/5          35/5
    default            -0.033 -5.7   -0.018 -3.4   +0.003 +0.6   +0.021 +3.9   +0.159 +31.7  +0.224 +46.8
    cf/side-gain       -0.101 -17.7  -0.059 -11.2  -0.047 -9.0   -0.047 -8.7   +0.080 +16.0  +0.143 +29.8
    cf/side-slope      -0.150 -26.4  -0.094 -17.8  -0.082 -15.5  -0.124 -22.7  -0.013 -2.6   +0.037 +7.6
    cf/crossflow-side  -0.150 -26.4  -0.095 -17.9  -0.082 -15.6  -0.116 -21.3  +0.002 +0.4   +0.059 +12.2

The default's yaw balance over a zig-zag is nearly right up to 25° and drifts to starboard at 30°/35°
(the port turn too weak); each side term, calibrated on the 10°/15° peaks, shifts the balance to port
at every angle, which fixes 30°/35° and spoils 20°/25°. The port deficit sets in between 25° and 30°,
faster than any term here that is linear in the angle or in ``sin α_R |sin α_R|``; the training peaks
of 10°/15° (and the stall angle calibrated on them, which stays at the grid's end) cannot show where.

A check made after the choice (a diagnostic, not a selection): the same CV on the frozen candidate
``full/symmetric-gamma_R`` (the default selection's choice on all 13 runs; ``candidates(base_name=...)``)
gives mean fold scores default 24.11, cf 23.71, cf/side-gain 16.66, side-slope 15.92, cf/side-slope
13.21, cf/crossflow-side 13.38, cf/stall-plus 14.57: the angle-dependent terms again beat the constant
side gain in every fold, but the order of the best two is reversed; the port deficit is larger on that
base (35°/5°, fold 10-15: −18.1 % default, −12.5 % cf/crossflow-side).

A zero-rudder yaw moment does not rescue the balance: with the propeller side force and moment ∝ thrust
free in the regression (structure ``yasukawa2015-asym``, ``YP_T``, ``NP_T``; candidates built ad hoc and
passed to :func:`cross_validate`, after the table), the mean fold scores are default 26.51,
cf/side-gain 32.31, cf/crossflow-side 37.43 (against 23.85, 13.42, 12.52 without): worse in every fold,
as the free asymmetry terms of :mod:`shipid.methods.mmg.extrapolation` were. Calibrated rather than
regressed (a neutral rudder angle, a propeller side force of the right-handed sign), they do not win the
same forward CV either (:mod:`shipid.methods.mmg.propeller_side`, ``shipid study kvlcc2-prop-side``).

Runs read: the twelve HSVA zig-zags of :data:`RUNS` (the HSVA basin only; no run of another basin).
The 20°/10° and 35°/5° runs are the held-out runs of the frozen overshoot study
(:mod:`shipid.methods.mmg.study`), which this study does not change.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from shipid.io.basins import read_kvlcc2
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import turning_selection as TS
from shipid.methods.mmg.candidates import CANDIDATES
from shipid.methods.mmg.side_calibration import SIDE_GAIN_GRID, fit_candidate, with_asymmetry
from shipid.methods.mmg.zigzag import zigzag_angles
from shipid.models import mmg

#: The HSVA zig-zags the study reads (all but the 5°/1° one).
RUNS = ("HSVA_CPMC_KVLCC2_Z_10_01.dat", "HSVA_CPMC_KVLCC2_Z_10_05.dat", "HSVA_CPMC_KVLCC2_Z_10_10_P.dat",
        "HSVA_CPMC_KVLCC2_Z_10_10_S.dat", "HSVA_CPMC_KVLCC2_Z_15_01.dat", "HSVA_CPMC_KVLCC2_Z_15_05.dat",
        "HSVA_CPMC_KVLCC2_Z_20_05.dat", "HSVA_CPMC_KVLCC2_Z_20_10_P.dat", "HSVA_CPMC_KVLCC2_Z_20_10_S.dat",
        "HSVA_CPMC_KVLCC2_Z_25_05.dat", "HSVA_CPMC_KVLCC2_Z_30_05.dat", "HSVA_CPMC_KVLCC2_Z_35_05.dat")
#: Forward folds: (name, largest training rudder angle, deg); scored on every run above it.
FOLDS = (("10-15", 15.0), ("10-20", 20.0), ("10-25", 25.0))
#: Decision rule: least number of folds in which the winner must beat the default.
MIN_FOLDS_BETTER = 2
#: Base candidate of every row (module docstring).
BASE = "linear-hull+rudder/symmetric-gamma_R"
#: Calibration grids per parameter: side slope k (1/rad), cross-flow side b, stall angle (rad).
SLOPE_GRID = (-0.4, -0.3, -0.2, -0.1, 0.0, 0.1, 0.2)
CROSSFLOW_SIDE_GRID = (-1.0, -0.75, -0.5, -0.25, 0.0, 0.25, 0.5)
STALL_GRID = tuple(np.deg2rad([10.0, 15.0, 20.0, 25.0, 30.0, 40.0, 60.0]).tolist())
GRIDS = {"rudder_side_gain": SIDE_GAIN_GRID, "rudder_side_slope": SLOPE_GRID,
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


#: The candidate the decision rule chose (``shipid study kvlcc2-rudder-angle``; module docstring);
#: ``shipid identify mmg --selection large-angle`` fits it.
CHOSEN = "cf/crossflow-side"


def resolve(trials, runs, prior: mmg.MmgModel, cand: Mapping, config: R.FitConfig = R.FitConfig()):
    """:func:`shipid.methods.mmg.turning_selection.resolve` on the grid of the calibrated particular
    (:data:`GRIDS`); the ``resolve`` of :func:`shipid.methods.mmg.pipeline.identify`."""
    par = cand.get(TS.CALIBRATE)
    return TS.resolve(trials, runs, prior, cand, config, grid=GRIDS[par] if par else SIDE_GAIN_GRID)


def rudder_angles(names: Sequence[str]) -> list[float]:
    """Rudder angle (deg) of each zig-zag by its file name."""
    return [float(np.degrees(zigzag_angles(f)[0])) for f in names]


def fold_sets(names: Sequence[str]) -> list[tuple[str, list[int], list[int]]]:
    """``(fold, training indices, scored indices)`` of :data:`FOLDS` over ``names``."""
    ang = rudder_angles(names)
    return [(f, [i for i, a in enumerate(ang) if a <= top + 1e-9], [i for i, a in enumerate(ang) if a > top + 1e-9])
            for f, top in FOLDS]


def calibrated(cand: Mapping, runs, data, use, prior, train: Sequence[int]) -> tuple[dict, float | None]:
    """``cand`` with its calibrated particular chosen on the runs ``train`` (and the value), or unchanged."""
    par = cand.get(TS.CALIBRATE)
    c = {k: v for k, v in cand.items() if k != TS.CALIBRATE}
    if not par:
        return c, None
    (a, _), = TS.calibrate_folds(runs, data, use, prior, c, [list(train)], grid=GRIDS[par], parameter=par)
    return with_asymmetry(c, a, par), float(a)


def score_rows(rep: Sequence[Mapping]) -> dict[str, float]:
    """Fold score of the replays ``rep`` of the scored runs (module docstring) and its parts."""
    pk = np.array([[r["r_peak_stbd_err_pct"], r["r_peak_port_err_pct"]] for r in rep], float)
    psi = np.array([r["psi_rms"] for r in rep], float)
    out = {"r_peak_rms_pct": float(np.sqrt(np.mean(pk ** 2))), "r_peak_stbd_mean_pct": float(pk[:, 0].mean()),
           "r_peak_port_mean_pct": float(pk[:, 1].mean()), "psi_rms_deg": float(np.sqrt(np.mean(psi ** 2)))}
    s = out["r_peak_rms_pct"] + out["psi_rms_deg"]
    out["score"] = float(s) if np.isfinite(s) else float("inf")
    return out


def load_runs(names: Sequence[str] = RUNS, root: Path | None = None):
    """What the forward-fold CVs read once: the HSVA prior, the trials ``names``, their smoothed runs
    (:func:`shipid.methods.mmg.estimator.smooth_run`), replay data and the peak-scored subset
    (:func:`shipid.methods.mmg.turning_selection.peak_runs`)."""
    trials = [read_kvlcc2(f, root) for f in names]
    return (mmg.load_published("kvlcc2_hsva", root), trials, [R.smooth_run(tr) for tr in trials],
            [TS.replay_data(tr) for tr in trials], TS.peak_runs(trials))


def cross_validate(cands: Mapping[str, Mapping] | None = None, *, names: Sequence[str] = RUNS,
                   root: Path | None = None, progress=None) -> dict[str, Any]:
    """The forward-fold CV of the module docstring. Returns per fold and candidate the calibrated value,
    the :func:`score_rows` numbers and the per-run replays; and :func:`decide`."""
    cands = candidates() if cands is None else cands
    prior, trials, runs, data, use = load_runs(names, root)
    folds: dict[str, Any] = {}
    for fold, train, test in fold_sets(names):
        row: dict[str, Any] = {"train": [names[i] for i in train], "scored": [names[i] for i in test]}
        for cname, cand in cands.items():
            c, a = calibrated(cand, runs, data, use, prior, train)
            model = fit_candidate([runs[i] for i in train], prior, c)
            rep = TS.batch_replay([(model, i) for i in test], data)
            row[cname] = {"calibrated": a, **score_rows(rep), "runs": dict(zip(row["scored"], rep))}
            if progress is not None:
                progress(f"{fold}: {cname} {row[cname]['score']:.2f}")
        folds[fold] = row
    return {"folds": folds, "decision": decide(folds, list(cands))}


def decide(folds: Mapping[str, Mapping], names: Sequence[str]) -> dict[str, Any]:
    """The decision rule of the module docstring: mean fold score per candidate, folds better than the
    default, and the choice."""
    mean = {c: float(np.mean([folds[f][c]["score"] for f in folds])) for c in names}
    better = {c: int(sum(folds[f][c]["score"] < folds[f]["default"]["score"] for f in folds)) for c in names}
    best = min(names, key=lambda c: mean[c])
    wins = best != "default" and mean[best] < mean["default"] and better[best] >= MIN_FOLDS_BETTER
    return {"mean_score": mean, "folds_better_than_default": better, "best_mean": best,
            "chosen": best if wins else "default"}


def heading_drift(model: mmg.MmgModel, trial) -> dict[str, float]:
    """Mean yaw-rate error (deg/s) and final heading error (deg) of the open-loop replay from execute
    (:func:`shipid.methods.mmg.extrapolation.replay`'s integration): a drift of the whole-run heading."""
    d = TS.replay_data(trial)
    t = np.concatenate([[0.0], np.cumsum(d["h"])])
    X = mmg.simulate_batch(model, t, d["x0"][None], d["U"][None])[0]
    e = np.degrees(np.unwrap(X[:, 2]) - np.unwrap(d["psi"]))
    return {"r_mean_err_deg_s": float(np.degrees(np.mean(X[:, 5] - d["r"]))), "psi_end_err_deg": float(e[-1])}


def format_cv(res: Mapping[str, Any]) -> str:
    """Per fold and candidate: calibrated value, score, RMS peak %, mean peak per side %, heading RMS deg;
    per candidate on the first fold the peak errors per scored run and side; the decision."""
    lines = [f"  {'fold':<6} {'candidate':<18} {'value':>8} {'score':>7} {'r_pk%':>6} {'stbd%':>7} {'port%':>7} "
             f"{'psi°':>6}"]
    for f, row in res["folds"].items():
        for c, r in row.items():
            if c in ("train", "scored"):
                continue
            v = "" if r["calibrated"] is None else f"{r['calibrated']:.4g}"
            lines.append(f"  {f:<6} {c:<18} {v:>8} {r['score']:7.2f} {r['r_peak_rms_pct']:6.2f} "
                         f"{r['r_peak_stbd_mean_pct']:+7.2f} {r['r_peak_port_mean_pct']:+7.2f} {r['psi_rms_deg']:6.2f}")
    first = next(iter(res["folds"].values()))
    lines.append("  fold 10-15, per scored run: peak yaw-rate error stbd / port %, heading RMS deg")
    for c, r in first.items():
        if c in ("train", "scored"):
            continue
        cells = [f"{n.split('_Z_')[1][:-4]} {x['r_peak_stbd_err_pct']:+.1f}/{x['r_peak_port_err_pct']:+.1f} "
                 f"{x['psi_rms']:.1f}" for n, x in r["runs"].items()]
        lines.append(f"  {c:<18} " + "; ".join(cells))
    d = res["decision"]
    lines.append("  mean fold score: " + ", ".join(f"{c} {v:.2f} ({d['folds_better_than_default'][c]} better)"
                                                  for c, v in d["mean_score"].items()))
    lines.append(f"  decision rule: lowest mean '{d['best_mean']}'; chosen '{d['chosen']}'")
    return "\n".join(lines)


__all__ = ["RUNS", "FOLDS", "CHOSEN", "resolve", "MIN_FOLDS_BETTER", "BASE", "SLOPE_GRID", "CROSSFLOW_SIDE_GRID", "STALL_GRID", "GRIDS",
           "candidates", "rudder_angles", "fold_sets", "calibrated", "score_rows", "load_runs", "cross_validate", "decide", "heading_drift",
           "format_cv"]
