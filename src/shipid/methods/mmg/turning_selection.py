"""Structure selection for the KVLCC2 (Yasukawa 2015 structure) on what a turning circle measures.

``shipid identify mmg --prior kvlcc2_hsva`` chooses among :data:`TURNING_CANDIDATES` by
:func:`select_for_turning`, a leave-one-run-out (or ``folds``-fold) cross-validation over
the TRAINING runs whose fold errors are those of an open-loop replay of each left-out run
(:func:`shipid.methods.mmg.extrapolation.replay`: the measured rudder and propeller replayed
from the measured state at execute over the whole run, the way a turning circle of another
basin is predicted):

* the relative error of the peak yaw rate reached on each side (%), the quantity that sets
  a turning circle's diameter (``D ≈ 2 U / r`` in the steady turn), and
* the RMS heading error over the whole replay (deg),

pooled over all folds' left-out zig-zags with a switch heading of
:data:`~shipid.methods.mmg.side_calibration.MIN_SWITCH_DEG` or more (the 1°-switch runs
are excluded a priori, as in :mod:`shipid.methods.mmg.side_calibration`; a run whose
file name does not give its angles is kept). Score (:data:`DEFAULT_CRITERION` ``"peak"``) =
RMS over runs and sides of the peak-yaw-rate errors (%), lower is better, the first listed on
a tie; ``"peak+heading"`` adds the RMS over runs of the heading RMS (deg), the score of
:mod:`shipid.methods.mmg.extrapolation`. The heading RMS is reported in the table either way.

Choice of the criterion, on HSVA runs only (:func:`nested_criterion_check`): each
criterion selects among the candidates by leave-one-out on the 10°/15° zig-zags, and its
choice, fitted on them, predicts the 20°–30° ones (score of the large-angle study: RMS
peak-yaw-rate error % + RMS heading error deg; mean peak error per side; overshoot RMS)::

    criterion     chosen                          20-30 score  r_pk%  stbd%  port%  psi°   ovs°
    peak+heading  hull-only/sym/cf                37.08        7.85   -3.00  -10.32 29.23  0.26
    peak          linear-hull+rudder/sym/cf/sg    11.58        3.74   +2.09  -4.57  7.84   0.87

The whole-run heading of a left-out small-angle zig-zag, replayed open loop, accumulates the
timing of every reversal; as a selection criterion it did not carry to larger angles, the peak
yaw rates did. (This comparison was made after the 13-run table below, computed with
``"peak+heading"``, had been seen; it reads no run of another basin.)

Candidates (fixed a priori; a full factorial over the first three axes):
free set (``full``, ``linear-hull+rudder``, ``hull-only``) × flow straightening γ_R (the
prior's per-side values | their symmetric mean) × rudder normal force (standard ``f_α sin α_R``
| with the cross-flow drag part ``C_Dc sin α_R |sin α_R|``, ``C_Dc = 1`` fixed after Hoerner,
Fluid-Dynamic Lift 1985 ch. 3, not tuned; ``rudder_crossflow`` of
:func:`shipid.models.mmg_forces.basis_yasukawa`), plus, for the three free sets with symmetric
γ_R and ``C_Dc = 1``, the port/starboard rudder effectiveness ``F_N (1 + s sign δ)``
(``rudder_side_gain``) calibrated on the training runs' peak yaw rates
(:func:`shipid.methods.mmg.side_calibration.calibrate`: grid
:data:`~shipid.methods.mmg.side_calibration.SIDE_GAIN_GRID` refined by a parabola). The
first six are the frozen list :data:`shipid.methods.mmg.candidates.CANDIDATES` of the
``yasukawa2015`` structure, which stays unchanged (the frozen ``kvlcc2-zigzag`` study and
its fingerprint use it).

A calibrated candidate is calibrated INSIDE each fold on that fold's training runs only
(and, for the identified model, on all training runs): the left-out runs never enter its
side gain. The replays of all candidates, folds and grid values are integrated together,
one RK4 batch per structure and particulars (the side gain varies per row;
:func:`shipid.methods.mmg.manoeuvres.rows_rk4`).

Leave-one-run-out on all 13 HSVA zig-zags (``select_for_turning`` with
``criterion="peak+heading"``; 10 left-out runs with switch ≥ 5°; peak errors %, heading deg;
``sg``: side-gain calibrated, ``cf``: ``C_Dc = 1``, ``sym``: symmetric γ_R)::

    candidate                       score   r_pk   psi    stbd%   port%
    full                            26.41   7.82  18.59  -7.48   +1.57
    linear-hull+rudder              33.84   8.44  25.40  -8.59   +3.98
    hull-only                       24.56   7.29  17.27  -7.00   +0.79
    full/sym                        12.65   5.85   6.80  +2.57   -5.43
    linear-hull+rudder/sym          14.74   5.32   9.42  +3.15   -4.98
    hull-only/sym                   12.69   6.33   6.37  +1.67   -6.87
    full/cf                         28.23   7.88  20.35  -8.35   +1.61
    linear-hull+rudder/cf           35.69   9.04  26.66  -9.61   +4.17
    hull-only/cf                    30.42   8.09  22.33  -7.43   +4.14
    full/sym/cf                     12.90   5.17   7.73  +1.92   -5.36
    linear-hull+rudder/sym/cf       13.98   5.04   8.93  +2.61   -5.10
    hull-only/sym/cf                12.73   5.04   7.69  +2.95   -4.63
    full/sym/cf/sg                  14.25   4.42   9.83  -1.08   -3.57
    linear-hull+rudder/sym/cf/sg    15.18   3.77  11.41  -0.95   -2.62
    hull-only/sym/cf/sg             15.31   3.89  11.41  -0.47   -2.13

The side gains calibrated in the folds lie between −0.029 and −0.050. The side-gain
candidates have the smallest peak-yaw-rate errors and the most balanced sides, but a larger
whole-run heading error, so under ``"peak+heading"`` the frozen list's ``full/symmetric-gamma_R``
is chosen; under ``"peak"`` (the default) ``linear-hull+rudder/sym/cf/sg``.
"""

