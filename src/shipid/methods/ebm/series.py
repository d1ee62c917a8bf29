"""Report series of Estimation-Before-Modelling (Yoon & Rhee 2003).

On request (:func:`with_series`; ``identify`` never does this work), :func:`build` turns the step-1
state estimates and the step-2 ridge fits into the :mod:`shipid.report.convention` entries that
``shipid report`` draws for an ``ebm`` result:

* ``signals`` (paper Figs 4, 9) — per trial, the smoothed relative velocities ``u_r, v_r``,
  yaw rate ``r``, hydrodynamic forces ``X, Y`` and moment ``N`` and the current ``c_x, c_y``
  with the smoother's σ; on simulated trials the true values are drawn beside them.
* ``matrices["regressor_correlation_<mode>"]`` (Tables 1–2) — ``WᵀW`` of the unit-length-scaled
  regressors of eq. 16 for surge and sway (the yaw regressors are ``L`` times the sway ones, so
  their matrix is the same), with the regressor names.
* ``tables["conditioning"]`` (Table 4) — κ, R, R², Mallows Cp, the ridge parameter k, p, n per mode.
* ``overlays["<force>_fit"]`` — for the first trial, the smoothed force of step 1 against the
  step-2 regression model ``H θ`` (eq. 14; kind ``"fit"``): the residual is what the Abkowitz
  model does not explain.
* ``residuals["innovation_<measurement>"]`` — the step-1 EKF innovations of the first trial with
  their predicted σ (√ of the diagonal of S).

Opt-in extras (they simulate the ship, seconds each):

* :func:`validation_overlays` (Figs 6, 10) — a held-out simulated trial against the identified
  model driven by the same PRBS rudder (``kind = "validation"``);
* :func:`d_optimal_contour` (Fig. 7) — ``log10 |WᵀW|`` over PRBS amplitude × clock period from
  :func:`shipid.methods.ebm.design.prbs_grid` (a coarse grid by default).
"""

from __future__ import annotations

import copy
import os
import warnings
from typing import Mapping, Sequence

import numpy as np

from shipid.methods._series import first_unreproduced, noted, recorded_call
from shipid.methods._trials import as_list, as_trial
from shipid.methods.ebm.design import paper_comparison, prbs_grid
from shipid.methods.ebm.estimator import EbmConfig, EbmRun, identify_run
from shipid.methods.ebm.pipeline import REQUIRED
from shipid.methods.ebm.trials import simulate_trial
from shipid.models import abkowitz as ab
from shipid.report.convention import contour, matrix, overlay, residual, signal, table, trial_summary

#: (name in the series, label, state index, unit, true channel of simulated trials)
SIGNALS = (
    ("velocity", "relative velocities", ((0, "u_r", "true_u_r"), (1, "v_r", "true_v_r")), "m/s"),
    ("yaw_rate", "yaw rate", ((2, "r", "true_r"),), "rad/s"),
    ("force_X", "surge force X", ((6, "X", "true_X"),), "N"),
    ("force_Y", "sway force Y", ((9, "Y", "true_Y"),), "N"),
    ("moment_N", "yaw moment N", ((12, "N", "true_N"),), "N*m"),
    ("current", "current", ((15, "c_x", None), (16, "c_y", None)), "m/s"),
)
MEAS = (("psi", 4, "rad"), ("u_log", 5, "m/s"))


def _name(trial, k: int) -> str:
    """A short name of a trial: its manoeuvre (simulated), else its file, else its number."""
    m = trial.meta
    if m.get("manoeuvre"):
        return f"{m['manoeuvre']} trial" + (f" (seed {m['seed']})" if "seed" in m else "")
    return str(m.get("source") or f"trial {k + 1}")


