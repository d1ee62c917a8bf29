"""Structure selection and the whole MMG identification: smoothing, regression, cross-validation, result.

:func:`identify` runs the steps of :mod:`shipid.methods.mmg.estimator` (smoothing of each run,
force regression, ridge fits) and, with ``select=True``, chooses the model structure among the
candidates by cross-validation over the training runs (:func:`select_structure`, batched in
:mod:`shipid.methods.mmg.cv_fast`), then assembles the :class:`~shipid.result.Result`
(:func:`build_result`) with the test conditions the manoeuvre simulations start from.
"""

from __future__ import annotations

import hashlib
from dataclasses import replace
from typing import Mapping, Sequence

import numpy as np

from shipid.io.trial import Trial
from shipid.errors import InputError, ShipidError
from shipid.methods.mmg.candidates import CANDIDATES, apply_candidate, candidate_config
from shipid.methods.mmg.covariance import honest_covariance, ridge_covariance
from shipid.methods.mmg.cv_fast import cross_validate_horizons
from shipid.methods.mmg.estimator import (MEAS, FitConfig, MmgFit, SmoothConfig, SmoothedRun, cross_validate,
                                          equation_for, fit, horizon_score, horizon_sse, smooth_run)
from shipid.methods.mmg.manoeuvres import equilibrium_speed, training_conditions
from shipid.methods.mmg.output_error import OEConfig, cluster_index, refinable, refined_fit, stack_horizons
from shipid.methods.mmg.simex import SimexConfig, simex_fit
from shipid.methods.mmg.staged import STAGED_STRUCTURES, enough_horizons, select_staged
from shipid.models import mmg
from shipid.result import Estimate, Result


def select_structure(trials: Sequence[Trial], runs: Sequence[SmoothedRun], prior: mmg.MmgModel,
                     candidates: Mapping[str, Mapping[str, Sequence[str]]] | None = None, *,
                     config: FitConfig = FitConfig(), folds: int | None = None,
                     horizon: float = 60.0, decimate: int = 2, progress=None,
                     batched: bool = True) -> tuple[str, dict[str, dict]]:
    """Leave-one-run-out (or ``folds``-fold) cross-validation over the TRAINING runs.

    Each candidate is fitted without the fold's runs and simulated on them over 60-s
    horizons restarted from the measured state every 60 s (every ``decimate``-th
    sample); the squared heading and position errors are pooled over all folds'
    horizons, and the score is :func:`horizon_score` of the pooled RMS. Returns the
    candidate with the lowest score (the first listed on a tie) and the table
    (``psi_rms`` in deg, ``pos_rms`` in m). ``batched``: compute the same table with all
    horizons of all folds simulated together (:func:`shipid.methods.mmg.cv_fast.cross_validate_horizons`);
    False runs the reference loop below.
    """
    cands = candidates or CANDIDATES[prior.structure]
    if batched:
        table = cross_validate_horizons(trials, runs, prior, cands, config=config, folds=folds, horizon=horizon,
                                        decimate=decimate, progress=progress)
        return min(table, key=lambda c: table[c]["score"]), table

    def fold_errors(model, test_idx, train_idx):
        return horizon_sse(model, [trials[i] for i in test_idx], horizon, decimate)

    table = cross_validate(runs, prior, cands, fold_errors, horizon_score, config=config, folds=folds,
                           progress=progress)
    best = min(table, key=lambda c: table[c]["score"])
    return best, table


def horizon_method(folds: int | None = None) -> str:
    """The one-line description of :func:`select_structure`'s criterion that a result's selection records."""
    return (f"{'leave-one-run-out' if folds is None else f'{folds}-fold'} CV on the training runs, "
            "60-s restarted horizons, errors pooled over folds, score = RMS psi/10 deg + RMS pos/1 m")


# ----------------------------------------------------------------------------- result
def _file_id(path: str) -> str:
    try:
        with open(path, "rb") as fh:
            return hashlib.sha256(fh.read()).hexdigest()[:16]
    except OSError:
        return ""


