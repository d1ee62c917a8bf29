"""Report series of the mass / centre-of-mass method (Linder et al. 2015).

Builds the :mod:`shipid.report.convention` entries that ``shipid report`` draws for a
``mass-cm`` result, on request (:func:`with_series`), from what Algorithm 1 computed (no extra estimation):

* ``overlays["p_<condition>"]`` — measured roll rate ``p`` (record mean removed) against the
  identified model's *simulated* roll rate: the reduced roll model (18) with the final
  estimate, driven by the measured rudder and the black-box yaw-rate simulation (44), i.e. the
  noise-free signal (46) that Algorithm 1 uses as its instrument. The residual is
  measured − simulated (it contains the roll disturbance, so it need not be white).
* ``residuals["equation_error_<condition>"]`` — the prefiltered equation error (42)-(43) of the
  last iteration: the innovations of the estimated noise model, which the method assumes white;
  ``std`` is the square root of the noise model's innovation variance λ.
* ``contours["cost"]`` — paper Fig. 4: the IV criterion (40) of the last iteration (its
  instruments, prefilters and weights) over a grid of load mass ``m`` and centre ``zm_bar``, every
  other parameter at the estimate (as :func:`shipid.methods.masscm.contour.cost_grid`). A coarse
  :data:`CONTOUR_N` × :data:`CONTOUR_N` grid (about 20 µs per cost evaluation: ~15 ms).
* The time series above keep at most :data:`MAX_SERIES_POINTS` samples each (every k-th sample, k
  the smallest stride that fits; the title says k): a result's size is bounded whatever the record
  length. The statistics of the method (residual whiteness, innovation variances) use every sample.
* ``provenance["inputs"]`` — one :func:`~shipid.report.convention.trial_summary` per dataset.

And, for the Table-3 study (``shipid study mass-cm-sensitivity --out``),
:func:`spread_result` turns the study summary and the per-run outputs into a
:class:`~shipid.result.Result` with ``tables["spread"]`` and ``xy["spread"]``.
"""

from __future__ import annotations

import copy
import os
import warnings
from typing import Mapping, Sequence

import numpy as np

from shipid.methods._series import noted, recorded_call
from shipid.io.files import read_trial
from shipid.methods._trials import as_trial, grouped
from shipid.methods.masscm.assemble import MassCMFit, fit_mass_cm
from shipid.models.roll_reduced import KnownParams
from shipid.methods.masscm.criterion import residual_function
from shipid.methods.masscm.data import first_row
from shipid.methods.masscm.moments import closed_loop_sim, transient_length
from shipid.methods.masscm.options import REQUIRED, MassCMOptions
from shipid.models.roll_reduced import THETA_NAMES, THETA_UNITS, discrete_coeffs, roll_terms, to_moment
from shipid.models.roll_sim import simulate_datasets
from shipid.report.convention import contour, overlay, residual, table, trial_summary, xy
from shipid.result import Estimate, Result

#: Grid points per axis of the Fig. 4 cost map stored with every result (coarse: cheap).
CONTOUR_N = 25
#: Most samples kept per stored time series (overlay or residual); longer records are decimated by a stride.
MAX_SERIES_POINTS = 2000
#: Grid span: relative in m, absolute (m) in zm_bar (as :func:`shipid.methods.masscm.contour.cost_grid`).
SPAN_M, SPAN_Z = 0.05, 0.02


def cost_map(core: dict, known, n: int = CONTOUR_N, span_m: float = SPAN_M, span_z: float = SPAN_Z) -> dict:
    """Cost (40) on an ``n × n`` grid of (m, zm_bar) around the estimate of ``core`` (:func:`iterate`).

    Returns ``m`` (n,), ``zm_bar`` (n,), ``cost`` (n, n) with rows over ``zm_bar``.
    """
    th = np.asarray(core["theta"], dtype=float)
    im, iz = THETA_NAMES.index("m"), THETA_NAMES.index("zm_bar")
    fun, _ = residual_function(core["state"], known, np.ones(th.size, dtype=bool), to_moment(th), None)
    ms = th[im] * (1 + np.linspace(-span_m, span_m, n))
    zs = th[iz] + np.linspace(-span_z, span_z, n)
    C = np.empty((n, n))
    t = th.copy()
    for a, zm in enumerate(zs):
        for b, m in enumerate(ms):
            t[im], t[iz] = m, zm
            C[a, b] = float(np.sum(fun(to_moment(t)) ** 2))
    return {"m": ms, "zm_bar": zs, "cost": C}