def signals(states, *, every: int = 1) -> dict:
    """Smoothed motion, forces and current of every trial (Figs 4, 9) as ``signals`` entries."""
    out = {}
    for k, st in enumerate(states):
        tag = f"t{k + 1}"
        src = _name(st.trial, k)
        t = st.smooth.t[::every] - st.smooth.t[0]
        x, sd = st.smooth.x[::every], st.smooth.std[::every]
        for name, label, cols, unit in SIGNALS:
            lines, std = {}, {}
            for i, nm, true in cols:
                lines[f"{nm} smoothed"] = x[:, i]
                std[f"{nm} smoothed"] = sd[:, i]
                if true and true in st.trial.channels:
                    lines[f"{nm} true"] = np.asarray(st.trial[true], dtype=float)[::every]
            has_true = any(c[2] and c[2] in st.trial.channels for _, _, cs, _ in SIGNALS for c in cs)
            out[f"{tag}_{name}"] = signal(t, lines, unit, std=std, label=label, paper="Figs 4, 9",
                                          title=f"Step 1 (EKF + {st.smooth.method.upper()} smoother) of {src}: "
                                                "smoothed motion, forces and current (shaded: ±2σ)"
                                                + ("; 'true': the simulation's values." if has_true else "."))
    return out


def correlation_matrices(fit) -> dict:
    """Tables 1–2: ``WᵀW`` of each mode's scaled regressors, with the coefficient names of eq. 13."""

    out = {}
    names = {"surge": ab.THETA_X_NAMES, "sway": ab.THETA_Y_NAMES, "yaw": ab.THETA_N_NAMES}
    # the yaw regressors are L times the sway ones (eq. 14): their scaled WᵀW is the sway matrix
    for mode, f in (("surge", fit.surge), ("sway", fit.sway)):
        C = np.asarray(f.correlation, dtype=float)
        n = names[mode] if len(names[mode]) == C.shape[0] else [str(i + 1) for i in range(C.shape[0])]
        out[f"regressor_correlation_{mode}"] = matrix(
            C, n, n, unit="correlation [-]", vmin=-1.0, vmax=1.0, annotate=True,
            paper="Table 1" if mode == "surge" else "Table 2",
            title=f"Correlation WᵀW of the unit-length-scaled {mode} regressors (eq. 16)"
                  + ("; the yaw regressors are L times these, same matrix" if mode == "sway" else "")
                  + "; |ρ| near 1: "
                  "collinear, their coefficients are hard to separate.")
    return out


def conditioning_table(fit) -> dict:
    """Table 4: κ, R, Cp (and R², k, p, n) per mode."""
    rows = []
    for mode, f in (("surge", fit.surge), ("sway", fit.sway), ("yaw", fit.yaw)):
        r2 = float(f.R2)
        rows.append([mode, float(f.kappa), float(np.sqrt(r2)) if r2 >= 0 else float("nan"), r2, float(f.Cp),
                     float(f.k), int(f.p), int(f.n)])
    return table(["mode", "κ", "R", "R²", "Cp", "ridge k", "p", "n"], rows, paper="Table 4",
                 title="Collinearity and fit of the ridge regression per mode: condition number κ of WᵀW, "
                       "multiple correlation R, Mallows Cp, Hoerl–Kennard ridge parameter k.")


def force_fit_overlays(states, fit) -> dict:
    """Smoothed force (step 1) vs regression model ``H θ`` (step 2) over the first trial."""
    n0 = states[0].smooth.t.size
    t = states[0].smooth.t - states[0].smooth.t[0]
    d = fit.data
    src = _name(states[0].trial, 0)
    out = {}
    for key, H, y, f, label, unit in (("X", d.HX, d.X, fit.surge, "surge force X", "N"),
                                      ("Y", d.HY, d.Y, fit.sway, "sway force Y", "N"),
                                      ("N", d.HN, d.N, fit.yaw, "yaw moment N", "N*m")):
        if H.shape[0] < n0:
            continue
        model = H[:n0] @ np.asarray(f.theta, dtype=float)
        out[f"{key}_fit"] = overlay(t, y[:n0], model, unit, kind="fit", label=f"{label} ({src})",
                                    title=f"{label} of {src}: smoothed by step 1 and predicted by the identified "
                                          "model (eq. 14, step-2 ridge fit); residual with its autocorrelation.")
    return out