from __future__ import annotations

import json
from dataclasses import replace as _replace
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from shipid.io.trial import Trial
from shipid.errors import InputError, ShipidError
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import manoeuvres as MM
from shipid.methods.mmg import validate as V
from shipid.methods.mmg.candidates import CANDIDATES
from shipid.methods.mmg.extrapolation import VALIDATE, large_angle_split, score_validation
from shipid.methods.mmg.side_calibration import (MIN_SWITCH_DEG, SIDE_GAIN_GRID, fit_candidate, refine_minimum,
                                                 with_asymmetry)
from shipid.methods.mmg.zigzag import execute_index, zigzag_angles
from shipid.models import mmg
from shipid.models.mmg_forces import RUDDER_LARGE_ANGLE

#: Key of a candidate whose particular of that name is calibrated on the training runs.
CALIBRATE = "calibrate"
#: The calibrated particular (port/starboard rudder effectiveness).
PARAMETER = "rudder_side_gain"


def turning_candidates() -> dict[str, dict]:
    """The frozen six, each with ``C_Dc = 1``, and three side-gain-calibrated ones: 15 (module docstring)."""
    base = CANDIDATES["yasukawa2015"]
    out = dict(base)
    for name, c in base.items():
        out[name + "/rudder-crossflow-1"] = dict(c, particulars=dict(c.get("particulars") or {},
                                                                     rudder_crossflow=1.0))
    for free in ("full", "linear-hull+rudder", "hull-only"):
        out[free + "/symmetric-gamma_R/rudder-crossflow-1/side-gain-calibrated"] = dict(
            out[free + "/symmetric-gamma_R/rudder-crossflow-1"], **{CALIBRATE: PARAMETER})
    return out


#: Candidates of the turning selection per prior structure.
TURNING_CANDIDATES: dict[str, dict[str, dict]] = {"yasukawa2015": turning_candidates()}


# ----------------------------------------------------------------------------- batched replays
def replay_data(tr: Trial) -> dict[str, Any]:
    """What :func:`shipid.methods.mmg.extrapolation.replay` integrates: state at execute, inputs, steps."""
    Z = V.measured_states(tr)
    U = V.trial_inputs(tr)
    k0 = execute_index(tr["delta"])
    t = np.asarray(tr.t[k0:], float)
    return {"x0": Z[k0], "U": U[k0:], "h": np.diff(t), "psi": Z[k0:, 2], "r": Z[k0:, 5], "n": int(t.size)}


#: Particulars that may differ between the rows of one replay batch (the side gain and the optional
#: large-angle rudder terms of :mod:`shipid.models.mmg_forces`; 0 where a row's model has none).
ROW_PARTICULARS = (PARAMETER,) + RUDDER_LARGE_ANGLE


def _group_key(m: mmg.MmgModel) -> str:
    return m.structure + json.dumps({k: float(v) for k, v in sorted(m.particulars.items())
                                     if k not in ROW_PARTICULARS})


