"""Staged structure selection of the Esso low-speed model: regression CV, then output-error CV of the best,
their port/starboard variants and their surge / slipstream-rudder / wind-gain variants.

The default of ``identify mmg --structure auto`` for a prior of the structures in :data:`STAGED_STRUCTURES`
(the Esso Osaka low-speed set), when the training runs hold enough restarted horizons to refine the
estimate (:func:`enough_horizons`). All on the training runs, on the same ``folds``-fold split, each
candidate fitted without a fold's runs and scored on them over 60-s horizons restarted every 60 s
(score RMS ψ/10° + RMS position/1 m, :func:`shipid.methods.mmg.estimator.horizon_score`, errors pooled
over folds):

1. the regression CV of :func:`shipid.methods.mmg.cv_fast.cross_validate_horizons` over the candidates
   of :data:`shipid.methods.mmg.candidates.CANDIDATES` (``folds`` as given; leave one run out by default);
2. :func:`cv_refinement` of the :data:`REFINE_CANDIDATES` best of step 1: each fitted by regression and
   by regression refined by output error (:func:`shipid.methods.mmg.output_error.refined_fit`), both
   scored (folds: ``folds``, else :data:`STAGED_FOLDS`);
3. :func:`cv_refinement` of the port/starboard variants
   (:func:`shipid.methods.mmg.candidates_asym.asym_variants`) of the best row of step 2 on the
   low-speed hull (a single-screw ship's propeller side force, a rudder neutral offset);
4. :func:`cv_refinement` of the surge, slipstream-rudder and wind-gain variants
   (:func:`shipid.methods.mmg.candidates_surge.surge_variants`) of the best row so far, when it is on a
   hull they extend;
5. the choice is the lowest score among all rows of steps 2–4: a candidate and its criterion
   (``"regression"`` or ``"output-error"``), recorded in MODEL.json
   (``diagnostics.structure_selection``: every stage's table, the choice, and why).

The rule was fixed before any held-out score; its evidence (the CV tables on the Esso Osaka training
runs) is in ``docs/validation/mmg.md``.
"""

from __future__ import annotations

from typing import Any, Callable, Mapping, Sequence

import numpy as np

from shipid.errors import ShipidError
from shipid.io.trial import Trial
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import output_error as OE
from shipid.methods.mmg import validate as V
from shipid.methods.mmg.candidates import CANDIDATES
from shipid.methods.mmg.candidates_asym import asym_variants
from shipid.methods.mmg.candidates_surge import BASE_STRUCTURES as SURGE_BASES
from shipid.methods.mmg.candidates_surge import surge_variants
from shipid.methods.mmg.cv_fast import cross_validate_horizons
from shipid.models import mmg

#: Prior structures whose default selection is staged (the only ones with port/starboard and surge variants).
STAGED_STRUCTURES = ("esso-lowspeed",)
#: How many of the best regression-CV candidates step 2 refines.
REFINE_CANDIDATES = 2
#: Folds of the output-error steps when none are given (each costs one output-error fit per fold).
STAGED_FOLDS = 4
#: The structures whose candidates have port/starboard variants.
ASYM_BASES = ("esso-lowspeed",)


def horizon_rows(model: mmg.MmgModel, trials: Sequence[Trial], decimate: int) -> list[dict[str, float]]:
    """Per run: horizon count and RMS of heading (deg) and position (m) over 60-s restarted horizons."""
    out = []
    for tr in trials:
        h = V.validate(model, R.subsample(tr, decimate), horizon=60.0, windows=(), whole=False).horizons
        if h["count"]:
            out.append({"count": h["count"], "psi": h["psi"]["rms"], "pos": h["pos"]["rms"]})
    return out


def summarise_rows(rows: Sequence[dict[str, float]]) -> dict[str, float]:
    """Pooled RMS (horizon-count weighted), the score, and the mean over runs of the per-run RMS."""
    if not rows:
        return {"psi_rms": float("inf"), "pos_rms": float("inf"), "psi_mean_of_runs": float("inf"),
                "pos_mean_of_runs": float("inf"), "score": float("inf"), "runs": 0}
    w = np.array([r["count"] for r in rows], float)
    out = {}
    for q in ("psi", "pos"):
        v = np.array([r[q] for r in rows])
        out[f"{q}_rms"] = float(np.sqrt(np.sum(w * v * v) / np.sum(w))) if np.all(np.isfinite(v)) else float("inf")
        out[f"{q}_mean_of_runs"] = float(np.mean(v))
    out["score"] = R.horizon_score({"psi": out["psi_rms"], "pos": out["pos_rms"]})
    out["runs"] = len(rows)
    return out