def innovations(states) -> dict:
    """Step-1 EKF innovations of the first trial with their predicted σ."""
    st = states[0]
    fr = st.filt
    t = np.asarray(fr.t, dtype=float) - float(fr.t[0])
    sd = np.sqrt(np.clip(np.einsum("kii->ki", np.asarray(fr.S, dtype=float)), 0.0, None))
    src = _name(st.trial, 0)
    out = {}
    for name, j, unit in MEAS:
        v = np.asarray(fr.innov, dtype=float)[:, j]
        out[f"innovation_{name}"] = residual(
            t, v, unit, std=np.where(np.isfinite(v), sd[:, j], np.nan), label=f"step-1 innovation of {name}",
            title=f"Step-1 EKF innovation of {name} ({src}, last pass) with the predicted ±2σ; about 95 % inside "
                  "and white for a consistent filter.")
    return out


def inputs(states) -> list[dict]:
    """``provenance["inputs"]``: a trial summary per trial (the channels EBM uses)."""

    out = []
    for k, st in enumerate(states):
        tr = st.trial
        try:
            name = str(tr.meta["source"]) if tr.meta.get("format") and tr.meta.get("source") else _name(tr, k)
            out.append(trial_summary(tr, name=name,
                                     channels=[c for c in REQUIRED if c in tr.channels]))
        except Exception:  # noqa: BLE001
            out.append({"name": str(tr.meta.get("source", f"trial {k + 1}"))})
    return out


def build(states, fit) -> dict:
    """All cheap series of an EBM result (see the module docstring); never raises.

    Returns the ``series`` dict (a part that fails is left out and named under ``"_problems"``).
    """
    series: dict = {}
    problems = []
    for what, kind, fn in (("signals", "signals", lambda: signals(states)),
                           ("correlation", "matrices", lambda: correlation_matrices(fit)),
                           ("conditioning", "tables", lambda: {"conditioning": conditioning_table(fit)}),
                           ("force fit", "overlays", lambda: force_fit_overlays(states, fit)),
                           ("innovations", "residuals", lambda: innovations(states))):
        try:
            series.setdefault(kind, {}).update(fn())
        except Exception as err:  # noqa: BLE001 - report extras must never lose the estimate
            problems.append(f"report series: {what} not built ({type(err).__name__}: {err})")
    if problems:
        series["_problems"] = problems
    return series


def attach(result, states, fit) -> None:
    """Add :func:`build` to ``result.series`` (entries already there are kept) and record the inputs."""
    series = build(states, fit)
    for p in series.pop("_problems", []):
        result.diagnostics.setdefault("warnings", []).append(p)
    for kind, part in (result.series or {}).items():
        if isinstance(part, Mapping) and isinstance(series.get(kind), dict):
            series[kind].update(part)
        else:
            series[kind] = part
    result.series = series
    result.provenance["inputs"] = inputs(states)


def with_series(fit, *, trials: Sequence | None = None):
    """A result with its report series: smoothed states and forces (Figs 4, 9), Tables 1, 2 and 4, force fits,
    step-1 innovations and the trial summaries.

    ``fit`` is an :class:`~shipid.methods.ebm.estimator.EbmRun` (:func:`~shipid.methods.ebm.estimator.identify_run`;
    its result is completed in place and returned) or a stored ``ebm`` :class:`~shipid.result.Result`
    (``Result.with_series()``, ``shipid report``). For a stored result the trials are ``trials`` (trials or
    paths, as ``shipid.identify("ebm", ...)`` takes them), else the files it records
    (``provenance["ebm_call"]``); both EBM steps are run again with the recorded vessel and configuration,
    and a copy of the result gets the series when that reproduces every stored estimate exactly (else,
    or when a file is missing, a copy with one warning saying why). A result that records no files and is
    given no trials, or that already has the smoothed signals, comes back unchanged.
    """
    if isinstance(fit, EbmRun):
        attach(fit.result, fit.states, fit.fit)
        return fit.result
    return _from_trials(fit, trials)