def batch_replay(rows: Sequence[tuple[mmg.MmgModel, int]], data: Sequence[Mapping]) -> list[dict[str, float]]:
    """The :func:`~shipid.methods.mmg.extrapolation.replay` numbers (``psi_rms``, ``r_peak_{stbd,port}_err_pct``)
    of every row ``(model, run index into data)``, integrated as one batch per structure and particulars."""
    out: list[dict[str, float] | None] = [None] * len(rows)
    groups: dict[str, list[int]] = {}
    for j, (m, _) in enumerate(rows):
        groups.setdefault(_group_key(m), []).append(j)
    for js in groups.values():
        D = [data[rows[j][1]] for j in js]
        L = max(d["n"] for d in D)
        m0 = rows[js[0]][0]
        per_row = {k: np.array([float(rows[j][0].particulars.get(k, 0.0)) for j in js]) for k in ROW_PARTICULARS
                   if any(k in rows[j][0].particulars for j in js) or k == PARAMETER}
        m0 = _replace(m0, particulars=dict(m0.particulars, **per_row))
        Th = {md: np.stack([np.asarray(rows[j][0].theta(md), float) for j in js]) for md in mmg.MODES}
        U = np.stack([np.pad(d["U"], [(0, L - d["n"]), (0, 0)], mode="edge") for d in D])
        h = np.stack([np.pad(d["h"], (0, L - d["n"]), mode="edge") for d in D])
        x = np.stack([d["x0"] for d in D]).astype(float)
        psi, r = np.empty((len(js), L)), np.empty((len(js), L))
        psi[:, 0], r[:, 0] = x[:, 2], x[:, 5]
        with np.errstate(all="ignore"):
            for k in range(L - 1):
                u = U[:, k]
                x = MM.rows_rk4(m0, Th, x, u[:, 0], u[:, 1], h[:, k:k + 1], wind=(u[:, 2], u[:, 3]))
                psi[:, k + 1], r[:, k + 1] = x[:, 2], x[:, 5]
        for b, (j, d) in enumerate(zip(js, D)):
            n = d["n"]
            e = np.degrees(np.unwrap(psi[b, :n]) - np.unwrap(d["psi"]))
            row = {"psi_rms": float(np.sqrt(np.mean(e ** 2))) if np.all(np.isfinite(e)) else float("inf")}
            xr, zr = r[b, :n], d["r"]
            for side, s in (("stbd", 1.0), ("port", -1.0)):
                m_pk = float(np.max(s * zr))
                p_pk = float(np.max(s * xr)) if np.all(np.isfinite(xr)) else float("nan")
                row[f"r_peak_{side}_err_pct"] = 100.0 * (p_pk - m_pk) / m_pk if np.isfinite(p_pk) else float("inf")
            out[j] = row
    return out  # type: ignore[return-value]


def trial_angles(tr: Trial) -> tuple[float, float] | None:
    """``(rudder, switch)`` angles (rad) of a zig-zag run named by its source file, or None when the name says none
    (:func:`shipid.methods.mmg.zigzag.zigzag_angles`)."""
    try:
        return zigzag_angles(Path(str(tr.meta.get("source", ""))).name)
    except InputError:
        return None


def peak_runs(trials: Sequence[Trial]) -> list[bool]:
    """Per run: does its peak yaw rate enter the criteria (switch ≥ MIN_SWITCH_DEG, or angles unknown)."""
    angles = [trial_angles(tr) for tr in trials]
    return [True if a is None else bool(np.degrees(a[1]) >= MIN_SWITCH_DEG - 1e-9) for a in angles]


def _fit(runs, prior, cand, config):
    """:func:`~shipid.methods.mmg.side_calibration.fit_candidate`, or None where the fit fails."""
    try:
        return fit_candidate(runs, prior, cand, config)
    except (ShipidError, ValueError, np.linalg.LinAlgError):
        return None


def _peak_rms(results: Sequence[Mapping]) -> float:
    e = np.array([r[f"r_peak_{s}_err_pct"] for r in results for s in ("stbd", "port")], float)
    return float(np.sqrt(np.mean(e ** 2))) if e.size and np.all(np.isfinite(e)) else float("inf")


