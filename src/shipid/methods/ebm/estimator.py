"""Estimation-Before-Modelling (EBM), end to end (Yoon & Rhee 2003).

The steps themselves live in :mod:`shipid.methods.ebm.pipeline`.

Step 1 (§3): for every trial, the continuous–discrete EKF (:mod:`shipid.estimate.cd_ekf`)
and the modified Bryson–Frazier smoother (:mod:`shipid.estimate.smoothers`) estimate
the 17 states of :mod:`shipid.models.ebm_state` — relative velocities, heading,
the hydrodynamic forces X, Y, N and the current — from the measurements of eq. 8.
As in §5.1.1 the estimation is run twice: the second pass starts from initial
velocities corrected by the current found in the first.

Step 2 (§4): the smoothed ``u_r, v_r, r`` (with the known δ and n) build the
regressors of eqs. 14–15 for all trials together, and ridge regression with the
Hoerl–Kennard biasing parameter (:mod:`shipid.estimate.ridge`) fits θ_X, θ_Y, θ_N
(eq. 13) to the smoothed X, Y, N.

What the pipeline knows (:func:`identify_states`): the vessel file's mass, inertia,
added masses (M of eq. 6, known in the paper), length and propeller particulars
(:func:`shipid.models.abkowitz.particulars_from_vessel`, whose coefficients are NaN); the
approach speed and propeller rate that fix ``c0`` of the rudder regressor come from the
trials (:func:`approach_condition`) and the sensor lever arms of eq. 8 from the trial or
the user (:func:`~shipid.methods.ebm.pipeline.sensor_positions`). Nothing of the packaged Table 3 enters.

Standard errors. The residuals of step 2 are smoothed-force errors: serially correlated
over tens of samples (the Gauss–Markov model of eq. 4 makes them smooth), so the textbook
ridge covariance, which assumes independent residuals, is optimistic. We use the
Newey–West sandwich on the ridge normal equations with Andrews' bandwidth, lags kept
within each trial (``cov="hac"`` of :func:`shipid.estimate.ridge.ridge`), plus the ridge
bias in quadrature. It was chosen over (a) propagating the smoother covariance, which
needs the N × N cross-covariance of the smoothed forces and still misses the regressors'
own errors, and (b) a moving-block bootstrap, which resamples the same residual
information at B times the cost: the HAC sandwich uses the residuals themselves, so it
sees force errors, regressor errors and model error alike. Two systematic parts that no
residual-based variance covers are treated separately: the yaw fit is weighted by
``1/σ`` of the smoothed moment (where the rudder moves, the smoother cannot follow the
moment's jump and its σ is larger), and the pipeline's own bias at the identified ship is
estimated by re-identifying it from a noise-free simulation with the trial's inputs and
subtracted where it exceeds half a std (:mod:`shipid.methods.ebm.bias`). The coverage of
the result is measured by ``shipid study ebm-coverage`` (:mod:`shipid.methods.ebm.coverage`).

Verdicts (:mod:`shipid.methods.ebm.verdict`): trials without rudder or speed excitation
are refused; each coefficient is ``estimated`` or ``not determined`` (relative std,
variance inflation, ridge-bias share, R² of the mode, eq. 11 observability), and the
undetermined ones are named in ``diagnostics["warnings"]``.

Required trial channels: ``x, y`` (DGPS antenna, m), ``x_dot, y_dot`` (m/s),
``psi`` (rad), ``U`` (speed log, m/s), ``delta`` (rad), ``n`` (1/s).
"""

from __future__ import annotations

import os
from dataclasses import asdict, dataclass, replace
from typing import Sequence

import numpy as np

from shipid.io.trial import Trial
from shipid.errors import InputError, ShipidError
from shipid.numerics.linalg import NotPositiveDefiniteError
from shipid.methods.ebm.bias import corrected, pipeline_bias
from shipid.methods.ebm.pipeline import (REQUIRED, EbmConfig, EbmFit, RegressionData, StateEstimate,
                                         approach_condition, combined_coefficients, estimate_states,
                                         fit_coefficients, measurements, observability_report, process_noise,
                                         prior_cov, regression_data, sensor_positions, sensor_source,
                                         slope_alpha)
from shipid.methods.ebm.verdict import check_excitation, coefficient_verdicts
from shipid.models import abkowitz as ab
from shipid.result import Estimate, Result


def identify_states(trials: Sequence[Trial], vessel="esso-osaka", *, config: EbmConfig = EbmConfig(),
                    progress=None):
    """Step 1 on every trial, the approach condition and step 2: ``(states, fit, params)``.

    ``params`` is :func:`shipid.models.abkowitz.particulars_from_vessel` (no packaged coefficient)
    with the approach of :func:`approach_condition`; ``vessel`` is a name or a
    :class:`shipid.vessels.Vessel`.
    """
    if not trials:
        raise InputError("no trial given")
    check_excitation(trials)
    p0 = ab.particulars_from_vessel(vessel)
    states = []
    for tr in trials:
        states.append(estimate_states(tr, p0, vessel=vessel, config=config))
        if progress is not None:
            progress()
    U0, n0, _ = approach_condition(states, config)
    p = ab.with_approach(p0, U0, n0)
    fit = fit_coefficients(states, p, config)
    if config.bias_correction:
        try:
            bias = pipeline_bias(trials, states, fit, p, vessel, config)
        except (FloatingPointError, ShipidError, NotPositiveDefiniteError, np.linalg.LinAlgError) as err:
            fit = replace(fit, note=f"EBM: no bias correction (the identified ship could not be re-identified: {err})")
        else:
            cf, applied = corrected(fit, bias, config.bias_threshold)
            fit = replace(cf, bias=applied)
    return states, fit, p


