"""Port/starboard yaw balance of the KVLCC2: neutral rudder angle and propeller side force, chosen by the forward angle CV.

Question: the rudder-angle selection of :mod:`shipid.methods.mmg.rudder_angle` (``cf/crossflow-side``)
drifts to port over the whole 20°/25° zig-zags (heading RMS 2° → 13–14°) while its default drifts to
starboard at 30°/35°. Does a small separate asymmetry term of a single-screw ship, set on the
training runs, keep the yaw balance right at the larger angles? The terms are those of
:mod:`shipid.models.mmg_prop_side` (the HSVA report gives the propeller's rotation: right-handed):

* ``rudder_neutral_angle`` ``δ_0``: the slipstream-swirl offset of the rudder inflow angle
  (physics expects ``δ_0 > 0`` for a right-handed propeller; the grid :data:`NEUTRAL_GRID` spans
  both signs, so that a value of the other sign shows a compensation, not the swirl);
* ``prop_side_thrust`` ``c``: the propeller side force ``Y_P = c T`` at the propeller, ``N_P = x_P L Y_P``,
  sign fixed by the rotation (``c ≥ 0``, grid :data:`PROP_SIDE_GRID`).

Candidates (:func:`candidates`, fixed a priori), on the frozen base of :mod:`~shipid.methods.mmg.rudder_angle`:

* ``default``, ``cf/crossflow-side`` — the two of that study (the rule's references);
* ``neutral-angle``, ``cf/crossflow-side/neutral-angle`` — each with ``δ_0`` calibrated;
* ``prop-side``, ``cf/crossflow-side/prop-side`` — each with ``c`` calibrated.

Calibration, on the fold's TRAINING runs only: the candidate's own calibrated particular first (the
cross-flow side ``b`` by the peak criterion of :func:`shipid.methods.mmg.turning_selection.calibrate_folds`,
as in that study), then the new term with ``b`` held, on its grid refined by a parabola's vertex (kept if
it scores lower), by the fold score evaluated on the training runs (:func:`training_score`: RMS over the
training runs with switch ≥ 5° and both sides of the open-loop peak-yaw-rate error, % + RMS over ALL
training runs, the 1°-switch ones included, of the whole-run heading RMS, deg; the heading part is what
measures the yaw balance). A calibrated value at its grid's end is labelled "not determined" (the
training runs do not bound it). Calibrated values are held fixed in the regression: their uncertainty
is not in the covariance (nor in bands drawn from it).

Cross-validation: the forward folds and fold score of :mod:`shipid.methods.mmg.rudder_angle`
(:data:`~shipid.methods.mmg.rudder_angle.FOLDS`: 10–15 → 20–35, 10–20 → 25–35, 10–25 → 30–35).

Decision rule (written before any score was computed): the candidate with the lowest mean fold score
replaces the current choice ``cf/crossflow-side`` only if it is one of the new candidates, its mean fold
score is lower than that of ``cf/crossflow-side`` and its fold score is lower than that of
``cf/crossflow-side`` in at least :data:`MIN_FOLDS_BETTER` of the three folds; otherwise
``cf/crossflow-side`` stays. The fold spread (standard deviation over the folds) is reported with each mean.

A check of what the data determine (:func:`yaw_balance`; a diagnostic, not a selection): per training
zig-zag, the first-order Nomoto fit ``ṙ = a δ + b r + c`` by least squares gives the rudder angle at which
the yaw rate settles to zero, ``δ_n = −c / a``, with its standard error (delta method; the residuals are
autocorrelated, so the SE is optimistic).

Result (``shipid study kvlcc2-prop-side``, 5–7 min on 2 shared cores; ``b``: the cross-flow side
calibrated by the peaks; second: ``δ_0`` deg or ``c`` ± run-bootstrap SE (:func:`bootstrap_se`), ``?`` not
determined; mean peak yaw-rate error per side %, heading RMS deg; the ``default`` and ``cf/crossflow-side``
rows reproduce the :mod:`~shipid.methods.mmg.rudder_angle` table)::

    fold   candidate                              b          second  score  r_pk%  stbd%   port%   psi°
    10-15  default                                                    18.91   6.56  +2.79   -7.35  12.35
    10-15  cf/crossflow-side                -0.2116                   13.72   3.75  +2.34   -3.15   9.97
    10-15  neutral-angle                             -0.265±0.16deg   24.32   7.77  +4.76   -8.73  16.55
    10-15  cf/crossflow-side/neutral-angle  -0.2116    -0.5±0.12deg   13.79   6.19  +6.04   -5.53   7.60
    10-15  prop-side                                           0±0?   18.91   6.56  +2.79   -7.35  12.35
    10-15  cf/crossflow-side/prop-side      -0.2116            0±0?   13.72   3.75  +2.34   -3.15   9.97
    10-20  default                                                    24.27   7.79  +1.26  -10.64  16.47
    10-20  cf/crossflow-side                -0.2931                   14.81   4.26  -0.94   -5.44  10.55
    10-20  neutral-angle                              -0.18±0.15deg   27.93   8.40  +2.29  -11.41  19.53
    10-20  cf/crossflow-side/neutral-angle  -0.2931   -0.5±0.093deg   11.84   5.48  +2.15   -7.27   6.36
    10-20  prop-side                                           0±0?   24.27   7.79  +1.26  -10.64  16.47
    10-20  cf/crossflow-side/prop-side      -0.2931            0±0?   14.81   4.26  -0.94   -5.44  10.55
    10-25  default                                                    28.38   8.30  +2.62  -11.30  20.07
    10-25  cf/crossflow-side                -0.2755                    9.03   4.52  +0.89   -6.19   4.50
    10-25  neutral-angle                             -0.152±0.15deg   31.68   8.80  +3.31  -11.86  22.88
    10-25  cf/crossflow-side/neutral-angle  -0.2755   -0.5±0.088deg   14.49   6.03  +3.34   -7.76   8.46
    10-25  prop-side                                           0±0?   28.38   8.30  +2.62  -11.30  20.07
    10-25  cf/crossflow-side/prop-side      -0.2755            0±0?    9.03   4.52  +0.89   -6.19   4.50

    mean fold score ± spread (sd over the 3 folds) (folds better than cf/crossflow-side):
    default 23.85 ± 4.75 (0); cf/crossflow-side 12.52 ± 3.07; neutral-angle 27.98 ± 3.68 (0);
    cf/crossflow-side/neutral-angle 13.37 ± 1.37 (1); prop-side = default; cf/crossflow-side/prop-side =
    cf/crossflow-side (c = 0 at the grid's end in every fold)

    whole-run heading RMS, deg (fold 10-15 models; every scored run)
    candidate                          20/5   20/10P 20/10S 25/5   30/5   35/5
    default                            2.21   2.27   3.02   2.06  16.47  24.92
    cf/crossflow-side                 13.49   8.36  10.68  13.64   3.46   5.70
    neutral-angle                      7.05   7.37   5.20   8.01  22.78  30.48
    cf/crossflow-side/neutral-angle    2.34   4.56   2.50   1.50  10.02  14.53

    yaw balance (Nomoto δ_n deg ± SE): 10/1 −0.46±0.03, 10/5 −0.15±0.07, 10/10P −0.61±0.12,
    10/10S +0.27±0.13, 15/1 −0.17±0.05, 15/5 −0.17±0.07, 20/5 +0.00±0.08, 20/10P +0.08±0.09,
    20/10S −0.18±0.09, 25/5 −0.05±0.08, 30/5 +0.75±0.10, 35/5 +1.11±0.11

By the rule ``cf/crossflow-side`` stays (the lowest mean; the neutral angle beats it in one fold of three).
The propeller side force of the right-handed sign is not wanted by any fold (``c`` stays at 0, the grid's
end: not determined), nor is the swirl's ``δ_0 > 0``: the calibrated ``δ_0`` is negative (−0.15° … −0.27° on
the default; −0.5° on ``cf/crossflow-side``, where it compensates the port drift that ``b`` brings to the
20°/25° runs). With ``b`` it repairs the whole-run heading of the 20°/25° runs (13.5 → 2.3°, 13.6 → 1.5°)
and gives back the 30°/35° ones (3.5 → 10.0°, 5.7 → 14.5°): the fold spread drops from 3.07 to 1.37, the
mean does not. The data check says why no term set on the training runs can do both: up to 25° the
zig-zags' own neutral rudder angle is between −0.6° and +0.3° (mean near −0.2°, no right-handed swirl
offset visible), at 30° and 35° it jumps to +0.75° and +1.11° (the starboard rudder less effective than the
port one there): the yaw balance changes between 25° and 30°, above every training fold's largest angle.

A check made after the choice (a diagnostic, not a selection): fitted on all 13 HSVA zig-zags as
``shipid identify mmg --selection rudder-angle`` fits (``b = −0.360``), the neutral angle calibrated on
them by :func:`calibrate_second` is ``δ_0 = −0.50°`` (training score 27.98 at ``δ_0 = 0``, 13.86 at −0.5°).
In-sample whole-run heading RMS, deg (the replays of all 13 runs; not a prediction)::

    model                 5/1   10/1  10/5  10/10P 10/10S 15/1  15/5  20/5  20/10P 20/10S 25/5  30/5  35/5
    cf/crossflow-side    47.7  55.9   7.9   2.3    6.7   30.9  15.6  17.7  11.1   14.5   19.4  10.1   6.0
    ... /neutral-angle    9.2  18.4  14.6   4.3    2.9    2.0   3.0   4.0   2.2    4.1    7.8   2.8   4.9

and ``shipid imo MODEL.json --samples 100`` gives for the 35° circles advance / tactical diameter (L, ±2 std
from the parameter covariance only) 3.05 / 3.11 (±0.04 / ±0.06) starboard and 3.27 / 3.40 (±0.04 / ±0.07)
port, against 3.11 / 3.15 and 3.23 / 3.38 for ``cf/crossflow-side``.

Leave one run out (:func:`leave_one_out`, the same diagnostic status; about 11 min): each of the 12 runs
predicted by the two models calibrated and fitted on the other 11 (``b`` −0.31 … −0.39, ``δ_0`` −0.40° … −0.51°,
all "calibrated"). Heading RMS deg / peak error stbd / port %::

    left out   cf/crossflow-side        ... /neutral-angle
    10/1       57.9  −34.4 / +58.1      28.1  −20.9 / +37.2
    10/5        7.5   +0.4 /  −1.3      15.0   +9.5 /  −9.7
    10/10P      2.3   −3.3 /  −2.0       4.3   +2.5 /  −6.7
    10/10S      6.9   −6.7 /  −6.8       3.1   −1.9 / −11.4
    15/1       31.8  −19.5 / +26.4       1.8   +3.2 /  +3.4
    15/5       15.8   −0.3 /  +1.1       2.7   +6.6 /  −5.1
    20/5       17.9   −1.3 /  −3.7       4.0   +3.7 /  −7.2
    20/10P     11.5   +2.8 /  +0.9       2.1   +5.4 /  −1.5
    20/10S     14.5   +3.8 /  −3.8       3.9   +6.4 /  −5.6
    25/5       21.6   −4.3 /  −2.2       9.7   −0.3 /  −4.6
    30/5        9.2   −0.2 /  −4.0       3.2   +2.6 /  −5.8
    35/5        3.8   +0.5 /  −7.1       7.7   +2.6 /  −8.5

Over the ten runs with switch ≥ 5° the fold-score measure is 16.14 (peaks 3.55 %, heading 12.59°) against
12.89 (6.11 %, 6.78°): the neutral angle halves the heading error of a model that has seen every angle
but moves the peaks apart (starboard +3.7 %, port −6.6 % on average) and is worse on the 35°/5° run,
the one nearest the 35° circles. It does not change the choice.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from shipid.errors import ShipidError
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import rudder_angle as RA
from shipid.methods.mmg import turning_selection as TS
from shipid.methods.mmg import validate as V
from shipid.methods.mmg.side_calibration import fit_candidate, refine_minimum, with_asymmetry
from shipid.methods.mmg.zigzag import execute_index
from shipid.models import mmg

#: Key of a candidate: the asymmetry particular calibrated after the candidate's own (module docstring).
SECOND = "calibrate_second"
#: Neutral rudder angles tried (rad): −2° … 2° by 0.5°.
NEUTRAL_GRID = tuple(np.deg2rad(np.arange(-2.0, 2.01, 0.5)).tolist())
#: Propeller side-force fractions of the thrust tried (sign fixed by the right-handed rotation).
PROP_SIDE_GRID = (0.0, 0.025, 0.05, 0.1, 0.15, 0.2, 0.3)
GRIDS = {"rudder_neutral_angle": NEUTRAL_GRID, "prop_side_thrust": PROP_SIDE_GRID}
#: Resamples of :func:`bootstrap_se`.
BOOTSTRAP = 200
#: Decision rule: least number of folds in which the winner must beat ``cf/crossflow-side``.
MIN_FOLDS_BETTER = 2
#: The current choice (:data:`shipid.methods.mmg.rudder_angle.CHOSEN`), the rule's reference.
CURRENT = RA.CHOSEN


def candidates() -> dict[str, dict]:
    """The six candidates of the module docstring."""
    base = RA.candidates()
    d, cs = base["default"], base[CURRENT]
    return {"default": d, CURRENT: cs,
            "neutral-angle": dict(d, **{SECOND: "rudder_neutral_angle"}),
            CURRENT + "/neutral-angle": dict(cs, **{SECOND: "rudder_neutral_angle"}),
            "prop-side": dict(d, **{SECOND: "prop_side_thrust"}),
            CURRENT + "/prop-side": dict(cs, **{SECOND: "prop_side_thrust"})}


def training_score(rep: Sequence[Mapping], use: Sequence[bool]) -> float:
    """RMS over the runs with ``use`` and both sides of the peak-yaw-rate error (%) + RMS over all runs of
    the whole-run heading RMS (deg) of the replays ``rep``."""
    pk = np.array([[r["r_peak_stbd_err_pct"], r["r_peak_port_err_pct"]] for r, u in zip(rep, use) if u], float)
    psi = np.array([r["psi_rms"] for r in rep], float)
    s = (float(np.sqrt(np.mean(pk ** 2))) if pk.size else 0.0) + float(np.sqrt(np.mean(psi ** 2)))
    return s if np.isfinite(s) else float("inf")


def _replays(cand, par, values, runs, data, prior, train) -> dict[float, list | None]:
    """Per value of ``par``: the replays of the runs ``train`` by the model fitted on them (None: the fit failed)."""
    rows, owner, out = [], [], {}
    for a in values:
        try:
            m = fit_candidate([runs[i] for i in train], prior, with_asymmetry(cand, a, par))
        except (ShipidError, ValueError, np.linalg.LinAlgError):
            out[float(a)] = None
            continue
        rows += [(m, i) for i in train]
        owner += [float(a)] * len(train)
    rep = TS.batch_replay(rows, data) if rows else []
    for a in dict.fromkeys(owner):
        out[a] = [rep[j] for j, o in enumerate(owner) if o == a]
    return out


def _table(per: Mapping[float, list | None], use_t: Sequence[bool], idx=None) -> dict[float, float]:
    out = {}
    for a, rep in per.items():
        if rep is None:
            out[a] = float("inf")
            continue
        k = range(len(rep)) if idx is None else idx
        out[a] = training_score([rep[i] for i in k], [use_t[i] for i in k])
    return out


def _argmin(table: Mapping[float, float]) -> tuple[float, int, list[float]]:
    """Grid minimum, its index, the sorted grid; the first on a tie."""
    g = sorted(table)
    best = min(g, key=lambda a: table[a])
    return best, g.index(best), g


def _vertex(table: Mapping[float, float]) -> float | None:
    """The parabola's vertex through the grid minimum and its neighbours, or None at the grid's end."""
    best, i, g = _argmin(table)
    if 0 < i < len(g) - 1 and all(np.isfinite(table[g[j]]) for j in (i - 1, i, i + 1)):
        return refine_minimum(g[i - 1:i + 2], [table[g[j]] for j in (i - 1, i, i + 1)])
    return None


def bootstrap_se(per: Mapping[float, list | None], use_t: Sequence[bool], *, resamples: int = BOOTSTRAP,
                 seed: int = 0) -> float:
    """Run-bootstrap standard error of the calibrated value: the training runs resampled with replacement
    (``resamples`` draws, seeded), the grid's scores recomputed from the replays of the models fitted on all
    of them (held: the refits are not repeated) and the minimum refined by the parabola's vertex each time.
    The standard deviation of those minima; ``inf`` with fewer than two finite grid values."""
    grid = [a for a, r in per.items() if r is not None]
    if len(grid) < 2:
        return float("inf")
    n = len(next(r for r in per.values() if r is not None))
    rng = np.random.default_rng(seed)
    mins = []
    for _ in range(resamples):
        idx = rng.integers(0, n, n)
        t = _table(per, use_t, idx)
        v = _vertex(t)
        mins.append(_argmin(t)[0] if v is None else v)
    return float(np.std(mins, ddof=1))


def calibrate_second(cand: Mapping, par: str, runs, data, use, prior, train: Sequence[int]
                     ) -> tuple[float, dict[float, float], str, float]:
    """``par`` on its grid (:data:`GRIDS`) by :func:`training_score` on the runs ``train``, the grid's best
    refined by the parabola's vertex (kept if lower). Returns the value, the table, its status and its
    :func:`bootstrap_se`: ``"not determined"`` at the grid's end or when the SE is not below the value's
    magnitude (the rule of the covariance machinery), else ``"calibrated"``."""
    use_t = [use[i] for i in train]
    per = _replays(cand, par, GRIDS[par], runs, data, prior, train)
    table = _table(per, use_t)
    best, i, g = _argmin(table)
    a = _vertex(table)
    if a is not None:
        table.update(_table(_replays(cand, par, [a], runs, data, prior, train), use_t))
        if table[a] < table[best]:
            best = a
    se = bootstrap_se(per, use_t)
    determined = 0 < i < len(g) - 1 and se < abs(best)
    return float(best), table, "calibrated" if determined else "not determined", se


def calibrated(cand: Mapping, runs, data, use, prior, train: Sequence[int]) -> tuple[dict, dict[str, Any]]:
    """``cand`` with its own calibrated particular (:func:`shipid.methods.mmg.rudder_angle.calibrated`) and then
    its :data:`SECOND` one set on the runs ``train``, and what was calibrated."""
    par2 = cand.get(SECOND)
    c, a = RA.calibrated({k: v for k, v in cand.items() if k != SECOND}, runs, data, use, prior, train)
    info: dict[str, Any] = {"calibrated": a}
    if par2:
        v, table, status, se = calibrate_second(c, par2, runs, data, use, prior, train)
        c = with_asymmetry(c, v, par2)
        info.update(second=par2, second_value=v, second_status=status, second_se=se,
                    second_table={f"{k:.6g}": t for k, t in sorted(table.items())})
    return c, info


def resolve(trials, runs, prior: mmg.MmgModel, cand: Mapping, config: R.FitConfig = R.FitConfig()):
    """The ``resolve`` of :func:`shipid.methods.mmg.pipeline.identify` for these candidates: the candidate's own
    particular by :func:`shipid.methods.mmg.rudder_angle.resolve`, then its :data:`SECOND` one by
    :func:`calibrate_second` on all the given runs. Returns the candidate to fit and what was calibrated."""
    par2 = cand.get(SECOND)
    c, info = RA.resolve(trials, runs, prior, {k: v for k, v in cand.items() if k != SECOND}, config)
    if not par2:
        return c, info
    data = [TS.replay_data(tr) for tr in trials]
    v, table, status, se = calibrate_second(c, par2, runs, data, TS.peak_runs(trials), prior, list(range(len(runs))))
    out = dict(info or {})
    out["second"] = {"parameter": par2, "value": v, "status": status, "se": se,
                     "training_score": {f"{k:.6g}": t for k, t in sorted(table.items())},
                     "criterion": "RMS peak-yaw-rate error (%, switch >= 5 deg) + RMS whole-run heading RMS (deg, "
                                  "all runs) of the open-loop replays of the given runs",
                     "note": "held fixed at this value in the regression: its uncertainty is not in the covariance"}
    return with_asymmetry(c, v, par2), out


def cross_validate(cands: Mapping[str, Mapping] | None = None, *, names: Sequence[str] = RA.RUNS,
                   root: Path | None = None, progress=None) -> dict[str, Any]:
    """The forward-fold CV of the module docstring: per fold and candidate what was calibrated, the
    :func:`shipid.methods.mmg.rudder_angle.score_rows` numbers and the per-run replays; :func:`decide`; and
    :func:`yaw_balance` of every run."""
    cands = candidates() if cands is None else cands
    prior, trials, runs, data, use = RA.load_runs(names, root)
    folds: dict[str, Any] = {}
    for fold, train, test in RA.fold_sets(names):
        row: dict[str, Any] = {"train": [names[i] for i in train], "scored": [names[i] for i in test]}
        for cname, cand in cands.items():
            c, info = calibrated(cand, runs, data, use, prior, train)
            model = fit_candidate([runs[i] for i in train], prior, c)
            rep = TS.batch_replay([(model, i) for i in test], data)
            row[cname] = {**info, **RA.score_rows(rep), "runs": dict(zip(row["scored"], rep))}
            if progress is not None:
                progress(f"{fold}: {cname} {row[cname]['score']:.2f}")
        folds[fold] = row
    return {"folds": folds, "decision": decide(folds, list(cands)),
            "yaw_balance": {n: yaw_balance(tr) for n, tr in zip(names, trials)}}


def leave_one_out(cand_names: Sequence[str] = (CURRENT, CURRENT + "/neutral-angle"), *,
                  names: Sequence[str] = RA.RUNS, root: Path | None = None, progress=None) -> dict[str, Any]:
    """A diagnostic, not a selection: each run left out in turn, the candidates calibrated (:func:`calibrated`)
    and fitted on the other runs, the left-out run replayed; per candidate the per-run numbers and
    :func:`shipid.methods.mmg.rudder_angle.score_rows` over all left-out runs. This interpolates in angle
    (the final model is fitted on every angle), where the forward folds extrapolate."""
    cands = candidates()
    prior, trials, runs, data, use = RA.load_runs(names, root)
    per: dict[str, dict[str, Any]] = {c: {} for c in cand_names}
    for i, n in enumerate(names):
        train = [j for j in range(len(names)) if j != i]
        for cname in cand_names:
            c, info = calibrated(cands[cname], runs, data, use, prior, train)
            model = fit_candidate([runs[j] for j in train], prior, c)
            per[cname][n] = {**TS.batch_replay([(model, i)], data)[0], **{k: v for k, v in info.items()
                                                                         if k != "second_table"}}
            if progress is not None:
                progress(f"left out {n}: {cname} psi {per[cname][n]['psi_rms']:.2f}")
    return {c: {"runs": per[c], **RA.score_rows([per[c][n] for n in names if use[names.index(n)]])}
            for c in cand_names}


def decide(folds: Mapping[str, Mapping], names: Sequence[str]) -> dict[str, Any]:
    """The decision rule of the module docstring: mean and spread of the fold score per candidate, folds
    better than :data:`CURRENT`, and the choice."""
    sc = {c: np.array([folds[f][c]["score"] for f in folds], float) for c in names}
    mean = {c: float(v.mean()) for c, v in sc.items()}
    spread = {c: float(v.std(ddof=1)) if v.size > 1 else 0.0 for c, v in sc.items()}
    better = {c: int(np.sum(sc[c] < sc[CURRENT])) for c in names}
    best = min(names, key=lambda c: mean[c])
    new = best not in ("default", CURRENT)
    wins = new and mean[best] < mean[CURRENT] and better[best] >= MIN_FOLDS_BETTER
    return {"mean_score": mean, "fold_spread": spread, "folds_better_than_current": better,
            "best_mean": best, "chosen": best if wins else CURRENT}


def yaw_balance(trial) -> dict[str, float]:
    """First-order Nomoto fit ``ṙ = a δ + b r + c`` from execute (least squares, ``ṙ`` by central differences):
    the neutral rudder angle ``δ_n = −c/a`` (deg) with its standard error (delta method), the mean yaw rate
    (deg/s) and the mean rudder (deg) over the run. The SE is optimistic (autocorrelated residuals)."""
    k0 = execute_index(trial["delta"])
    t = np.asarray(trial.t[k0:], float)
    r = V.measured_states(trial)[k0:, 5]
    d = V.trial_inputs(trial)[k0:, 0]
    rd = np.gradient(r, t)
    A = np.stack([d, r, np.ones_like(d)], axis=-1)
    coef, *_ = np.linalg.lstsq(A, rd, rcond=None)
    res = rd - A @ coef
    dof = max(A.shape[0] - 3, 1)
    C = np.linalg.inv(A.T @ A) * float(res @ res) / dof
    a, _, c = coef
    g = np.array([c / a ** 2, 0.0, -1.0 / a])
    se = float(np.sqrt(max(g @ C @ g, 0.0)))
    return {"delta_n_deg": float(np.degrees(-c / a)), "delta_n_se_deg": float(np.degrees(se)),
            "r_mean_deg_s": float(np.degrees(r.mean())), "delta_mean_deg": float(np.degrees(d.mean()))}


def heading_by_run(res: Mapping[str, Any]) -> dict[str, dict[str, float]]:
    """Whole-run heading RMS (deg) per candidate and scored run, from the first fold that scores the run."""
    out: dict[str, dict[str, float]] = {}
    for row in res["folds"].values():
        for c, r in row.items():
            if c in ("train", "scored"):
                continue
            for n, x in r["runs"].items():
                out.setdefault(c, {}).setdefault(n, float(x["psi_rms"]))
    return out


def format_cv(res: Mapping[str, Any]) -> str:
    """Per fold and candidate: calibrated values, score and parts; per candidate the mean and the spread over
    folds; whole-run heading RMS per run (fold 10-15 models; larger folds for runs it does not score); the
    yaw balance of the runs; the decision."""
    lines = [f"  {'fold':<6} {'candidate':<32} {'b':>8} {'second':>16} {'score':>7} {'r_pk%':>6} {'stbd%':>7} "
             f"{'port%':>7} {'psi°':>6}"]
    for f, row in res["folds"].items():
        for c, r in row.items():
            if c in ("train", "scored"):
                continue
            b = "" if r["calibrated"] is None else f"{r['calibrated']:.4g}"
            s = ""
            if r.get("second"):
                v = r["second_value"]
                deg = r["second"] == "rudder_neutral_angle"
                se = r["second_se"]
                s = (f"{np.degrees(v):.3g}+-{np.degrees(se):.2g}deg" if deg else f"{v:.3g}+-{se:.2g}")
                s += "?" if r["second_status"] != "calibrated" else ""
            lines.append(f"  {f:<6} {c:<32} {b:>8} {s:>16} {r['score']:7.2f} {r['r_peak_rms_pct']:6.2f} "
                         f"{r['r_peak_stbd_mean_pct']:+7.2f} {r['r_peak_port_mean_pct']:+7.2f} {r['psi_rms_deg']:6.2f}")
    lines.append("  (second: value +- run-bootstrap SE; '?': not determined, at the grid's end or SE >= |value|)")
    d = res["decision"]
    lines.append("  mean fold score +- spread (folds better than " + CURRENT + "):")
    for c, v in d["mean_score"].items():
        lines.append(f"    {c:<32} {v:6.2f} +- {d['fold_spread'][c]:5.2f} ({d['folds_better_than_current'][c]})")
    hb = heading_by_run(res)
    runs = list(next(iter(hb.values())))
    lines.append("  whole-run heading RMS deg per scored run: " + " ".join(n.split("_Z_")[1][:-4] for n in runs))
    for c, per in hb.items():
        lines.append(f"    {c:<32} " + " ".join(f"{per[n]:6.2f}" for n in runs))
    lines.append("  yaw balance of each run (Nomoto fit): delta_n deg +- SE; mean r deg/s; mean delta deg")
    for n, y in res["yaw_balance"].items():
        lines.append(f"    {n.split('_Z_')[1][:-4]:<8} {y['delta_n_deg']:+6.2f} +- {y['delta_n_se_deg']:.2f}; "
                     f"{y['r_mean_deg_s']:+.3f}; {y['delta_mean_deg']:+.3f}")
    lines.append(f"  decision rule: lowest mean '{d['best_mean']}'; chosen '{d['chosen']}'")
    return "\n".join(lines)


__all__ = ["SECOND", "NEUTRAL_GRID", "PROP_SIDE_GRID", "GRIDS", "MIN_FOLDS_BETTER", "CURRENT", "candidates",
           "BOOTSTRAP", "training_score", "bootstrap_se", "calibrate_second", "calibrated", "resolve", "cross_validate", "leave_one_out", "decide", "yaw_balance",
           "heading_by_run", "format_cv"]