def undetermined_note(value: float, se: float) -> str:
    """``""`` when the data determine a coefficient, else the note saying why not: its standard error is
    not finite or not below its magnitude (the value is kept in the model)."""
    if np.isfinite(se) and se < abs(value):
        return ""
    what = "not finite" if not np.isfinite(se) else f"{se:.3g} not below |value| {abs(value):.3g}"
    return f"; SE {what}: not determined by the data (the value is kept in the model)"


#: :func:`form_check` names the coefficients whose differential and integral estimates differ by more than
#: this many standard errors of the reported (differential) estimate.
FORM_CHECK_SE = 2.0


def form_check(res: Result, runs: Sequence[SmoothedRun], prior: mmg.MmgModel, free: Mapping[str, Sequence[str]],
               fit_config: FitConfig) -> dict | None:
    """The differential form of step 2 checked against the integral form on the same smoothed runs.

    The differential form (Yoon & Rhee 2003, eq. 16) regresses forces computed from the smoothed accelerations,
    which lag the rudder (:mod:`shipid.methods.mmg.coverage`); its standard errors do not hold that bias:
    in the simulated KVLCC2 campaign (``shipid study mmg-coverage --vessel kvlcc2``) its ±2 std of
    N_v, N_r, NR_arm covered the truth in a fifth to a quarter of the runs, the integral form's in 0.95 or
    more (figures in ``docs/validation/mmg.md``). So where the result is the differential form's
    (and not refined by output error), the integral form's naive estimate (no SIMEX) is computed too,
    and each estimated coefficient's difference is expressed in the reported standard errors.

    The difference is also kept as a model-form term (``form_std``: ``|θ_differential − θ_integral|``;
    ``std_with_form``: ``√(SE² + form_std²)``). :func:`shipid.methods.mmg.imo.sample_coefficients` adds
    ``δδᵀ`` (``δ`` the vector of differences) to the covariance of its draws: the other form's estimate
    counts as one standard deviation of the model-form error, the convention of a systematic error
    taken as the difference of two defensible methods. It is a fixed convention (no tuning); what it
    gives in the simulated KVLCC2 campaign is in ``docs/validation/mmg.md``.

    Returns None for the integral form; else ``{"integral": {name: value}, "difference_in_se": {name: z},
    "form_std": {name: |δ|}, "std_with_form": {name: s}, "over": [names with |z| > FORM_CHECK_SE,
    largest first], "not_determined_with_form": [estimated names whose std_with_form is not below
    |value|]}``.
    """
    if equation_for(fit_config, prior) != "differential":
        return None
    fi = fit(runs, prior, free, replace(fit_config, equation="integral"))
    # a mode with no estimable column has no fit (estimator.fit skips it)
    other = {c: float(v) for m, fm in fi.fits.items() for c, v in zip(fi.free.get(m, ()), fm.theta)}
    z, form_std, with_form = {}, {}, {}
    for c, v in other.items():
        e = res.estimates.get(c)
        if e is not None and e.status == "estimated" and np.isfinite(e.std) and e.std > 0:
            z[c] = float((e.value - v) / e.std)
            form_std[c] = float(abs(e.value - v))
            with_form[c] = float(np.hypot(e.std, e.value - v))
    over = sorted((c for c in z if abs(z[c]) > FORM_CHECK_SE), key=lambda c: -abs(z[c]))
    # the rule of undetermined_note, applied to the std with the model-form term
    loose = [c for c in with_form if not with_form[c] < abs(res.estimates[c].value)]
    return {"integral": other, "difference_in_se": z, "form_std": form_std, "std_with_form": with_form,
            "over": over, "not_determined_with_form": loose}


def form_line(check: Mapping) -> str | None:
    """One warning line for a :func:`form_check` with coefficients over the threshold (None if none)."""
    over, z = check["over"], check["difference_in_se"]
    if not over:
        return None
    names = ", ".join(over[:4]) + (f" and {len(over) - 4} more" if len(over) > 4 else "")
    loose = check.get("not_determined_with_form") or []
    also = (f"; with that difference as model-form error {len(loose)} are not determined ({', '.join(loose)})"
            if loose else "")
    return (f"step 2's differential and integral forms disagree by more than {FORM_CHECK_SE:g} standard errors on "
            f"{len(over)} of {len(z)} estimated coefficients ({names}; largest {abs(z[over[0]]):.1f} SE, {over[0]}{also}): "
            "the standard errors leave out the differential form's bias (shipid.methods.mmg.pipeline.form_check; "
            "diagnostics.form_check.std_with_form adds the difference as model-form error, and shipid imo's bands "
            "include it); --equation integral gives the form whose error bars held in the simulated coverage study")