def identify(trials: Sequence[Trial], vessel="esso-osaka", *,
             config: EbmConfig = EbmConfig(), progress=None) -> Result:
    """Both EBM steps on ``trials``; returns a :class:`~shipid.result.Result`.

    Estimates: the 26 coefficients of eq. 13 (non-dimensional, with HAC standard errors
    and a verdict ``estimated`` / ``not determined``, :mod:`shipid.methods.ebm.verdict`),
    the current speed (m/s) and direction (rad) per trial and averaged. Diagnostics:
    κ, R², C_p, k per mode (Table 4), the correlation matrices (Tables 1–2), the
    combined coefficients of eq. 21, the step-1 consistency (mean NIS), the approach
    condition taken from the trials and ``warnings``. Nothing of the vessel file's
    [abkowitz] coefficients enters (:func:`identify_states`). ``series`` is empty: the report
    series (smoothed states, force fits, innovations, Tables 1, 2, 4) are made on request by
    :func:`shipid.methods.ebm.series.with_series`.
    """
    return identify_run(trials, vessel, config=config, progress=progress).result


@dataclass(frozen=True)
class EbmRun:
    """An estimate with what its report series are computed from (:func:`shipid.methods.ebm.series.with_series`).

    ``states`` are the step-1 :class:`StateEstimate` per trial, ``fit`` the step-2 :class:`EbmFit`,
    ``params`` the particulars with the approach condition.
    """

    result: Result
    states: list
    fit: EbmFit
    params: object


def identify_run(trials: Sequence[Trial], vessel="esso-osaka", *, config: EbmConfig = EbmConfig(),
                 progress=None) -> EbmRun:
    """:func:`identify` returning an :class:`EbmRun` (the same Result, and its states and fit).

    The result records in ``provenance["ebm_call"]`` the trial files (where the trials were read from
    files), the vessel and the whole configuration, so that ``shipid report`` can make the report
    series again.
    """
    states, fit, p = identify_states(trials, vessel, config=config, progress=progress)
    res = build_result(states, fit, p, config, vessel)
    res.provenance["ebm_call"] = {"files": [_file_of(tr) for tr in trials],
                                  "vessel": vessel if isinstance(vessel, str) else getattr(vessel, "name", None),
                                  "config": asdict(config)}
    return EbmRun(res, list(states), fit, p)


def _file_of(trial) -> str | None:
    """The absolute path of the file a trial was read from, or its ``source`` label when that is not a file."""
    src = (getattr(trial, "meta", None) or {}).get("source")
    return os.path.abspath(src) if isinstance(src, str) and os.path.isfile(src) else src