def _config(d: Mapping | None) -> EbmConfig:
    """The :class:`EbmConfig` recorded in ``provenance["ebm_call"]["config"]`` (lists back to tuples)."""
    known = EbmConfig.__dataclass_fields__
    return EbmConfig(**{k: (tuple(v) if isinstance(v, list) else v) for k, v in dict(d or {}).items() if k in known})


def _from_trials(result, trials):
    """:func:`with_series` of a stored result (see there)."""
    call = recorded_call(result, "ebm", "ebm_call", "signals")
    if call is None:
        return result
    vessel = str(call.get("vessel") or "esso-osaka")
    if trials is None:
        files = call.get("files") or []
        if not files or any(not isinstance(p, str) for p in files):
            return result
        missing = [p for p in files if not os.path.isfile(p)]
        if missing:
            return noted(result, f"trial file not found: {missing[0]} (give the trials: with_series(trials=...))")
        trials = files
    try:
        data = [as_trial(x, required=list(REQUIRED), method="ebm", vessel=vessel) for x in as_list(trials)]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            run = identify_run(data, vessel, config=_config(call.get("config")))
    except Exception as err:  # noqa: BLE001 - the report must still be written
        return noted(result, f"{type(err).__name__}: {' '.join(str(err).split())[:160]}")
    n = first_unreproduced(result, run.result)
    if n is not None:
        return noted(result, f"EBM on these trials gives {n} = {run.result.value(n):.6g}, not the stored "
                              f"{result.value(n):.6g} (other trials or files changed?)")
    out = copy.deepcopy(result)
    attach(out, run.states, run.fit)
    return out


# ---------------------------------------------------------------------------------------------------
# opt-in extras (simulations)
# ---------------------------------------------------------------------------------------------------
def validation_overlays(result, manoeuvre: str = "prbs-10-40", duration: float = 300.0, seed: int = 500,
                        vessel: str = "esso-osaka") -> dict:
    """Figs 6, 10: a held-out simulated trial (measured, with noise) against the identified model.

    The held-out trial is :func:`shipid.methods.ebm.trials.simulate_trial` of ``manoeuvre`` with the
    true coefficients and measurement noise; the model run uses the coefficients in ``result`` and
    the same seed (so the same PRBS rudder sequence), no noise.
    """

    p = ab.params_from_vessel(vessel)
    th = lambda names: tuple(float(result.estimates[n].value) for n in names)  # noqa: E731
    theta = p.with_theta(th(ab.THETA_X_NAMES), th(ab.THETA_Y_NAMES), th(ab.THETA_N_NAMES))
    meas = simulate_trial(manoeuvre, duration, seed=seed, vessel=vessel)
    model = simulate_trial(manoeuvre, duration, seed=seed, vessel=vessel, noise=False, theta=theta)
    t = meas.t - meas.t[0]
    out = {}
    for ch, label, unit in (("psi", "heading ψ", "rad"), ("U", "speed log U", "m/s")):
        out[f"{ch}_validation"] = overlay(
            t, meas[ch], model[ch], unit, kind="validation", label=f"{label} ({manoeuvre}, held out)",
            title=f"{label} of a held-out simulated {manoeuvre} trial (seed {seed}, with measurement noise) and the "
                  "identified model driven by the same rudder (not used for estimation).")
    return out


def add_validation(result, manoeuvre: str = "prbs-10-40", duration: float = 300.0, seed: int = 500,
                   vessel: str = "esso-osaka") -> None:
    """:func:`validation_overlays` into ``result.series["overlays"]``; a failure (e.g. an unstable
    identified model) becomes a warning, never an exception."""
    try:
        ov = validation_overlays(result, manoeuvre, duration, seed, vessel)
    except Exception as err:  # noqa: BLE001
        result.diagnostics.setdefault("warnings", []).append(
            f"report series: validation overlays not built ({type(err).__name__}: {err})")
        return
    result.series.setdefault("overlays", {}).update(ov)