def build_result(f: MmgFit, prior: mmg.MmgModel, runs: Sequence[SmoothedRun], *, structure_name: str,
                 selection: Mapping | None = None, smooth_config: SmoothConfig = SmoothConfig(),
                 fit_config: FitConfig = FitConfig(), extra_provenance: Mapping | None = None,
                 overrides: Mapping | None = None, covariance: tuple[np.ndarray, str] | None = None) -> Result:
    """A self-describing :class:`Result` (MODEL.json): structure, particulars, coefficients, covariance.

    ``covariance``: ``(Σ, description)`` over the free coefficients in MODEL.json order
    (:func:`shipid.methods.mmg.covariance.parameter_covariance`); default the ridge covariance.
    """
    names = [c for m in mmg.MODES for c in f.free.get(m, ())]
    if covariance is None:
        cov, cov_note = ridge_covariance(f), "ridge SE; optimistic (serially correlated residuals)"
    else:
        cov, cov_note = np.asarray(covariance[0], float), covariance[1]
    se_of = dict(zip(names, np.sqrt(np.maximum(np.diag(cov), 0.0))))
    est: dict[str, Estimate] = {}
    for mode in mmg.MODES:
        for c in mmg.COEFS[prior.structure][mode]:
            unit = mmg.COEF_UNITS.get(c, "-")
            if c in f.free.get(mode, ()):
                i = f.free[mode].index(c)
                v, se = float(f.fits[mode].theta[i]), float(se_of[c])
                why = undetermined_note(v, se)
                # an undetermined coefficient's note (its warning line) names the covariance by its first clause
                # only: the full description is in every estimated coefficient's note and in diagnostics
                est[c] = Estimate(v, se, unit, "not determined" if why else "estimated",
                                  (cov_note.split(";")[0] if why else cov_note) + why)
            else:
                why = "regime not visited in the training runs" if c in f.dropped.get(mode, ()) else \
                    "not free in the chosen structure"
                est[c] = Estimate(float(f.model.coef[c]), float("nan"), unit, "fixed",
                                  f"prior value ({prior.name}); {why}")
    model = f.model.to_dict()
    model["free"] = {m: list(v) for m, v in f.free.items()}
    model["structure_candidate"] = structure_name
    model["fixed_from"] = prior.name
    model["particular_overrides"] = dict(overrides or {})
    diag = {"converged": all(fi.converged for fi in f.fits.values()),
            "iterations": int(sum(fi.iterations for fi in f.fits.values())),
            "ridge": {m: {"k": fi.k, "R2": fi.R2, "kappa": fi.kappa, "Cp": fi.Cp, "n": fi.n, "p": fi.p,
                          "converged": fi.converged} for m, fi in f.fits.items()},
            "dropped": {m: list(v) for m, v in f.dropped.items() if v},
            "step1_nis_mean": {r.source: r.nis_mean for r in runs},
            "step1_sigma": {r.source: dict(zip(MEAS, r.sigma.tolist())) for r in runs},
            "notes": ["Masses, added masses and sub-model shape constants are fixed at the prior model "
                      f"({prior.name}); for the Esso Osaka that set was identified by its authors from runs "
                      "of the same data set.",
                      f"Standard errors and covariance: {cov_note}."],
            "covariance": {"kind": cov_note,
                           "se_ridge": dict(zip(names, np.sqrt(np.maximum(np.diag(ridge_covariance(f)), 0.0))
                                                .tolist()))}}
    if selection is not None:
        diag["structure_selection"] = dict(selection)
    prov = {"training_runs": [{"file": r.source, "sha256_16": _file_id(r.source)} for r in runs],
            "step1": {k: float(v) for k, v in smooth_config.__dict__.items()},  # sigmas unused if auto_sigma
            "step2": {**{k: v for k, v in fit_config.__dict__.items()},
                      "equation_used": equation_for(fit_config, prior)},
            "pipeline": "EBM (Yoon & Rhee 2003) adapted: kinematic CD-EKF + RTS, forces from EOM, ridge per mode"}
    if extra_provenance:
        prov.update(extra_provenance)
    return Result(method="mmg-ebm", estimates=est, model=model, covariance=cov, covariance_names=names,
                  diagnostics=diag, provenance=prov)