def build_result(states, fit: EbmFit, p, config: EbmConfig, vessel: str) -> Result:
    est: dict[str, Estimate] = {}
    warn: list[str] = []
    names = {"surge": ab.THETA_X_NAMES, "sway": ab.THETA_Y_NAMES, "yaw": ab.THETA_N_NAMES}
    obs = [observability_report(s) if s.model is not None else None for s in states]
    observable = all(o is None or o["relative"]["min_rank"] == o["relative"]["n"] for o in obs)
    if not observable:
        warn.append("EBM step 1: the 17-state model is not observable along the trajectory (eq. 11 rank test)")
    verdict = coefficient_verdicts(fit, names, observable)
    se_note = ("Newey-West (HAC) std of the ridge estimate with the ridge bias in quadrature"
               if config.se == "hac" else
               "ridge std assuming independent residuals (optimistic: smoothed forces are correlated)")
    for mode, f in (("surge", fit.surge), ("sway", fit.sway), ("yaw", fit.yaw)):
        for nm, th, se in zip(names[mode], f.theta, f.se):
            v = verdict[nm]
            note = se_note if v["status"] == "estimated" else "not determined by the data: " + "; ".join(v["reasons"])
            est[nm] = Estimate(float(th), float(se), "-", v["status"], note)
    und = [nm for nm, v in verdict.items() if v["status"] != "estimated"]
    if und:
        warn.append(f"EBM: {len(und)} of {len(verdict)} coefficients not determined by these trials: "
                    + ", ".join(und))
    if fit.note:
        warn.append(fit.note)
    for s_ in states:
        if sensor_source(s_.trial, config).startswith("not stated"):
            warn.append(f"EBM: {s_.trial.meta.get('source') or 'a trial'} states no sensor positions: DGPS antenna "
                        "and speed log taken at the body origin (give them with --antenna X,Y --log-offset Y)")
    for mode, f in (("surge", fit.surge), ("sway", fit.sway), ("yaw", fit.yaw)):
        if not f.converged:
            warn.append(f"EBM {mode}: Hoerl-Kennard iteration for the ridge parameter did not converge "
                        f"(k = {f.k:.3g} used)")
    cs = np.array([s.current for s in states])
    cstd = np.array([s.current_std for s in states])
    w = 1.0 / np.maximum(cstd ** 2, 1e-300)
    cm = np.sum(w * cs, axis=0) / np.sum(w, axis=0)
    cm_std = np.sqrt(1.0 / np.sum(w, axis=0))
    speed = float(np.hypot(*cm))
    dirn = float(np.arctan2(cm[1], cm[0]))
    sp_std = float(np.hypot(cm[0] * cm_std[0], cm[1] * cm_std[1]) / max(speed, 1e-12))
    dr_std = float(np.hypot(cm[1] * cm_std[0], cm[0] * cm_std[1]) / max(speed ** 2, 1e-12))
    est["current_speed"] = Estimate(speed, sp_std, "m/s", "estimated", "U_c of eq. 2, all trials")
    est["current_direction"] = Estimate(dirn, dr_std, "rad", "estimated",
                                        "psi_c of eq. 2 (direction the current sets towards)")
    thY = fit.sway.theta
    thN = fit.yaw.theta
    comb = combined_coefficients(thY, thN, fit.alpha)
    diag = {
        "converged": bool(fit.surge.converged and fit.sway.converged and fit.yaw.converged),
        "iterations": {m: f.iterations for m, f in (("surge", fit.surge), ("sway", fit.sway), ("yaw", fit.yaw))},
        "modes": {m: {"kappa": f.kappa, "R2": f.R2, "R2_uncentred": f.R2_uncentred, "Cp": f.Cp,
                      "p": f.p, "k": f.k, "n": f.n}
                  for m, f in (("surge", fit.surge), ("sway", fit.sway), ("yaw", fit.yaw))},
        "correlation": {"surge": fit.surge.correlation, "sway": fit.sway.correlation},
        "alpha": fit.alpha,
        "combined_eq21": {"Yv+Yr/alpha": comb[0], "Nv*alpha+Nr": comb[1]},
        "approach": {"U0": p.U0, "n0": p.n0, "c0": p.c0,
                     "source": "measured values given by the user" if config.approach_speed is not None
                     else f"trials: smoothed u_r and channel n over the first {config.approach_s:g} s"},
        "trials": [{"source": s.trial.meta.get("source", ""), "manoeuvre": s.trial.meta.get("manoeuvre", ""),
                    "n": int(s.trial.t.size), "mean_nis": float(np.nanmean(s.filt.nis)),
                    "sensors": sensor_positions(s.trial, vessel, config),
                    "sensors_from": sensor_source(s.trial, config),
                    "current": s.current.tolist(), "passes": s.passes,
                    "first_pass_current": None if s.first_pass_current is None else s.first_pass_current.tolist(),
                    "observability_eq11": o}
                   for s, o in zip(states, obs)],
        "verdicts": verdict,
        "se_method": config.se,
        "hac_bandwidth": {m: f.bandwidth for m, f in (("surge", fit.surge), ("sway", fit.sway), ("yaw", fit.yaw))},
        "warnings": warn,
    }
    model = {"family": "modified Abkowitz (Hwang 1980), Yoon & Rhee 2003 eqs. 13-15",
             "vessel": vessel if isinstance(vessel, str) else vessel.name,
             "L": p.L, "rho": p.rho, "c0": p.c0, "U0": p.U0, "n0": p.n0,
             "nondimensionalisation": "X, Y by rho/2 L^2, N by rho/2 L^3 (eq. 14)",
             "yaw_rudder_variant": config.yaw_rudder_variant}
    prov = {"config": {"q_force": list(config.q_force), "q_current": config.q_current,
                       "passes": config.passes, "smoother": config.smoother, "ridge_k": config.ridge_k},
            "inputs": [s.trial.meta.get("source", "") for s in states]}
    return Result(method="ebm", estimates=est, model=model, diagnostics=diag, provenance=prov)


#: The last coverage study of the stated std (read by the report's verdict panel): ±2-std coverage
#: pooled over the six linear coefficients, perturbed ships and unknown noise scales, on a seed
#: not used for tuning (``shipid study ebm-coverage --runs 50 --seed 100 --workers 1``).
COVERAGE = {"coverage": 0.923, "n": 50, "nominal": 0.954,
            "note": "pooled over Y_v, Y_r, N_v, N_r, Y_delta, N_delta; lowest N_v and N_r at 0.88",
            "source": "shipid study ebm-coverage --runs 50 --seed 100"}

__all__ = ["COVERAGE", "EbmConfig", "StateEstimate", "RegressionData", "EbmFit", "estimate_states",
           "regression_data", "fit_coefficients", "identify", "identify_run", "EbmRun", "identify_states", "combined_coefficients",
           "slope_alpha", "measurements", "build_result", "REQUIRED", "process_noise", "prior_cov",
           "sensor_positions", "sensor_source", "observability_report", "approach_condition"]
