"""Report series of the DP identification (Fossen, Sagatun & Sørensen 1996).

Adds to a ``dp`` :class:`~shipid.result.Result`, on request (:func:`with_series`), what ``shipid report``
draws; ``identify`` never does this work:

* ``histories["theta<i>"]`` — the parameter estimate of the final EKF pass of its scheme against
  time, with its ±σ band and the true value where known (paper Fig. 8).

* ``residuals["innovation_<scheme>_<channel>"]`` — the innovations of the final filter pass of
  each scheme (SI1: distance run along the heading, eq. 32; SI2, SI3: x, y, ψ, eqs. 44–45) for
  the first trial of the scheme, with ``std`` = the square root of the diagonal of the
  innovation covariance S that the EKF predicted. For a consistent filter about 95 % of the
  innovations lie inside ±2σ and they are white; the report tests both.
* ``overlays["SI2_psi"]`` — measured heading of the first sway–yaw trial against the EKF's
  one-step-ahead model prediction (measurement − innovation).
* ``provenance["inputs"]`` — a :func:`~shipid.report.convention.trial_summary` per trial.

Positions are converted from the bis system (eqs. 26–28) back to metres, time to seconds.
"""

from __future__ import annotations

import copy
import os
import warnings
from typing import Mapping, Sequence

import numpy as np

from shipid.methods._series import first_unreproduced, noted, recorded_call
from shipid.methods._trials import as_trial, grouped
from shipid.methods.dp.entry import REQUIRED
from shipid.methods.dp.estimator import DPFit, DPOptions, fit_dp
from shipid.models import dp
from shipid.report.convention import history, overlay, residual, trial_summary
from shipid.result import Result
from shipid.vessels import load_vessel

#: Measured channels of each scheme's model (:func:`shipid.methods.dp.stage_models.prepare`).
CHANNELS = {"surge": (("s", "distance run along the heading s", "m"),),
            "momentum": (("x", "north position x", "m"), ("y", "east position y", "m"),
                         ("psi", "heading ψ", "rad"))}
INPUT_CHANNELS = ("x", "y", "psi", "p1", "p2", "p3", "p4", "p5", "p6", "alpha6")


def innovations(stages, vessel, trials_by_stage: dict[str, Sequence]) -> tuple[dict, dict]:
    """Innovation residuals (with σ) and one-step overlays of the first trial of every scheme.

    Parameters
    ----------
    stages : sequence of :class:`shipid.methods.dp.estimator.StageResult`
    vessel : DPVessel
    trials_by_stage : dict
        Scheme name (``"SI1"`` ...) -> the trials it ran on, in the same order.
    """
    res, ov = {}, {}
    L = float(vessel.bis.L)
    for st in stages:
        trials = trials_by_stage.get(st.name) or []
        if not trials:
            continue
        ekf = st.ekf
        tr = trials[0]
        nu = np.asarray(ekf.innovations[0], dtype=float)             # (n, nz) bis
        n, nz = nu.shape
        S = np.asarray(ekf.combined.S, dtype=float)[:n, :nz, :nz]    # trial 0 is the first block
        sd = np.sqrt(np.clip(np.einsum("kii->ki", S), 0.0, None))
        prep = st.data[0] if getattr(st, "data", None) else None   # the samples the filter ran on
        if prep is not None:
            t = np.asarray(vessel.bis.t_from_bis(prep["t"]), dtype=float)[:n]
        else:
            t = np.asarray(tr.t, dtype=float)[:n]
        t = t - t[0]
        chans = CHANNELS["surge" if nz == 1 else "momentum"]
        src = tr.meta.get("source") or f"{st.name} trial 1"
        for j, (ch, label, unit) in enumerate(chans):
            scale = L if unit == "m" else 1.0
            v, s = nu[:, j] * scale, sd[:, j] * scale
            s = np.where(np.isfinite(v), s, np.nan)
            res[f"innovation_{st.name}_{ch}"] = residual(
                t, v, unit, std=s, label=f"{st.name} innovation of {label}",
                title=f"Innovation of {label} ({st.name}, {src}, final pass) with the EKF's predicted ±2σ "
                      "(√ of the diagonal of S); about 95 % inside and white for a consistent filter.")
            if st.name == "SI2" and ch == "psi" and ch in tr.channels:
                meas = (np.asarray(prep["Z"][:, 2], dtype=float)[:n].copy() if prep is not None
                        else np.asarray(tr[ch], dtype=float)[:n].copy())
                if ch == "psi":  # unwrapped over the valid fixes, as the filter sees it
                    ok = np.isfinite(meas)
                    meas[ok] = np.unwrap(meas[ok])
                ov[f"SI2_{ch}"] = overlay(
                    t, meas, meas - v, unit, kind="fit", label=f"{label} ({src})",
                    title=f"{label} of the first sway–yaw trial ({src}): measured and the EKF's one-step-ahead "
                          "model prediction (final SI2 pass); residual = innovation, with its autocorrelation.")
    return res, ov


def inputs(trials_by_stage: dict[str, Sequence]) -> list[dict]:
    """``provenance["inputs"]``: one trial summary per trial, noting the scheme that used it."""
    out = []
    for name, trials in trials_by_stage.items():
        for k, tr in enumerate(trials):
            try:
                chans = [c for c in INPUT_CHANNELS if c in tr.channels]
                out.append(trial_summary(tr, name=tr.meta.get("source") or f"{name} trial {k + 1}",
                                         channels=chans, note=f"scheme {name}"))
            except Exception:  # noqa: BLE001 - an odd trial must not break the method
                out.append({"name": f"{name} trial {k + 1}", "note": f"scheme {name}"})
    return out