#: Prior structures whose identification is refined by output error by default where the staged selection
#: does not decide it (:func:`shipid.methods.mmg.staged.cv_refinement` compares both on the training runs).
REFINE_BY_DEFAULT = ("esso-lowspeed",)
#: ``refine="auto"`` refines only with at least this many restarted horizons per refined
#: coefficient: the horizons are the clusters of the sandwich covariance (its rank is at most
#: their number) and the independent pieces of evidence of the criterion; where ``OEConfig.stride``
#: makes them overlap the clusters are whole runs (:func:`shipid.methods.mmg.output_error.cluster_index`)
#: and those are counted.
MIN_HORIZONS_PER_COEFFICIENT = 5


def default_refine(prior: mmg.MmgModel, refine: str = "auto") -> str:
    """``refine`` unless it is ``"auto"``: then ``"output-error"`` for :data:`REFINE_BY_DEFAULT`, else ``"none"``."""
    if refine != "auto":
        return refine
    return "output-error" if prior.structure in REFINE_BY_DEFAULT else "none"


#: Why a refined coefficient's std counts the refinement's shift (:func:`_covariance`), in MODEL.json's words.
SHIFT_NOTE = ("the refinement's shift from the regression estimate counted as one standard deviation (the "
              "output-error estimate restarts from measured, noisy states: in simulation it moves far from the "
              "truth, shipid study mmg-coverage --refine output-error)")


def _covariance(f_reg: MmgFit, f: MmgFit, runs, prior: mmg.MmgModel, config: FitConfig,
                oe, simex_info=None, start: Mapping[str, float] | None = None) -> tuple[np.ndarray, str]:
    """The covariance MODEL.json carries: the run bootstrap / HAC of the regression
    (:func:`~shipid.methods.mmg.covariance.honest_covariance` of the regression fit ``f_reg``); with an
    output-error refinement (``f``, ``oe``) the rows
    and columns of the refined coefficients are the refinement's horizon-cluster sandwich (per mode, as
    :func:`~shipid.methods.mmg.output_error.refined_fit` keeps them), with no cross terms to the others,
    plus ``δδᵀ``, ``δ`` the refinement's shift from its ``start`` (the regression estimate): the shift counts as
    one standard deviation of the output-error estimator's bias, as the differential form's distance from the
    integral form does (:func:`form_check`). Why: the criterion restarts every horizon from the measured,
    noisy state, so the estimate it converges to is the best 60-s predictor from such starts, not the ship's
    coefficients; in the simulated coverage study (:mod:`shipid.methods.mmg.coverage`, ``refine="output-error"``,
    runs of 4 x 1200 s; ``docs/validation/mmg.md``) the refined Y_v, Y_r, YR_gain were biased by −760 to −1050 %, NR_arm by
    −39 %, and the sandwich covered the truth in 0.14–0.50 of the runs, while the regression they started from
    was within 3 %.
    With a SIMEX correction (``simex_info``) its Monte Carlo covariance is added to the regression's, and
    where that is the HAC sandwich also the part of the covariance the measured noise causes through the
    step-1 states (:attr:`~shipid.methods.mmg.simex.SimexInfo.noise_cov`; the run bootstrap holds it)."""
    S, note, kind = honest_covariance(f_reg, runs, prior, config)
    if simex_info is not None and simex_info.applied:
        S = S + simex_info.mc_cov
        note += " + Monte Carlo variance of the SIMEX correction"
        if kind == "hac" and simex_info.noise_cov is not None:
            S = S + simex_info.noise_cov
            note += " + the measurement noise's part through the step-1 states (SIMEX draws)"
    if oe is None:
        return S, note
    names = [c for m in mmg.MODES for c in f.free.get(m, ())]
    ii = [names.index(c) for c in oe.names if c in names]
    R = ridge_covariance(f)                        # the refined fit's per-mode blocks hold the sandwich
    S = np.array(S, float)
    S[ii, :] = 0.0
    S[:, ii] = 0.0
    S[np.ix_(ii, ii)] = R[np.ix_(ii, ii)]
    if start is not None:
        d = np.array([f.model.coef[c] - start[c] for c in oe.names if c in names])
        S[np.ix_(ii, ii)] += np.outer(d, d)
        return S, (f"refined coefficients: output-error horizon-cluster sandwich SE with {SHIFT_NOTE}; "
                   f"the others: {note}")
    return S, (f"refined coefficients: output-error horizon-cluster sandwich SE; the others: {note}")