# ----------------------------------------------------------------------------- calibration per fold
def calibrate_folds(runs: Sequence[R.SmoothedRun], data: Sequence[Mapping], use: Sequence[bool],
                    prior: mmg.MmgModel, cand: Mapping, train_sets: Sequence[Sequence[int]], *,
                    config: R.FitConfig = R.FitConfig(), grid: Sequence[float] = SIDE_GAIN_GRID,
                    parameter: str = PARAMETER) -> list[tuple[float, dict[float, float]]]:
    """:func:`shipid.methods.mmg.side_calibration.calibrate` (grid, then the parabola's vertex kept if it
    scores lower) once per training set, each on ITS runs only (indices into ``runs``/``data``), with the
    replays of all training sets batched. Returns ``(value, {value tried: peak score})`` per set."""
    def scores(todo):           # todo: list of (set index, value) -> peak score of each
        rows, owner, res = [], [], {}
        for key in todo:
            s, a = key
            m = _fit([runs[i] for i in train_sets[s]], prior, with_asymmetry(cand, a, parameter), config)
            idx = [i for i in train_sets[s] if use[i]]
            if m is None or not idx:
                res[key] = float("inf")
                continue
            for i in idx:
                rows.append((m, i))
                owner.append(key)
        rep = batch_replay(rows, data)
        per: dict = {}
        for key, r in zip(owner, rep):
            per.setdefault(key, []).append(r)
        res.update({k: _peak_rms(v) for k, v in per.items()})
        return res

    first = scores([(s, float(a)) for s in range(len(train_sets)) for a in grid])
    tables = [{float(a): first[(s, float(a))] for a in grid} for s in range(len(train_sets))]
    best = [min(t, key=lambda a: t[a]) for t in tables]
    todo = []
    for s, t in enumerate(tables):
        g = sorted(t)
        i = g.index(best[s])
        if 0 < i < len(g) - 1 and all(np.isfinite(t[g[j]]) for j in (i - 1, i, i + 1)):
            todo.append((s, refine_minimum(g[i - 1:i + 2], [t[g[j]] ** 2 for j in (i - 1, i, i + 1)])))
    second = scores(todo)
    for (s, a), sa in second.items():
        tables[s][a] = sa
        if sa < tables[s][best[s]]:
            best[s] = a
    return [(best[s], tables[s]) for s in range(len(train_sets))]


def resolve(trials: Sequence[Trial], runs: Sequence[R.SmoothedRun], prior: mmg.MmgModel, cand: Mapping,
            config: R.FitConfig = R.FitConfig(), *, grid: Sequence[float] = SIDE_GAIN_GRID
            ) -> tuple[dict, dict | None]:
    """The candidate to fit on all training runs: a calibrated one with its particular calibrated on them
    (on ``grid``, then the parabola's vertex; and the calibration's table), any other unchanged (and None)."""
    par = cand.get(CALIBRATE)
    if not par:
        return dict(cand), None
    data = [replay_data(tr) for tr in trials]
    (a, table), = calibrate_folds(runs, data, peak_runs(trials), prior, cand, [list(range(len(runs)))], grid=grid,
                                  config=config, parameter=par)
    c = with_asymmetry(cand, a, par)
    c.pop(CALIBRATE, None)
    return c, {"parameter": par, "value": a, "training_peak_score": {f"{k:g}": v for k, v in sorted(table.items())},
               "criterion": "RMS over the training zig-zags with switch >= 5 deg and both sides of the open-loop "
                            "peak-yaw-rate error (%)",
               "note": "held fixed at this value in the regression: its uncertainty is not in the covariance "
                       "(nor in bands drawn from it)"}


# ----------------------------------------------------------------------------- selection
#: Selection scores: ``"peak"`` the RMS over left-out runs and sides of the peak-yaw-rate error (%);
#: ``"peak+heading"`` that plus the RMS of their whole-run heading RMS (deg).
CRITERIA = ("peak", "peak+heading")
#: The criterion :func:`select_for_turning` uses unless told (module docstring: chosen by
#: :func:`nested_criterion_check` on HSVA runs only).
DEFAULT_CRITERION = "peak"
METHOD = ("CV on the training runs ({folds}); each left-out zig-zag replayed open loop (measured rudder and "
          "propeller from the measured state at execute); a side-gain-calibrated candidate is calibrated in each "
          "fold on that fold's training runs only; score = RMS over left-out runs (switch >= 5 deg) and sides of "
          "the peak-yaw-rate error (%){heading}")