def histories(stages, theta_true=None) -> dict:
    """Fig. 8: every free parameter of every scheme against time, with ±σ and the true value where known."""
    hist = {}
    for st in stages:
        for j, i in enumerate(st.free):
            nm = dp.THETA_NAMES[i]
            hist[nm] = history(st.t, st.free_theta[:, j], st.free_std[:, j], "- (bis)",
                               true=None if theta_true is None else float(theta_true[i]),
                               label=f"θ{i + 1}'' = {dp.THETA_MEANING[nm]} ({st.name})", paper="Fig. 8")
    return hist


def attach(result, stages, vessel, trials_by_stage: Mapping[str, Sequence], theta_true=None) -> None:
    """Add histories, innovations, one-step overlays and input summaries to ``result`` (never raises)."""
    by = {k: list(trials_by_stage.get(k) or []) for k in ("SI1", "SI2", "SI3")}
    series = {}
    try:
        series["histories"] = histories(stages, theta_true)
    except Exception as err:  # noqa: BLE001 - report extras must never lose the estimate
        result.diagnostics.setdefault("warnings", []).append(
            f"report series: parameter histories not built ({type(err).__name__}: {err})")
    series.update(result.series)
    result.series = series
    try:
        res, ov = innovations(stages, vessel, by)
        if res:
            result.series.setdefault("residuals", {}).update(res)
        if ov:
            result.series.setdefault("overlays", {}).update(ov)
    except Exception as err:  # noqa: BLE001 - report extras must never lose the estimate
        result.diagnostics.setdefault("warnings", []).append(
            f"report series: innovations not built ({type(err).__name__}: {err})")
    prov = result.provenance
    if not isinstance(prov.get("inputs"), list) or all(isinstance(x, str) for x in prov.get("inputs", [])):
        files = prov.get("inputs")
        summ = inputs(by)
        if isinstance(files, list) and len(files) == len(summ):   # keep the file paths the CLI recorded
            for e, f in zip(summ, files):
                e["name"] = str(f)
        prov["inputs"] = summ


def with_series(fit, *, trials: Mapping | None = None) -> Result:
    """A result with its report series: parameter histories (Fig. 8), innovations with σ, the SI2 heading
    overlay and the trial summaries.

    ``fit`` is a :class:`~shipid.methods.dp.estimator.DPFit` (:func:`~shipid.methods.dp.estimator.fit_dp`;
    its result is completed in place and returned) or a stored ``dp`` :class:`~shipid.result.Result`
    (``Result.with_series()``, ``shipid report``). For a stored result the trials are ``trials`` (the
    mapping ``{"surge": [...], "sway-yaw": [...], "azimuth": [...]}`` of trials or paths that
    ``shipid.identify("dp", ...)`` takes), else the files it records (``provenance["dp_call"]``); SI1 → SI2
    → SI3 is run again with the recorded vessel and options, and a copy of the result gets the series
    when that reproduces every stored estimate exactly (else, or when a file is missing, a copy with one
    warning saying why). A result that records no files and is given no trials, or that already has
    the histories, comes back unchanged.
    """
    if isinstance(fit, DPFit):
        attach(fit.result, fit.stages, fit.vessel, fit.trials, fit.theta_true)
        return fit.result
    return _from_trials(fit, trials)



def _from_trials(result, trials):
    """:func:`with_series` of a stored result (see there)."""
    call = recorded_call(result, "dp", "dp_call", "histories")
    if call is None:
        return result
    if trials is None:
        files = call.get("files") or {}
        paths = [p for ps in files.values() for p in ps]
        if not paths or any(not isinstance(p, str) for p in paths):
            return result
        missing = [p for p in paths if not os.path.isfile(p)]
        if missing:
            return noted(result, f"trial file not found: {missing[0]} (give the trials: with_series(trials=...))")
        trials = files
    try:
        groups = grouped(trials, ("surge", "sway-yaw", "azimuth"), "dp")
        t = {g: [as_trial(x, required=list(REQUIRED), manoeuvre=f"dp-{g}") for x in ts] for g, ts in groups.items()}
        vessel = dp.dp_vessel(load_vessel(str(call.get("vessel") or "supply")))
        known = DPOptions.__dataclass_fields__
        opts = {k: (tuple(v) if isinstance(v, list) else v) for k, v in (result.provenance.get("options") or {}).items()
                if k in known}
        tt = result.diagnostics.get("theta_true")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fit = fit_dp(t["surge"], t["sway-yaw"], t["azimuth"], vessel, DPOptions(**opts),
                         theta_true=None if tt is None else np.asarray(tt, dtype=float))
    except Exception as err:  # noqa: BLE001 - the report must still be written
        return noted(result, f"{type(err).__name__}: {' '.join(str(err).split())[:160]}")
    n = first_unreproduced(result, fit.result)
    if n is not None:
        return noted(result, f"SI1 -> SI3 on these trials gives {n} = {fit.result.value(n):.6g}, not the stored "
                              f"{result.value(n):.6g} (other trials or files changed?)")
    out = copy.deepcopy(result)
    attach(out, fit.stages, fit.vessel, fit.trials, fit.theta_true)
    return out


__all__ = ["histories", "innovations", "inputs", "attach", "with_series"]