def d_optimal_contour(grid) -> dict:
    """Fig. 7: ``contours["d_optimal"]`` from a :class:`shipid.methods.ebm.design.DesignGrid`."""
    a, per, val = grid.optimum("sway")
    return contour(grid.periods, grid.amplitudes, grid.sway, x_label="PRBS clock period", x_unit="s",
                   y_label="PRBS amplitude", y_unit="deg", z_label="log10 |WᵀW| (sway = yaw regressors)",
                   points=[{"x": per, "y": a, "label": "optimum"}], paper="Fig. 7",
                   title=f"D-optimality of the PRBS rudder input: log10 |WᵀW| of the sway regressors over amplitude "
                         f"× clock period ({grid.duration:g} s runs, {len(grid.seeds)} PRBS seed(s) per point, "
                         f"{grid.amplitudes.size} × {grid.periods.size} grid); optimum {a:g}° / {per:g} s on this grid "
                         "(the full map: shipid design prbs).")


#: Coarse grid of the demo and of ``identify ebm --figures`` (the paper's Fig. 7 spans 5–35° × 15–200 s).
#: Its runs are as long as the full map's (1200 s, :func:`shipid.methods.ebm.design.prbs_grid`), so that it
#: previews the same criterion: the criterion depends on how many rudder switches a run holds, and
#: 600-s runs (the first choice, a second cheaper) put the best point at 35° / 30 s instead. One PRBS seed
#: and dt = 2 s keep it to a few seconds; the caption of :func:`coarse_d_optimal` says it is coarse and
#: points to ``shipid design prbs --out``.
COARSE_AMPLITUDES = (10.0, 20.0, 35.0)
COARSE_PERIODS = (30.0, 60.0, 105.0, 200.0)
COARSE_DURATION = 1200.0


def coarse_d_optimal(vessel: str = "esso-osaka", *, amplitudes: Sequence[float] | None = None,
                     periods: Sequence[float] | None = None, duration: float | None = None,
                     dt: float = 2.0) -> dict:
    """A coarse Fig. 7 map (default :data:`COARSE_AMPLITUDES` × :data:`COARSE_PERIODS`, one PRBS seed,
    :data:`COARSE_DURATION` s at ``dt`` = 2 s: 12 noise-free simulations, a few seconds)."""

    grid = prbs_grid(COARSE_AMPLITUDES if amplitudes is None else amplitudes,
                     COARSE_PERIODS if periods is None else periods,
                     duration=COARSE_DURATION if duration is None else duration, seeds=(0,), dt=dt, vessel=vessel)
    c = d_optimal_contour(grid)
    # caption: say loudly that this is a coarse preview, so that its optimum is not read as the paper's answer
    a, per, _ = grid.optimum("sway")
    comp = paper_comparison(grid)
    c["points"][0]["label"] = "coarse-grid optimum"
    c["title"] = (f"COARSE preview only ({grid.amplitudes.size} × {grid.periods.size} grid: amplitudes "
                  f"{', '.join(f'{v:g}' for v in grid.amplitudes)}°, periods {', '.join(f'{v:g}' for v in grid.periods)} s; "
                  f"{grid.duration:g} s runs at dt = {grid.dt:g} s, {len(grid.seeds)} PRBS seed): log10 |WᵀW| of the "
                  f"sway (= yaw) regressors. Its best point is {a:g}° / {per:g} s; {comp['text']}. A coarse grid "
                  "of one PRBS realisation is no evidence of the D-optimal input: the criterion depends on how "
                  "many rudder switches a run holds and one realisation is a noisy sample. The map on a fine "
                  "grid with several seeds comes from `shipid design prbs --out RESULT.json` and "
                  "`shipid report RESULT.json`.")
    return c


__all__ = ["signals", "correlation_matrices", "conditioning_table", "force_fit_overlays", "innovations", "inputs",
           "build", "attach", "with_series", "validation_overlays", "add_validation", "d_optimal_contour", "coarse_d_optimal"]