def cv_refinement(trials: Sequence[Trial], runs: Sequence[R.SmoothedRun], prior: mmg.MmgModel,
                  candidates: Sequence[str], *, folds: int | None = STAGED_FOLDS, decimate: int = 2,
                  config: R.FitConfig = R.FitConfig(), oe_config: OE.OEConfig = OE.OEConfig(),
                  pool: Mapping[str, Mapping] | None = None, progress: Callable[[str], None] | None = None,
                  per_fold: bool = False) -> dict[str, dict[str, Any]]:
    """``folds``-fold CV over the TRAINING runs of each candidate, regression vs regression + output error.

    Returns ``{candidate + "/regression" | "/output-error": summary}`` with the pooled RMS
    (``psi_rms`` deg, ``pos_rms`` m), the CV ``score`` and the mean over left-out runs of
    their per-run RMS (``*_mean_of_runs``); a candidate whose fit or refinement fails in a fold scores inf.
    ``pool``: where the candidate names are looked up (default :data:`CANDIDATES` of the prior's structure).
    ``per_fold``: each summary also has ``"fold_scores"``, the score of each fold's left-out runs pooled.
    """
    say = progress or (lambda s: None)
    cands = CANDIDATES[prior.structure] if pool is None else pool
    groups = R.fold_groups(len(runs), folds)
    out: dict[str, dict] = {}
    for cname in candidates:
        cprior, free = R.apply_candidate(prior, cands[cname])
        cfg = R.candidate_config(config, cands[cname])
        rows: dict[str, list] = {}
        fold_rows: dict[str, list] = {}
        try:
            for gi, g in enumerate(groups):
                tr_idx = [i for i in range(len(runs)) if i not in g]
                f = R.fit([runs[i] for i in tr_idx], cprior, free, cfg)
                test = [trials[i] for i in g]
                f2, oe = OE.refined_fit(f, [trials[i] for i in tr_idx], oe_config)
                for key, model in ((cname + "/regression", f.model), (cname + "/output-error", f2.model)):
                    sc = horizon_rows(model, test, decimate)
                    rows.setdefault(key, []).extend(sc)
                    fold_rows.setdefault(key, []).append(sc)
                say(f"cv {cname} fold {gi + 1}/{len(groups)}: output-error cost {oe.cost0:.4g} -> {oe.cost:.4g} "
                    f"in {oe.iterations} iterations")
        except (ShipidError, np.linalg.LinAlgError, ValueError, FloatingPointError) as err:
            say(f"cv {cname}: failed ({err}); scored inf")
            for key in (cname + "/regression", cname + "/output-error"):
                out[key] = dict(summarise_rows([]), failed=str(err))
            continue
        for k, v in rows.items():
            out[k] = summarise_rows(v)
            if per_fold:
                out[k]["fold_scores"] = [summarise_rows(fr)["score"] for fr in fold_rows[k]]
    return out


def enough_horizons(trials: Sequence[Trial], prior: mmg.MmgModel, oe_config: OE.OEConfig,
                    per_coefficient: int) -> tuple[bool, str]:
    """Whether the training runs hold ``per_coefficient`` restarted horizons per refinable coefficient of the
    default candidate (the first of :data:`CANDIDATES`), the condition of ``refine="auto"``; and the count."""
    cand = next(iter(CANDIDATES[prior.structure].values()))
    p = sum(1 for m in mmg.MODES for c in cand[m] if not c.startswith(oe_config.exclude_prefixes))
    try:
        H = OE.stack_horizons(trials, oe_config.horizon, oe_config.decimate, oe_config.stride)
        n = int(OE.cluster_index(H, oe_config).max()) + 1
    except ShipidError:
        n = 0
    return n >= per_coefficient * p, f"{n} restarted horizons for {p} refinable coefficients"


