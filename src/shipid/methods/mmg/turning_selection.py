"""Structure selection for the KVLCC2 (Yasukawa 2015 structure) on what a turning circle measures.

``shipid identify mmg --prior kvlcc2_hsva --selection turning`` chooses among :data:`TURNING_CANDIDATES` by
:func:`select_for_turning`, a leave-one-run-out (or ``folds``-fold) cross-validation over
the TRAINING runs whose fold errors are those of an open-loop replay of each left-out run
(:func:`batch_replay`: the measured rudder and propeller replayed from the measured state at execute over
the whole run, the way a turning circle of another basin is predicted):

* the relative error of the peak yaw rate reached on each side (%), the quantity that sets
  a turning circle's diameter (``D ≈ 2 U / r`` in the steady turn), and
* the RMS heading error over the whole replay (deg),

pooled over all folds' left-out zig-zags with a switch heading of :data:`MIN_SWITCH_DEG` or more (the
1°-switch runs are excluded a priori: their yaw-rate peaks are a few tenths of a degree per second and set
by the switching, not by the turn; a run whose file name does not give its angles is kept). Score
(:data:`DEFAULT_CRITERION` ``"peak"``) = RMS over runs and sides of the peak-yaw-rate errors (%), lower is
better, the first listed on a tie; ``"peak+heading"`` adds the RMS over runs of the heading RMS (deg). The
heading RMS is reported in the table either way.

Candidates (fixed a priori; a full factorial over the first three axes):
free set (``full``, ``linear-hull+rudder``, ``hull-only``) × flow straightening γ_R (the
prior's per-side values | their symmetric mean) × rudder normal force (standard ``f_α sin α_R``
| with the cross-flow drag part ``C_Dc sin α_R |sin α_R|``, ``C_Dc = 1`` fixed after Hoerner,
Fluid-Dynamic Lift 1985 ch. 3, not tuned; ``rudder_crossflow`` of
:func:`shipid.models.mmg_forces.basis_yasukawa`), plus, for the three free sets with symmetric
γ_R and ``C_Dc = 1``, the port/starboard rudder effectiveness ``F_N (1 + s sign δ)``
(``rudder_side_gain``) calibrated on the training runs' peak yaw rates (:func:`calibrate_folds`: grid
:data:`SIDE_GAIN_GRID` refined by the vertex of a parabola, :func:`refine_minimum`). The first six are
the candidate list :data:`shipid.methods.mmg.candidates.CANDIDATES` of the ``yasukawa2015`` structure.

A calibrated candidate is calibrated INSIDE each fold on that fold's training runs only
(and, for the identified model, on all training runs): the left-out runs never enter its
side gain. The replays of all candidates, folds and grid values are integrated together,
one RK4 batch per structure and particulars (the side gain varies per row;
:func:`shipid.methods.mmg.manoeuvres.rows_rk4`).

The cross-validation tables behind the candidates and the criterion (HSVA zig-zags only):
``docs/validation/mmg.md``, "KVLCC2 HSVA zig-zags", "Selection for turning".
"""


from __future__ import annotations

import json
import re
from dataclasses import replace as _replace
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from shipid.io.trial import Trial
from shipid.errors import InputError, ShipidError
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import manoeuvres as MM
from shipid.methods.mmg import validate as V
from shipid.methods.mmg.candidates import CANDIDATES, apply_candidate, candidate_config
from shipid.models import mmg
from shipid.models.mmg_forces import RUDDER_LARGE_ANGLE

#: Port/starboard rudder-effectiveness values tried (``rudder_side_gain``).
SIDE_GAIN_GRID = (-0.15, -0.1, -0.05, 0.0, 0.05, 0.1, 0.15)
#: Smallest switch heading (deg) of a zig-zag whose peak yaw rates enter the criterion.
MIN_SWITCH_DEG = 5.0

#: Key of a candidate whose particular of that name is calibrated on the training runs.
CALIBRATE = "calibrate"
#: The calibrated particular (port/starboard rudder effectiveness).
PARAMETER = "rudder_side_gain"


def turning_candidates() -> dict[str, dict]:
    """The six yasukawa2015 candidates, each also with ``C_Dc = 1``, and three side-gain-calibrated ones: 15
    (module docstring)."""
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


# ----------------------------------------------------------------------------- zig-zags and candidates
def zigzag_angles(name: str) -> tuple[float, float]:
    """(rudder, switch heading) in rad from an HSVA file name ``..._Z_20_10_P.dat``."""
    m = re.search(r"_Z_(\d+)_(\d+)", name)
    if not m:
        raise InputError(f"cannot read the zig-zag angles from '{name}'")
    return np.deg2rad(float(m.group(1))), np.deg2rad(float(m.group(2)))