def cost_contour(core: dict, known, n: int = CONTOUR_N, *, true: tuple[float, float] | None = None) -> dict:
    """``contours["cost"]`` (paper Fig. 4) from :func:`cost_map`; ``true`` = (m, zm_bar) adds a marker."""
    g = cost_map(core, known, n)
    th = np.asarray(core["theta"], dtype=float)
    pts = [{"x": float(th[THETA_NAMES.index("m")]), "y": float(th[THETA_NAMES.index("zm_bar")]),
            "label": "estimate"}]
    if true is not None:
        pts.append({"x": float(true[0]), "y": float(true[1]), "label": "true"})
    return contour(g["m"], g["zm_bar"], g["cost"], x_label="load mass m", x_unit="kg",
                   y_label="load centre z̄_m", y_unit="m", z_label="IV cost (40) [-]", log=True, points=pts,
                   paper="Fig. 4",
                   title=f"IV cost (40) of the last iteration over load mass and centre ({n} × {n} grid), other "
                         "parameters at the estimate; the valley follows constant load moment m·z̄_m.")


def _stride(n: int, max_points: int = MAX_SERIES_POINTS) -> int:
    """Smallest stride that keeps at most ``max_points`` of ``n`` samples."""
    return max(1, -(-int(n) // int(max_points)))


def _every(k: int) -> str:
    return "" if k == 1 else f" Stored every {k}-th sample (at most {MAX_SERIES_POINTS} per series)."


def model_overlays(core: dict, prep, known, options=None, max_points: int = MAX_SERIES_POINTS) -> tuple[dict, dict]:
    """Measured vs simulated roll rate per dataset, and the prefiltered equation errors.

    Returns ``(overlays, residuals)`` dicts of convention entries, each series decimated by a stride to at
    most ``max_points`` samples.
    """
    conds = [ds.condition for ds in prep]
    th_q = core["theta_q"]
    terms = roll_terms(th_q, known, conds, moment=True)
    G = discrete_coeffs(th_q, known, conds, np.array([ds.T for ds in prep]), moment=True)
    st = core["state"]
    ov, res = {}, {}
    count: dict[str, int] = {}
    for i, ds in enumerate(prep):
        count[ds.condition] = count.get(ds.condition, 0) + 1
        tag = ds.condition if count[ds.condition] == 1 else f"{ds.condition}_{count[ds.condition]}"
        t = np.arange(ds.y.size) * ds.T
        sim = closed_loop_sim(ds, terms, i, known)
        k = _stride(t.size, max_points)
        if sim is not None:
            ov[f"p_{tag}"] = overlay(t[::k], (ds.y - ds.y.mean())[::k], sim[0][::k], "rad/s", kind="fit",
                                     label=f"roll rate p ({tag})",
                                     title=f"Roll rate p of the {tag} dataset: measured (record mean removed) and "
                                           "simulated by the identified roll model (18) from the measured rudder "
                                           "and the black-box yaw rate (44); residual = roll not explained by "
                                           "rudder and yaw (waves, noise), with its autocorrelation and 95 % "
                                           "white-noise bounds." + _every(k))
        eps = ds.y - ds.Phi @ G[i]
        opts = options if options is not None else MassCMOptions()
        s = first_row(opts)
        L = st.L[i] if st is not None and i < len(st.L) else None
        ef = L.prefilter(eps)[s:] if L is not None else eps[s:]
        s += transient_length(L, ef.size, opts)            # the prefilter's start-up, as in the moments
        ef = ef[s - first_row(opts):]
        lam = float(st.lam[i]) if st is not None and i < len(st.lam) else float("nan")
        k = _stride(ef.size, max_points)
        ef = ef[::k]
        std = np.full(ef.size, np.sqrt(lam)) if np.isfinite(lam) and lam > 0 else None
        res[f"equation_error_{tag}"] = residual(
            t[s:][::k], ef, "rad/s", std=std, label=f"prefiltered equation error, {tag}",
            title=f"Prefiltered equation error (42)-(43) of the {tag} dataset at the last iteration (the noise "
                  "model's innovations, assumed white) with ±2√λ." + _every(k))
    return ov, res


def inputs(datasets: Sequence) -> list[dict]:
    """``provenance["inputs"]``: a :func:`trial_summary` per ``(condition, Trial)``."""
    out = []
    for cond, tr in datasets:
        try:
            chans = [c for c in REQUIRED if c in tr.channels]
            out.append(trial_summary(tr, name=tr.meta.get("source") or f"{cond} dataset", channels=chans,
                                     note=f"condition: {cond}"))
        except Exception:  # noqa: BLE001 - an odd trial object must not break the method
            out.append({"name": str(getattr(tr, "meta", {}).get("source", cond)), "note": f"condition: {cond}"})
    return out


def attach(result, core: dict, prep, known, options=None, datasets=None, *, contour_n: int = CONTOUR_N) -> None:
    """Add the report series (overlays, equation errors, Fig. 4 map) and input summaries to ``result``.

    ``contour_n = 0`` leaves the Fig. 4 map out (:func:`with_series` asks for it with ``cost_map=True``).

    Never raises: a part that fails is skipped with a warning in ``result.diagnostics["warnings"]``.
    """
    series = result.series if isinstance(result.series, dict) else {}
    result.series = series
    parts = (("overlays", lambda: model_overlays(core, prep, known, options)),
             ("Fig. 4 cost contour", lambda: cost_contour(core, known, contour_n) if contour_n else None))
    for what, fn in parts:
        try:
            out = fn()
        except Exception as err:  # noqa: BLE001 - report extras must never lose the estimate
            result.diagnostics.setdefault("warnings", []).append(
                f"report series: {what} not built ({type(err).__name__}: {err})")
            continue
        if out is None:
            continue
        if what == "overlays":
            ov, res = out
            if ov:
                series.setdefault("overlays", {}).update(ov)
            if res:
                series.setdefault("residuals", {}).update(res)
        else:
            series.setdefault("contours", {})["cost"] = out
    if datasets is not None:
        prov = result.provenance if isinstance(result.provenance, dict) else {}
        result.provenance = prov
        prov["inputs"] = inputs(datasets)


def with_series(fit, *, cost_map: bool = False, trials: Mapping | None = None) -> Result:
    """A result with its report series: roll-rate overlays, prefiltered equation errors, trial summaries and,
    with ``cost_map=True``, the Fig. 4 cost map on a :data:`CONTOUR_N` × :data:`CONTOUR_N` grid.

    ``fit`` is a :class:`~shipid.methods.masscm.assemble.MassCMFit` (:func:`~shipid.methods.masscm.assemble.fit_mass_cm`;
    its result is completed in place and returned) or a stored mass-cm :class:`~shipid.result.Result`
    (``Result.with_series()``, ``shipid report``): then the datasets are ``trials`` (the mapping
    ``{"nominal": ..., "calibration": ..., "loaded": ...}`` of trials or paths that ``shipid.identify("mass-cm", ...)``
    takes), else they are read again from the files the result records (``provenance["mass_cm_call"]``),
    Algorithm 1 is run with the recorded known parameters, options and
    initialisation, and a copy of the result gets the series when that reproduces the stored m exactly (for a
    result refined by ``refine="pem"``: Algorithm 1's m recorded in ``diagnostics["refine"]``, so the series are
    those of Algorithm 1's estimate, the refinement's start; else,
    or when a file is missing, a copy with one warning saying why; a result that records no files and is given
    no trials, or already has overlays, comes back unchanged). Report work on request: ``identify`` never does it;
    ``shipid identify mass-cm`` does it for the result it writes (``--cost-map`` adds the map).
    """
    if isinstance(fit, MassCMFit):
        attach(fit.result, fit.core, fit.prep, fit.known, fit.options, fit.datasets,
               contour_n=CONTOUR_N if cost_map else 0)
        return fit.result
    return _from_files(fit, cost_map, trials)


def _from_files(result, cost_map: bool, trials: Mapping | None = None):
    """:func:`with_series` of a stored result (see there)."""
    call = recorded_call(result, "mass-cm", "mass_cm_call", "overlays")
    if call is None:
        return result
    files = call.get("files") or []
    if trials is None:
        if not files or any(not isinstance(p, str) for _, p in files):
            return result
        missing = [p for _, p in files if not os.path.isfile(p)]
        if missing:
            return noted(result, f"dataset file not found: {missing[0]}")
    try:
        if trials is None:
            datasets = [(c, read_trial(p, required=["t", *REQUIRED], method="mass-cm")) for c, p in files]
        else:
            datasets = [(c, as_trial(t, required=["t", *REQUIRED], method="mass-cm"))
                        for c, ts in grouped(trials, ("nominal", "calibration", "loaded"), "mass-cm").items()
                        for t in ts]
        known = KnownParams(**(result.model or {})["known"])
        opts = {k: v for k, v in result.diagnostics["options"].items() if k in MassCMOptions.__dataclass_fields__}
        prior = call.get("z_f_prior")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fit = fit_mass_cm(datasets, known, theta0=call.get("theta0"), z_f=call.get("z_f"),
                              z_f_prior=None if prior is None else tuple(prior), init=call.get("init"),
                              options=MassCMOptions(**opts), noise_check=False)
    except Exception as err:  # noqa: BLE001 - the report must still be written
        return noted(result, f"{type(err).__name__}: {' '.join(str(err).split())[:160]}")
    ref = result.diagnostics.get("refine") or {}
    # a refined result stores Algorithm 1's m (the refinement's start) beside its own
    want = ref["algorithm1"]["m"][0] if ref.get("applied") else result.value("m")
    if fit.result.value("m") != want:
        return noted(result, f"Algorithm 1 on the recorded files gives m = {fit.result.value('m'):.6g} kg, "
                              f"not the stored {want:.6g} kg (files changed?)")
    made = with_series(fit, cost_map=cost_map)
    out = copy.deepcopy(result)
    kept = result.series if isinstance(result.series, Mapping) else {}
    out.series = {**dict(kept), **{k: v for k, v in made.series.items() if k in ("overlays", "residuals", "contours")}}
    out.provenance = {**dict(result.provenance), "inputs": made.provenance.get("inputs", [])}
    return out


# ---------------------------------------------------------------------------------------------------
# Table 3 (sensitivity study) as a Result
# ---------------------------------------------------------------------------------------------------
def spread_series(summary: dict, outputs: Sequence[dict | None]) -> dict:
    """``tables["spread"]`` and ``xy["spread"]`` (paper Table 3) from :func:`masscm_study.summarise`.

    The table has per parameter: true value, mean and std over the plausible runs, the bounds the
    initial values were drawn from, and the paper's mean and std. The scatter shows every plausible
    run's ``zm_bar`` against ``m`` (one point per run).
    """
    rows = []
    for n, p in summary["parameters"].items():
        lo, hi = p["bounds"]
        rows.append([n, THETA_UNITS.get(n, "-"), p["true"], p["mean"], p["std"], lo, hi, p["paper_mean"],
                     p["paper_std"]])
    tab = table(["parameter", "unit", "true", "mean", "std", "initial lower", "initial upper", "paper mean",
                 "paper std"], rows, paper="Table 3",
                title=f"Sensitivity to the initial values: {summary['used']} of {summary['runs']} runs plausible "
                      f"({summary['flagged']} flagged), z_f {summary.get('zf_mode', '?')}; mean and std over the "
                      "plausible runs, next to the paper's.",
                caption=f"implausible rule: {summary.get('implausible_rule', '')}")
    ok = [o for o in outputs if o is not None and not o.get("implausible")]
    out = {"tables": {"spread": tab}}
    if ok:
        m = np.array([o["m"] for o in ok], dtype=float)
        zm = np.array([o["zm_bar"] for o in ok], dtype=float)
        out["xy"] = {"spread": xy(m, {"plausible runs": zm}, x_label="load mass m", x_unit="kg",
                                  y_label="load centre z̄_m", y_unit="m", style="scatter", paper="Table 3",
                                  title=f"Estimates (m, z̄_m) of the {m.size} plausible runs from random "
                                        "initial values (Table-3 study).")}
    return out


def spread_result(summary: dict, outputs: Sequence[dict | None], *, command: str | None = None):
    """The Table-3 study as a :class:`~shipid.result.Result` (method ``mass-cm``) for ``shipid report``.

    Estimates are the means over the plausible runs with their run-to-run std (the spread caused
    by the initial values, not a standard error of the data).
    """
    est = {n: Estimate(float(p["mean"]), float(p["std"]), THETA_UNITS.get(n, "-"), "study mean",
                       f"mean ± std over plausible runs; true {p['true']:g}, paper {p['paper_mean']:g} ± "
                       f"{p['paper_std']:g}") for n, p in summary["parameters"].items()}
    diag = {k: summary[k] for k in ("runs", "flagged", "used", "mean_iterations", "wall_s", "zf_mode",
                                    "implausible_rule") if k in summary}
    diag["converged"] = bool(summary.get("used", 0) > 0)
    if summary.get("flagged"):
        diag["warnings"] = [f"{summary['flagged']} of {summary['runs']} runs implausible or not converged "
                            "(left out of the means)"]
    prov = {k: summary[k] for k in ("seed", "data_seed", "init", "workers") if k in summary}
    prov["study"] = "mass-cm-sensitivity (Linder et al. 2015 §5, Table 3)"
    try:  # the three synthetic datasets every run used (cheap to re-create: seeded, noise-free)
        d = simulate_datasets("fishing-vessel", seed=int(summary.get("data_seed", 0)))
        prov["inputs"] = inputs([(c, tr) for c, tr in d.items()])
        for e in prov["inputs"]:
            e["note"] = f"{e.get('note', '')}; simulated, data seed {summary.get('data_seed', 0)}".lstrip("; ")
    except Exception:  # noqa: BLE001 - the summary is still worth a report
        pass
    if command:
        prov["command"] = command
    return Result(method="mass-cm", estimates=est,
                  model={"vessel": "fishing-vessel", "paper": summary.get("paper", "Linder et al. 2015, Table 3")},
                  diagnostics=diag, series=spread_series(summary, outputs), provenance=prov)


__all__ = ["CONTOUR_N", "MAX_SERIES_POINTS", "with_series", "cost_map", "cost_contour", "model_overlays", "inputs", "attach", "spread_series",
           "spread_result"]