def equilibrium_line(model: Mapping) -> str | None:
    """The warning line when the identified model (a MODEL.json ``model`` dict with its
    ``training_conditions``) cannot run straight at the training runs' median propeller rate.

    A ship at a steady propeller rate settles at the speed where thrust balances resistance
    (:func:`~shipid.methods.mmg.manoeuvres.equilibrium_speed`). Where the identified surge model has no such
    speed its surge coefficients are not physical (in the simulated coverage study this happened once in 100
    campaigns, where the propeller polynomial was poorly excited), and ``shipid simulate`` /
    ``shipid imo`` need an approach speed. None when the model has an equilibrium or the runs have no
    forward propeller rate."""
    rps = (model.get("training_conditions") or {}).get("rps_ahead")
    if not rps:
        return None
    try:
        equilibrium_speed(mmg.MmgModel.from_dict(model), float(rps))
    except ShipidError as e:
        return (f"implausible surge model at the training runs' median propeller rate: {e}; its surge "
                "coefficients are not physical, and 'shipid simulate' and 'shipid imo' need --speed")
    return None


def identify(trials: Sequence[Trial], prior: mmg.MmgModel, *, structure: str | None = None,
             select: bool = True, folds: int | None = None, smooth_config: SmoothConfig = SmoothConfig(),
             fit_config: FitConfig = FitConfig(), name: str = "mmg-identified", progress=None,
             extra_provenance: Mapping | None = None, selector=None, refine: str = "none",
             oe_config: OEConfig = OEConfig(), candidates: Mapping[str, Mapping] | None = None,
             resolve=None, simex: SimexConfig | None = SimexConfig()) -> Result:
    """The whole pipeline on training runs: smooth, (select structure by CV), fit, Result.

    Parameters
    ----------
    trials : sequence of Trial
        Training runs only.
    prior : MmgModel
        Supplies the structure, the fixed constants and the values of non-free coefficients.
    structure : str, optional
        A candidate name of :data:`CANDIDATES`; with ``select`` and no name, chosen by CV: for a prior of
        :data:`~shipid.methods.mmg.staged.STAGED_STRUCTURES` with the default ``candidates`` and ``selector``,
        ``refine`` other than ``"none"`` and enough horizons
        (:func:`~shipid.methods.mmg.staged.enough_horizons`), by the staged CV of
        :func:`shipid.methods.mmg.staged.select_staged`, which also decides the refinement (its chosen
        criterion; ``refine="output-error"`` restricts the choice to the refined rows); else by
        :func:`select_structure`. ``diagnostics["structure_selection"]`` records the criterion, the
        tables and why.
    selector : callable, optional
        ``selector(trials, runs, prior, candidates, config, folds) -> (name, table, method[, record])``;
        default :func:`select_structure` (60-s horizon errors). It receives the training
        runs only; ``record`` (a dict) updates ``diagnostics["structure_selection"]``.
    candidates : mapping, optional
        The candidate structures to choose among (default :data:`CANDIDATES` of the prior's structure).
    resolve : callable, optional
        ``resolve(trials, runs, prior, candidate, config) -> (candidate, info)``: the candidate to fit
        on all training runs (e.g. with a particular calibrated on them,
        :func:`shipid.methods.mmg.turning_selection.resolve`); ``info`` (or None) is kept in
        ``diagnostics["calibration"]``. It receives the training runs only.
    refine : {"none", "output-error", "auto"}
        ``"output-error"``: refine the chosen structure's regression estimate on the
        training runs' restarted 60-s horizons (:func:`shipid.methods.mmg.output_error.refined_fit`);
        the refined coefficients carry the horizon-cluster sandwich standard errors.
        ``"auto"``: :func:`default_refine`, and refine only when the training runs hold at least
        :data:`MIN_HORIZONS_PER_COEFFICIENT` horizons per refined coefficient (else the
        regression estimate, with the reason in ``diagnostics["output_error"]``). Where the staged
        selection runs (``structure`` above), the criterion it chose replaces ``"auto"``.
    simex : SimexConfig or None
        Correct the chosen structure's regression estimate for the errors of the smoothed states
        (:func:`shipid.methods.mmg.simex.simex_fit`: with the default ``SimexConfig()`` only where its pilot
        finds the measurement noise material; the covariance gains the correction's Monte Carlo part);
        recorded in ``diagnostics["simex"]``. None: no correction. The output-error refinement, if any,
        starts from the corrected estimate. The cross-validation fits of the structure selection are
        not corrected.
    """
    if not trials:
        raise InputError("no training runs given")
    runs = [smooth_run(tr, smooth_config) for tr in trials]
    if progress is not None:
        progress()
    cands = CANDIDATES[prior.structure] if candidates is None else candidates
    selection = None
    staged_note = None
    if (structure is None and select and len(trials) >= 2 and selector is None and candidates is None
            and refine in ("auto", "output-error") and prior.structure in STAGED_STRUCTURES):
        ok, count = enough_horizons(trials, prior, oe_config, MIN_HORIZONS_PER_COEFFICIENT)
        if ok:
            st = select_staged(trials, runs, prior, config=fit_config, folds=folds, oe_config=oe_config,
                               criteria=("output-error",) if refine == "output-error" else
                               ("regression", "output-error"))
            structure, cands, selection = st["chosen"], st["pool"], st["selection"]
            refine = st["criterion"] if st["criterion"] == "output-error" else "none"
        else:
            staged_note = (f"staged selection not run: {count} (it needs {MIN_HORIZONS_PER_COEFFICIENT} per "
                           "coefficient, as refine='auto'); regression CV only")
    if structure is None and select and len(trials) >= 2:
        more: list = []
        if selector is None:
            structure, table = select_structure(trials, runs, prior, cands, config=fit_config, folds=folds)
            method = horizon_method(folds)
        else:
            structure, table, method, *more = selector(trials, runs, prior, cands, fit_config, folds)
        scores = sorted((row.get("score", np.inf), c) for c, row in table.items() if c != structure)
        why = (f"lowest CV score of the {len(table)} candidates: "
               f"{table.get(structure, {}).get('score', np.nan):.4f} ({structure})")
        if scores:
            why += f"; next {scores[0][0]:.4f} ({scores[0][1]})"
        selection = {"method": method, "criterion": "regression CV" if selector is None else "selector",
                     "table": table, "chosen": structure, "why": why, "training_runs": [r.source for r in runs]}
        if more:        # a selector's own record (criterion, why, further tables) over the generic one
            selection.update(more[0])
        if staged_note:
            selection["note"] = staged_note
    elif structure is None:
        structure = next(iter(cands))
    if structure not in cands:
        raise InputError(f"unknown structure '{structure}' (choose from {', '.join(cands)})")
    cand, cal = cands[structure], None
    if resolve is not None:
        cand, cal = resolve(trials, runs, prior, cand, fit_config)
    cprior, free = apply_candidate(prior, cand)
    fit_config = candidate_config(fit_config, cand)
    f = f_naive = fit(runs, cprior, free, fit_config, name=name)
    simex_info = None
    if simex is not None:
        f, simex_info = simex_fit(f_naive, trials, cprior, free, fit_config, smooth_config, simex)
    oe, skipped, start = None, None, None
    auto = refine == "auto"
    if auto:
        refine = default_refine(cprior, "auto")
    if refine == "output-error":
        try:
            H = stack_horizons(trials, oe_config.horizon, oe_config.decimate, oe_config.stride)
        except ShipidError:
            if not auto:
                raise
            H = None
        p = len(refinable(f, oe_config))
        n = 0 if H is None else int(cluster_index(H, oe_config).max()) + 1      # independent clusters
        if auto and n < MIN_HORIZONS_PER_COEFFICIENT * p:
            what = "restarted horizons" if H is None or n == H.count else "runs of overlapping horizons"
            skipped = (f"not refined: {n} {what} for {p} coefficients "
                       f"(refine='auto' needs {MIN_HORIZONS_PER_COEFFICIENT} per coefficient)")
        else:
            start = dict(f.model.coef)
            f, oe = refined_fit(f, trials, oe_config, H=H)
    elif refine != "none":
        raise InputError(f"unknown refinement '{refine}' (none, output-error)")
    extra_provenance = dict(extra_provenance or {})
    if "rudder_sign" not in extra_provenance and all(tr.meta.get("rudder_sign_flipped") for tr in trials):
        # the reader (e.g. data.basins.read_kvlcc2) flipped the file's rudder: a report that reads the
        # recorded files again must flip it too
        extra_provenance["rudder_sign"] = -1
    res = build_result(f, cprior, runs, structure_name=structure, selection=selection,
                       smooth_config=smooth_config, fit_config=fit_config, extra_provenance=extra_provenance,
                       overrides=cand.get("particulars"),
                       covariance=_covariance(f_naive, f, runs, cprior, fit_config, oe, simex_info, start))
    res.model["training_conditions"] = training_conditions(trials)
    line = equilibrium_line(res.model)
    if line:
        res.diagnostics.warnings.append(line)
    if cal is not None:
        res.diagnostics["calibration"] = cal
    if simex_info is not None:
        res.diagnostics["simex"] = simex_info.to_dict()
    if skipped:
        res.diagnostics["output_error"] = {"refined": [], "note": skipped}
    check = form_check(res, runs, cprior, free, fit_config) if oe is None else None
    if check is not None:
        res.diagnostics["form_check"] = check
        line = form_line(check)
        if line:
            res.diagnostics.warnings.append(line)
    if oe is not None:
        moved = []
        for j, c in enumerate(oe.names):
            e = res.estimates[c]
            why = undetermined_note(e.value, e.std)
            res.estimates[c] = Estimate(e.value, e.std, e.unit, "not determined" if why else e.status,
                                        "output-error refinement on 60-s restarted horizons; horizon-cluster "
                                        "sandwich SE with the shift from the regression estimate "
                                        f"{start[c]:.6g} as one std" + why)
            se = float(np.sqrt(oe.cov[j, j])) if np.isfinite(oe.cov[j, j]) and oe.cov[j, j] >= 0 else np.nan
            if np.isfinite(se) and abs(e.value - start[c]) > 2.0 * se:       # NaN sandwich: said per coefficient
                moved.append(c)
        if moved:
            res.diagnostics.warnings.append(
                f"output-error refinement moved {len(moved)} of {len(oe.names)} coefficients more than 2 of their "
                f"sandwich SE from the regression ({', '.join(moved[:6])}{', ...' if len(moved) > 6 else ''}): "
                "effective values for prediction from measured states, not the ship's coefficients; their std "
                "count the shift")
        res.diagnostics["output_error"] = {
            "refined": list(oe.names), "start": {c: float(start[c]) for c in oe.names}, "moved_over_2se": moved,
            "cost_start": oe.cost0, "cost_end": oe.cost, "iterations": oe.iterations,
            "rtol_reached": oe.converged, "horizons": oe.horizons,
            "note": "Levenberg-Marquardt stopped after at most max_iter iterations (early stopping, the "
                    "setting the training-run CV compared)" + (
                        "" if oe_config.robust is None else
                        f" in each of 1 + {oe_config.robust_passes} passes, horizons Huber-weighted beyond "
                        f"{oe_config.robust:g} x the median horizon error after the first; costs under the "
                        "final weights"),
            "config": {k: (list(v) if isinstance(v, tuple) else v) for k, v in oe_config.__dict__.items()}}
        if not oe.cost < oe.cost0:
            res.diagnostics.warnings.append("output-error refinement did not lower the horizon error; the "
                                            "regression estimate is kept")
    return res


__all__ = ["select_structure", "horizon_method", "undetermined_note", "build_result", "identify", "default_refine",
           "form_check", "form_line", "equilibrium_line", "FORM_CHECK_SE",
           "REFINE_BY_DEFAULT", "MIN_HORIZONS_PER_COEFFICIENT"]