def execute_index(delta: np.ndarray, threshold: float = np.deg2rad(1.0)) -> int:
    """First sample where the rudder has moved more than ``threshold`` from its initial value."""
    k = np.flatnonzero(np.abs(delta - delta[0]) > threshold)
    if k.size == 0:
        raise InputError("no rudder execute found")
    return max(int(k[0]) - 1, 0)


def with_asymmetry(cand: Mapping, a: float, parameter: str = "gamma_R_asymmetry") -> dict:
    """``cand`` with the particular ``parameter`` set to ``a`` (for the γ_R asymmetry fraction, in place
    of any γ_R override of its own; ``"rudder_side_gain"``: the port/starboard rudder effectiveness
    ``F_N (1 + s sign δ)`` of :func:`shipid.models.mmg_forces.basis_yasukawa`)."""
    c = dict(cand)
    drop = ("gamma_R", "gamma_R_asymmetry") if parameter == "gamma_R_asymmetry" else (parameter,)
    part = {k: v for k, v in (cand.get("particulars") or {}).items() if k not in drop}
    part[parameter] = float(a)
    c["particulars"] = part
    return c


def fit_candidate(runs: Sequence[R.SmoothedRun], prior: mmg.MmgModel, cand: Mapping,
                  config: R.FitConfig = R.FitConfig()) -> mmg.MmgModel:
    """The regression fit of ``cand`` on ``runs``."""
    cprior, free = apply_candidate(prior, cand)
    return R.fit(runs, cprior, free, candidate_config(config, cand)).model


def refine_minimum(x: Sequence[float], y: Sequence[float]) -> float:
    """Vertex of the parabola through three points whose middle one is lowest (clipped to their span)."""
    (x0, x1, x2), (y0, y1, y2) = x, y
    den = (x0 - x1) * (x0 - x2) * (x1 - x2)
    A = (x2 * (y1 - y0) + x1 * (y0 - y2) + x0 * (y2 - y1)) / den
    B = (x2 * x2 * (y0 - y1) + x1 * x1 * (y2 - y0) + x0 * x0 * (y1 - y2)) / den
    if not A > 0:
        return float(x1)
    return float(np.clip(-B / (2 * A), x0, x2))


# ----------------------------------------------------------------------------- batched replays
def replay_data(tr: Trial) -> dict[str, Any]:
    """What :func:`batch_replay` integrates for one run: the measured state at execute, the inputs, the steps."""
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
    """Open-loop replay of every row ``(model, run index into data)`` from the measured state at execute with
    the measured rudder and propeller, integrated as one batch per structure and particulars: the whole-run
    heading RMS error ``psi_rms`` (deg) and the relative error of the peak yaw rate reached on each side,
    ``r_peak_{stbd,port}_err_pct`` (%)."""
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
    (:func:`zigzag_angles`)."""
    try:
        return zigzag_angles(Path(str(tr.meta.get("source", ""))).name)
    except InputError:
        return None


def peak_runs(trials: Sequence[Trial]) -> list[bool]:
    """Per run: does its peak yaw rate enter the criteria (switch ≥ MIN_SWITCH_DEG, or angles unknown)."""
    angles = [trial_angles(tr) for tr in trials]
    return [True if a is None else bool(np.degrees(a[1]) >= MIN_SWITCH_DEG - 1e-9) for a in angles]


def _fit(runs, prior, cand, config):
    """:func:`fit_candidate`, or None where the fit fails."""
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
    """The value of ``parameter`` with the lowest peak score on each training set, each on ITS runs only
    (indices into ``runs``/``data``), the replays of all training sets batched.

    Peak score: the RMS over the set's runs with ``use`` (switch ≥ :data:`MIN_SWITCH_DEG`) and both sides
    of the open-loop peak-yaw-rate error (%) of the candidate fitted on the set with that value. The
    grid's best (the first on a tie), then, for an interior best, the vertex of the parabola through it
    and its neighbours' mean-square scores (:func:`refine_minimum`), kept if it scores lower. Returns
    ``(value, {value tried: peak score})`` per set."""
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
#: ``docs/validation/mmg.md``: chosen on HSVA runs only).
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


__all__ = ["CALIBRATE", "PARAMETER", "ROW_PARTICULARS", "TURNING_CANDIDATES", "turning_candidates", "replay_data", "batch_replay",
           "trial_angles", "peak_runs", "calibrate_folds", "resolve", "select_for_turning", "METHOD", "CRITERIA",
           "DEFAULT_CRITERION", "SIDE_GAIN_GRID", "MIN_SWITCH_DEG", "zigzag_angles", "execute_index", "with_asymmetry",
           "fit_candidate", "refine_minimum"]