def select_for_turning(trials: Sequence[Trial], runs: Sequence[R.SmoothedRun], prior: mmg.MmgModel,
                       candidates: Mapping[str, Mapping], config: R.FitConfig = R.FitConfig(),
                       folds: int | None = None, *, criterion: str = DEFAULT_CRITERION
                       ) -> tuple[str, dict[str, dict], str]:
    """The ``selector`` of :func:`shipid.methods.mmg.pipeline.identify` for turning (module docstring).

    Returns the chosen name, the table (per candidate: ``score``, ``r_peak_rms`` %, ``psi_rms`` deg,
    the mean peak error per side %, the side gains calibrated per fold, ``folds``, ``count``) and the
    method line. ``criterion``: one of :data:`CRITERIA`."""
    if criterion not in CRITERIA:
        raise InputError(f"unknown selection criterion '{criterion}' (choose from {', '.join(CRITERIA)})")
    groups = R.fold_groups(len(runs), folds)
    data = [replay_data(tr) for tr in trials]
    use = peak_runs(trials)
    sets = [[i for i in range(len(runs)) if i not in g] for g in groups]
    rows, owner, table = [], [], {}
    for cname, cand in candidates.items():
        cal = None
        if cand.get(CALIBRATE):
            cal = calibrate_folds(runs, data, use, prior, cand, sets, config=config, parameter=cand[CALIBRATE])
        failed = False
        for f, (g, tr_idx) in enumerate(zip(groups, sets)):
            c = with_asymmetry(cand, cal[f][0], cand[CALIBRATE]) if cal else cand
            m = _fit([runs[i] for i in tr_idx], prior, c, config) if tr_idx else None
            if m is None:
                failed = True
                continue
            for i in g:
                if use[i]:
                    rows.append((m, i))
                    owner.append(cname)
        table[cname] = {"failed": failed, "calibrated": [c[0] for c in cal] if cal else None}
    per: dict[str, list] = {}
    for cname, r in zip(owner, batch_replay(rows, data)):
        per.setdefault(cname, []).append(r)
    out: dict[str, dict] = {}
    for cname in candidates:
        res = per.get(cname, [])
        pk = _peak_rms(res)
        psi = np.array([r["psi_rms"] for r in res], float)
        psi_rms = float(np.sqrt(np.mean(psi ** 2))) if psi.size and np.all(np.isfinite(psi)) else float("inf")
        score = (pk + (psi_rms if criterion == "peak+heading" else 0.0)) if res and not table[cname]["failed"] \
            else float("inf")
        row = {"score": float(score) if np.isfinite(score) else float("inf"), "r_peak_rms": pk, "psi_rms": psi_rms,
               "r_peak_stbd_mean_pct": float(np.mean([r["r_peak_stbd_err_pct"] for r in res])) if res else float("nan"),
               "r_peak_port_mean_pct": float(np.mean([r["r_peak_port_err_pct"] for r in res])) if res else float("nan"),
               "folds": len(groups), "count": len(res)}
        if table[cname]["calibrated"] is not None:
            row["calibrated_per_fold"] = {PARAMETER: table[cname]["calibrated"]}
        out[cname] = row
    best = min(out, key=lambda c: out[c]["score"])
    return best, out, METHOD.format(folds="leave-one-run-out" if folds is None else f"{folds}-fold",
                                    heading=" + RMS of their heading RMS (deg)" if criterion == "peak+heading" else "")


def nested_criterion_check(*, root: Path | None = None) -> dict[str, Any]:
    """Which criterion's choice carries to larger rudder angles, within the HSVA zig-zags only.

    For each of :data:`CRITERIA`: the selection (:func:`select_for_turning`, leave one run out) on the
    10°/15° zig-zags (:data:`shipid.methods.mmg.extrapolation.TRAIN`), the chosen candidate fitted
    (and calibrated, :func:`resolve`) on them, and scored on the 20°–30° ones
    (:data:`~shipid.methods.mmg.extrapolation.VALIDATE`) by
    :func:`shipid.methods.mmg.extrapolation.score_validation`. Reads no other run."""
    prior, trs, runs, ap, val = large_angle_split(root)
    cands = TURNING_CANDIDATES[prior.structure]
    out: dict[str, Any] = {}
    for crit in CRITERIA:
        best, table, _ = select_for_turning(trs, runs, prior, cands, criterion=crit)
        c, cal = resolve(trs, runs, prior, cands[best])
        row = score_validation(fit_candidate(runs, prior, c), val, VALIDATE, ap)
        row.pop("runs")
        out[crit] = {"chosen": best, "calibration": cal, "validation": row, "cv_score": table[best]["score"]}
    return out


__all__ = ["CALIBRATE", "PARAMETER", "ROW_PARTICULARS", "TURNING_CANDIDATES", "turning_candidates", "replay_data", "batch_replay",
           "trial_angles", "peak_runs", "calibrate_folds", "resolve", "select_for_turning", "METHOD", "CRITERIA", "DEFAULT_CRITERION",
           "nested_criterion_check"]