def method_line(folds: int | None, oe_folds: int | None) -> str:
    """The one-line description of the staged criterion that MODEL.json records."""
    k1 = "leave-one-run-out" if folds is None else f"{folds}-fold"
    k2 = "leave-one-run-out" if oe_folds is None else f"{oe_folds}-fold"
    return (f"staged CV on the training runs, 60-s restarted horizons, errors pooled over folds, score = RMS "
            f"psi/10 deg + RMS pos/1 m: regression CV ({k1}) of every candidate; {k2} CV, regression and "
            f"output error, of the {REFINE_CANDIDATES} best, then of the port/starboard variants of the best "
            "low-speed row, then of the surge / slipstream-rudder / wind-gain variants of the best row; "
            "lowest score of all")


def select_staged(trials: Sequence[Trial], runs: Sequence[R.SmoothedRun], prior: mmg.MmgModel, *,
                  config: R.FitConfig = R.FitConfig(), folds: int | None = None,
                  oe_config: OE.OEConfig = OE.OEConfig(), criteria: Sequence[str] = ("regression", "output-error"),
                  progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Steps 1–5 of the module docstring on the TRAINING runs.

    ``criteria``: the rows the choice is among (``"output-error"`` only: the refined rows).
    Returns ``{"chosen": candidate, "criterion": "regression" | "output-error", "pool": every candidate scored
    (name -> candidate dict), "selection": the record for MODEL.json}``.
    """
    say = progress or (lambda s: None)
    pool = dict(CANDIDATES[prior.structure])
    oe_folds = STAGED_FOLDS if folds is None else folds
    table = cross_validate_horizons(trials, runs, prior, pool, config=config, folds=folds)
    ranked = sorted(table, key=lambda c: table[c]["score"])[:REFINE_CANDIDATES]
    say(f"regression CV: output-error CV of {', '.join(ranked)}")
    kw = dict(folds=oe_folds, config=config, oe_config=oe_config, pool=pool, progress=say)
    ref = cv_refinement(trials, runs, prior, ranked, **kw)
    stages = [{"stage": "refinement", "candidates": ranked,
               "why": f"the {REFINE_CANDIDATES} best of the regression CV"}]

    def best_row(keys):
        ok = [k for k in keys if np.isfinite(ref[k]["score"])]
        return min(ok, key=lambda k: ref[k]["score"]) if ok else None

    def stage(b, variants, name, what, why):
        """Output-error CV of ``variants`` of the structure of row ``b``, recorded as stage ``name``."""
        base = b.rsplit("/", 1)[0]
        extra = variants(base, pool[base])
        pool.update(extra)
        say(f"output-error CV of the {what} variants of '{base}'")
        ref.update(cv_refinement(trials, runs, prior, list(extra), **kw))
        stages.append({"stage": name, "base": base, "candidates": list(extra), "why": why})

    low = [k for k in ref if pool[k.rsplit("/", 1)[0]].get("structure", prior.structure) in ASYM_BASES]
    b = best_row(low)
    if b is not None:
        stage(b, asym_variants, "port/starboard", "port/starboard",
              f"'{b}' is the best row on the low-speed hull so far")
    b = best_row(ref)
    if b is not None and pool[b.rsplit("/", 1)[0]].get("structure", prior.structure) in SURGE_BASES:
        stage(b, surge_variants, "surge", "surge / slipstream-rudder / wind-gain", f"'{b}' is the best row so far")
    rows = [k for k in ref if k.rsplit("/", 1)[1] in criteria]
    choice = best_row(rows)
    if choice is None:
        raise ShipidError("staged structure selection: every candidate failed in the cross-validation")
    name, criterion = choice.rsplit("/", 1)
    runner_up = best_row([k for k in rows if k != choice])
    why = f"lowest CV score of the {len(rows)} rows scored: {ref[choice]['score']:.4f} ({choice})"
    if runner_up is not None:
        why += f"; next {ref[runner_up]['score']:.4f} ({runner_up})"
    selection = {"method": method_line(folds, oe_folds), "criterion": "staged", "table": table,
                 "refinement_table": ref, "stages": stages, "chosen": name, "chosen_criterion": criterion,
                 "why": why, "training_runs": [r.source for r in runs]}
    return {"chosen": name, "criterion": criterion, "pool": pool, "selection": selection}


__all__ = ["STAGED_STRUCTURES", "REFINE_CANDIDATES", "STAGED_FOLDS", "horizon_rows", "summarise_rows",
           "cv_refinement", "enough_horizons", "method_line", "select_staged"]
