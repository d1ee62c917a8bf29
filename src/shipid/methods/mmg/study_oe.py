"""Esso Osaka held-out study on the 9-run split, with the output-error refinement chosen by training-run CV.

Split (:func:`heldout9_split`): the test runs are the union of both papers' test runs
(:data:`shipid.io.basins.SPLITS`, 8 runs) plus one random run — 9 runs; the other 32
runs of the data set are the training runs. The ninth run (:data:`NINTH`): ``"issue"``
(default) ``random_03-Aug-2020_11_04_37``, the split on which the published set scores
12.20° / 0.842 m; ``"seeded"`` a draw with
:data:`RANDOM_SEED` from the random runs not among the eight (``random_06-Aug-2020_16_24_25_6``);
``"bench"`` the ninth run of
``benchmarks/bench_mmg_cv.py`` (``random_31-Jul-2020_14_52_18``).

Protocol, all on the 32 training runs before any test run is read:

1. the structure is chosen among the frozen candidates by the regression CV of
   :func:`shipid.methods.mmg.pipeline.select_structure` (``folds``-fold, 60-s restarted
   horizons, score RMS ψ/10° + RMS position/1 m);
2. :func:`cv_refinement` compares, on the same folds, the regression estimate with the
   regression estimate refined by output error
   (:mod:`shipid.methods.mmg.output_error`), each fitted without the fold's runs and
   scored on them; pooled RMS and the mean over left-out runs of their per-run RMS;
3. the final model is the chosen structure fitted on all 32 runs, refined when step 2
   says so (lower pooled score).

The held-out side (:func:`heldout9_evaluate`) then reads the 9 test runs once and
reports, per run and as the mean over runs of the per-run RMS over 60-s horizons
restarted every 60 s at 10 Hz, the identified and the published model.

The refinement settings tried, the port/starboard, surge, wind and timing terms the study adopted,
and every held-out result with the command that regenerates it: ``docs/validation/mmg.md``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from shipid.io.basins import SPLITS, esso_dir, read_esso
from shipid.io.trial import Trial
from shipid.errors import InputError
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import output_error as OE
from shipid.methods.mmg import pipeline as P
from shipid.methods.mmg import timing as TM
from shipid.methods.mmg import timing_inputs as TI
from shipid.methods.mmg import validate as V
from shipid.methods.mmg.candidates_asym import asym_variants
from shipid.methods.mmg.candidates_surge import BASE_STRUCTURES as SURGE_BASES
from shipid.methods.mmg.candidates_surge import surge_variants
from shipid.models import mmg

#: Seed of the ``"seeded"`` draw of the ninth (random-manoeuvre) test run.
RANDOM_SEED = 19
#: The ninth test run of each named split (module docstring); ``"seeded"`` is drawn.
NINTH = {"issue": "random/random_03-Aug-2020_11_04_37.csv", "seeded": None,
         "bench": "random/random_31-Jul-2020_14_52_18.csv"}


def heldout9_split(root: Path | None = None, ninth: str = "issue") -> dict[str, list[str]]:
    """``{"train": 32 runs, "test": 9 runs}`` (module docstring), as paths relative to the data folder."""
    if ninth not in NINTH:
        raise InputError(f"unknown ninth-run choice '{ninth}' (choose from {', '.join(NINTH)})")
    d = esso_dir(root)
    allruns = sorted(str(p.relative_to(d)) for p in d.glob("*/*.csv"))
    test: list[str] = []
    for sp in ("miyauchi2022", "wakita2022"):
        test += [f for f in SPLITS[sp]["test"] if f not in test]
    rnd = [f for f in allruns if f.startswith("random/") and f not in test]
    test.append(NINTH[ninth] or rnd[int(np.random.default_rng(RANDOM_SEED).integers(len(rnd)))])
    return {"train": [f for f in allruns if f not in test], "test": test, "ninth": ninth}


def _scores(model: mmg.MmgModel, trials: Sequence[Trial], decimate: int) -> list[dict[str, float]]:
    """Per run: horizon count and squared-RMS of heading (deg) and position (m)."""
    out = []
    for tr in trials:
        h = V.validate(model, R.subsample(tr, decimate), horizon=60.0, windows=(), whole=False).horizons
        if h["count"]:
            out.append({"count": h["count"], "psi": h["psi"]["rms"], "pos": h["pos"]["rms"]})
    return out


def _summarise(rows: Sequence[dict[str, float]]) -> dict[str, float]:
    w = np.array([r["count"] for r in rows], float)
    out = {}
    for q in ("psi", "pos"):
        v = np.array([r[q] for r in rows])
        out[f"{q}_rms"] = float(np.sqrt(np.sum(w * v * v) / np.sum(w))) if np.all(np.isfinite(v)) else float("inf")
        out[f"{q}_mean_of_runs"] = float(np.mean(v))
    out["score"] = R.horizon_score({"psi": out["psi_rms"], "pos": out["pos_rms"]})
    out["runs"] = len(rows)
    return out


#: Per-run horizon counts and RMS of a model on runs, and their pooled summary (public names of the two helpers).
horizon_rows = _scores
summarise_rows = _summarise


def cv_refinement(trials: Sequence[Trial], runs: Sequence[R.SmoothedRun], prior: mmg.MmgModel,
                  candidates: Sequence[str], *, folds: int = 4, decimate: int = 2,
                  oe_config: OE.OEConfig = OE.OEConfig(), pool: Mapping[str, Mapping] | None = None,
                  progress: Callable[[str], None] | None = None, per_fold: bool = False) -> dict[str, dict[str, Any]]:
    """``folds``-fold CV over the TRAINING runs of each candidate, regression vs regression + output error.

    Returns ``{candidate + "/regression" | "/output-error": summary}`` with the pooled RMS
    (``psi_rms`` deg, ``pos_rms`` m), the CV ``score`` and the mean over left-out runs of
    their per-run RMS (``*_mean_of_runs``). ``pool``: where the candidate names are looked up
    (default :data:`shipid.methods.mmg.candidates.CANDIDATES` of the prior's structure).
    ``per_fold``: each summary also has ``"fold_scores"``, the score of each fold's left-out runs pooled.
    """
    say = progress or (lambda s: None)
    cands = R.CANDIDATES[prior.structure] if pool is None else pool
    groups = R.fold_groups(len(runs), folds)
    rows: dict[str, list] = {}
    fold_rows: dict[str, list] = {}
    for cname in candidates:
        cprior, free = R.apply_candidate(prior, cands[cname])
        cfg = R.candidate_config(R.FitConfig(), cands[cname])
        for gi, g in enumerate(groups):
            tr_idx = [i for i in range(len(runs)) if i not in g]
            f = R.fit([runs[i] for i in tr_idx], cprior, free, cfg)
            test = [trials[i] for i in g]
            f2, oe = OE.refined_fit(f, [trials[i] for i in tr_idx], oe_config)
            for key, model in ((cname + "/regression", f.model), (cname + "/output-error", f2.model)):
                sc = _scores(model, test, decimate)
                rows.setdefault(key, []).extend(sc)
                fold_rows.setdefault(key, []).append(sc)
            say(f"cv {cname} fold {gi + 1}/{len(groups)}: output-error cost {oe.cost0:.4g} -> {oe.cost:.4g} "
                f"in {oe.iterations} iterations")
    out = {k: _summarise(v) for k, v in rows.items()}
    if per_fold:
        for k, v in fold_rows.items():
            out[k]["fold_scores"] = [_summarise(fr)["score"] for fr in v]
    return out


def heldout9_train(*, root: Path | None = None, ninth: str = "issue", folds: int = 4, refine_candidates: int = 2,
                   oe_config: OE.OEConfig = OE.OEConfig(), asymmetry: bool = True, surge: bool = True,
                   retime: bool = True, input_lags: bool = True,
                   progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Training side (module docstring, steps 1–3). Reads no test run.

    ``refine_candidates``: how many of the best regression candidates :func:`cv_refinement` compares.
    ``asymmetry``: then :func:`cv_refinement` also scores the port/starboard variants
    (:func:`shipid.methods.mmg.candidates_asym.asym_variants`) of the candidate (low-speed hull) that
    the first refinement CV ranks best, and the choice is among all.
    ``surge``: then it also scores the surge and slipstream-rudder variants
    (:func:`shipid.methods.mmg.candidates_surge.surge_variants`) of the candidate ranked best so far
    (if it is on a low-speed hull), and the choice is among all.
    ``retime``: before anything else, the channel offsets of :func:`shipid.methods.mmg.timing.estimate_lags`
    are estimated on the training runs and every training run is re-timed by them
    (:func:`shipid.methods.mmg.timing.retime`); the offsets are returned as ``"retime"`` and
    :func:`heldout9_evaluate` re-times the test runs by the same offsets.
    ``input_lags`` (with ``retime``): the offsets of the rudder angle, propeller rate and wind
    (:func:`shipid.methods.mmg.timing_inputs.estimate_input_lags` on the state-re-timed training runs)
    are added, and the inputs re-timed in the same step; the estimate with its per-run spread is
    returned as ``"retime_inputs"``.
    """
    say = progress or (lambda s: None)
    sp = heldout9_split(root, ninth)
    leak = set(sp["train"]) & set(sp["test"])
    if leak:
        raise ValueError(f"test runs in the training set: {sorted(leak)}")
    say(f"heldout9: reading {len(sp['train'])} training runs")
    trials = [read_esso(f, root) for f in sp["train"]]
    lags = ilags = None
    if retime:
        lags = TM.estimate_lags(trials)
        say(f"heldout9: channel offsets behind the position (training runs): heading {lags.psi:.2f} s, "
            f"velocities {lags.uv:.2f} s, yaw rate {lags.r:.2f} s")
        if input_lags:
            ilags = TI.estimate_input_lags([TM.retime(tr, lags) for tr in trials])
            lags = TI.with_inputs(lags, ilags)
            say(f"heldout9: input offsets (training runs; per-run median, se): rudder {ilags.delta:.2f} s "
                f"({ilags.delta_median:.2f}, {ilags.delta_se:.2f}), propeller {ilags.n:.2f} s ({ilags.n_median:.2f}, "
                f"{ilags.n_se:.2f}), wind {ilags.wind:.2f} s ({ilags.wind_median:.2f}, {ilags.wind_se:.2f})")
        trials = [TM.retime(tr, lags) for tr in trials]
        say("heldout9: training runs re-timed")
    prior = mmg.load_published("esso_osaka_3m", root)
    runs = [R.smooth_run(tr) for tr in trials]
    best, table = P.select_structure(trials, runs, prior, folds=folds)
    ranked = sorted(table, key=lambda c: table[c]["score"])[:refine_candidates]
    pool = dict(R.CANDIDATES[prior.structure])
    say(f"heldout9: regression CV chose '{best}'; output-error CV on {', '.join(ranked)}")
    ref = cv_refinement(trials, runs, prior, ranked, folds=folds, oe_config=oe_config, pool=pool, progress=say)
    if asymmetry:
        # the port/starboard variants of the candidate the first refinement CV ranks best (on the low-speed hull)
        base = next(k.rsplit("/", 1)[0] for k in sorted(ref, key=lambda k: ref[k]["score"])
                    if pool[k.rsplit("/", 1)[0]].get("structure", prior.structure) == "esso-lowspeed")
        extra = asym_variants(base, pool[base])
        pool.update(extra)
        say(f"heldout9: output-error CV of the port/starboard variants of '{base}'")
        ref.update(cv_refinement(trials, runs, prior, list(extra), folds=folds, oe_config=oe_config, pool=pool,
                                 progress=say))
    if surge:
        # the surge / slipstream-rudder variants of the candidate ranked best so far (on a low-speed hull)
        best = min(ref, key=lambda k: ref[k]["score"]).rsplit("/", 1)[0]
        if pool[best].get("structure", prior.structure) in SURGE_BASES:
            extra = surge_variants(best, pool[best])
            pool.update(extra)
            say(f"heldout9: output-error CV of the surge / slipstream-rudder variants of '{best}'")
            ref.update(cv_refinement(trials, runs, prior, list(extra), folds=folds, oe_config=oe_config, pool=pool,
                                     progress=say))
    choice = min(ref, key=lambda k: ref[k]["score"])
    structure, criterion = choice.rsplit("/", 1)
    res = P.identify(trials, prior, structure=structure, select=False, candidates=pool,
                     refine="output-error" if criterion == "output-error" else "none", oe_config=oe_config,
                     name="esso-osaka-3m-heldout9",
                     extra_provenance={"split": "heldout9", "test_runs_never_used": sp["test"]})
    return {"split": sp, "regression_cv": table, "refinement_cv": ref, "chosen": choice,
            "result": res.to_dict(), "retime": None if lags is None else lags.to_dict(),
            "retime_inputs": None if ilags is None else
            dict(ilags.to_dict(), not_determined=TI.at_bound(ilags))}


def heldout9_evaluate(trained: dict[str, Any], *, root: Path | None = None) -> dict[str, Any]:
    """Held-out side: identified and published models on the 9 test runs (10 Hz, 60-s horizons every 60 s).

    With ``trained["retime"]`` the identified model is scored on the test runs re-timed by those
    offsets (estimated on the training runs; heading error against the raw heading samples that
    much later), the published model on the runs as recorded.
    """
    ident = V.model_from_result(trained["result"])
    pub = mmg.load_published("esso_osaka_3m", root)
    test = [read_esso(f, root) for f in trained["split"]["test"]]
    lags = trained.get("retime")
    moved = test if not lags else [TM.retime(tr, TM.Lags(**lags)) for tr in test]
    out: dict[str, Any] = {"per_run": {}}
    for name, m, runs in (("identified", ident, moved), ("published", pub, test)):
        rows = _scores(m, runs, 1)
        out["per_run"][name] = dict(zip(trained["split"]["test"], rows))
        out[name] = _summarise(rows)
    return out


def format_heldout9(st: dict[str, Any]) -> str:
    """The two CV tables of :func:`heldout9_train` and the choice."""
    lines = [f"Esso Osaka 9-run held-out split ('{st['split'].get('ninth', 'issue')}'): "
             f"{len(st['split']['train'])} training runs, "
             f"test runs {', '.join(st['split']['test'])}",
             "  regression CV (training runs): candidate, score, pooled RMS psi [deg] / pos [m]"]
    for c, r in st["regression_cv"].items():
        lines.append(f"    {c:<56} {r['score']:7.3f} {r['psi_rms']:7.2f} {r['pos_rms']:7.3f}")
    lines.append("  refinement CV (training runs): pooled score, pooled RMS psi / pos, mean over left-out runs psi / pos")
    for c, r in st["refinement_cv"].items():
        mark = " <- chosen" if c == st["chosen"] else ""
        lines.append(f"    {c:<56} {r['score']:7.3f} {r['psi_rms']:7.2f} {r['pos_rms']:7.3f} "
                     f"{r['psi_mean_of_runs']:7.2f} {r['pos_mean_of_runs']:7.3f}{mark}")
    return "\n".join(lines)


def format_heldout9_test(st: dict[str, Any]) -> str:
    """The held-out table of :func:`heldout9_evaluate` (``st["heldout"]``)."""
    lines = []
    if "heldout" in st:
        ev = st["heldout"]
        lines.append("  held-out (read once, after the choice): run, identified psi [deg] / pos [m], published")
        for run in st["split"]["test"]:
            a, b = ev["per_run"]["identified"].get(run), ev["per_run"]["published"].get(run)
            if a and b:
                lines.append(f"    {run:<50} {a['psi']:7.2f} {a['pos']:7.3f}   {b['psi']:7.2f} {b['pos']:7.3f}")
        i, p = ev["identified"], ev["published"]
        lines.append(f"  mean over runs: identified {i['psi_mean_of_runs']:.2f} deg / {i['pos_mean_of_runs']:.3f} m, "
                     f"published {p['psi_mean_of_runs']:.2f} deg / {p['pos_mean_of_runs']:.3f} m")
    return "\n".join(lines)


__all__ = ["RANDOM_SEED", "NINTH", "heldout9_split", "horizon_rows", "summarise_rows", "cv_refinement",
           "heldout9_train", "heldout9_evaluate", "format_heldout9", "format_heldout9_test"]
