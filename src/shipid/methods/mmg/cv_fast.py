"""Batched cross-validation of MMG candidate structures on restarted horizons.

The same numbers as :func:`shipid.methods.mmg.estimator.cross_validate` with
:func:`shipid.methods.mmg.estimator.horizon_sse` as fold errors (the reference path,
kept and tested against this one), computed in far fewer numpy calls:

1. every candidate is fitted on every fold's training runs from the sums of per-run
   regression moments computed once per candidate (:mod:`shipid.methods.mmg.moments`:
   the fit of :func:`shipid.methods.mmg.estimator.fit` on the fold's stacked
   :func:`shipid.methods.mmg.estimator.regression_data`, to rounding);
2. every restarted horizon of every test run, of every fold, of every candidate that
   shares a structure and particulars, becomes one row of a single batch with the
   coefficients of its fold's model; all rows are integrated together by RK4 with
   the measured inputs held over each step (:func:`shipid.methods.mmg.manoeuvres.rows_rk4`,
   the per-row form of :func:`shipid.models.mmg.simulate_batch`), on each run's own
   uniform grid ``t_0 + dt k`` as :func:`shipid.methods.mmg.validate.validate` uses;
3. the errors are pooled exactly as the reference does: per run the mean square over
   its valid horizon samples times its horizon count, summed over the fold's runs,
   then over folds; a non-finite prediction makes that candidate's error infinite.

The cost of the reference is about one numpy call chain per step per run per
candidate per fold; here it is one per step per structure group, so the per-call
overhead (which dominates at a few horizons per batch) is paid ``runs × candidates``
times less often.
"""

from __future__ import annotations

import json
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from shipid.io.trial import Trial
from shipid.errors import ShipidError
from shipid.methods.mmg import manoeuvres as MM
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import validate as V
from shipid.methods.mmg.moments import fit_from_moments, run_moments
from shipid.models import mmg, mmg_kernels


def run_horizons(trial: Trial, horizon: float, decimate: int, stride: float | None = None) -> dict[str, Any] | None:
    """The restarted horizons of one run as :func:`shipid.methods.mmg.validate.validate` builds them (None if none).

    ``stride``: seconds between horizon starts; None (default) restarts every ``horizon`` seconds, as the
    validation does (non-overlapping horizons); a shorter stride gives overlapping ones.
    """
    tr = R.subsample(trial, decimate)
    t = np.asarray(tr.t, float)
    Z = V.measured_states(tr)
    U = V.trial_inputs(tr)
    V._check_finite(tr, Z, U)
    dt = float(np.median(np.diff(t)))
    nsteps = int(round(horizon / dt))
    every = nsteps if stride is None else max(int(round(stride / dt)), 1)
    starts = V.horizon_starts(t.size, nsteps, every, min_steps=max(nsteps // 2, 2))
    if starts.size == 0:
        return None
    L = nsteps + 1
    j = starts[:, None] + np.arange(L)[None, :]
    idx = np.minimum(j, t.size - 1)
    tg = t[0] + dt * np.arange(L)
    return {"x0": Z[starts], "U": U[idx], "Z": Z[idx], "valid": j <= t.size - 1, "h": np.diff(tg),
            "count": int(starts.size)}


def simulate_rows(model: mmg.MmgModel, Th: Mapping[str, np.ndarray], x0: np.ndarray, U: np.ndarray,
                  h: np.ndarray, compiled: bool = True) -> np.ndarray:
    """(B, L, 6) predictions of rows with inputs ``U`` (B, L, 4) and steps ``h`` (B, L - 1).

    ``compiled``: for the structures :func:`shipid.models.mmg_kernels.supported` names, the compiled
    copy :func:`shipid.models.mmg_kernels.simulate_rows` (the same numbers to round-off); False, or any
    other structure, integrates :func:`shipid.methods.mmg.manoeuvres.rows_rk4` step by step (the reference).
    """
    if compiled and mmg_kernels.supported(model.structure):
        return mmg_kernels.simulate_rows(model.structure, model.particulars, mmg.mass_terms(model), Th, x0, U, h)
    B, L = U.shape[:2]
    out = np.empty((B, L, 6))
    x = np.array(x0, float)
    out[:, 0] = x
    with np.errstate(all="ignore"):
        for k in range(L - 1):
            u = U[:, k]
            x = MM.rows_rk4(model, Th, x, u[:, 0], u[:, 1], h[:, k:k + 1], wind=(u[:, 2], u[:, 3]))
            out[:, k + 1] = x
    return out


def _group_key(model: mmg.MmgModel) -> str:
    return model.structure + json.dumps({k: float(v) for k, v in sorted(model.particulars.items())})


def cross_validate_horizons(trials: Sequence[Trial], runs: Sequence[R.SmoothedRun], prior: mmg.MmgModel,
                            candidates: Mapping[str, Mapping], *, config: R.FitConfig = R.FitConfig(),
                            folds: int | None = None, horizon: float = 60.0, decimate: int = 2,
                            progress: Callable[[], None] | None = None, moments: bool = True) -> dict[str, dict]:
    """The table of :func:`shipid.methods.mmg.estimator.cross_validate` with horizon errors, batched (module docstring).

    ``moments``: fit the folds from per-run moments (:mod:`shipid.methods.mmg.moments`); False
    stacks each fold's regression rows and calls :func:`shipid.methods.mmg.estimator.fit`
    (the same fits; kept for the benchmark and the tests).
    """
    groups = R.fold_groups(len(runs), folds)
    hz: list[dict | None] = []
    bad: set[int] = set()              # runs the reference's fold errors would fail on
    for i, tr in enumerate(trials):
        try:
            hz.append(run_horizons(tr, horizon, decimate))
        except ShipidError:
            hz.append(None)
            bad.add(i)
    fitted: dict[str, list[tuple[list[int], mmg.MmgModel | None]]] = {}
    failed: dict[str, bool] = {}
    for cname, cand in candidates.items():
        cprior, free = R.apply_candidate(prior, cand)
        cfg = R.candidate_config(config, cand)
        fitted[cname], failed[cname] = [], False
        try:       # each run's regression data once; a fold sums (or stacks) its training runs' blocks
            blocks = [R.regression_data([run], cprior, free, cfg) for run in runs]
            if moments:
                blocks = [run_moments(b) for b in blocks]
        except (ShipidError, np.linalg.LinAlgError, ValueError):
            blocks = None
        for g in groups:
            tr_idx = [i for i in range(len(runs)) if i not in g]
            if not tr_idx:
                continue
            try:
                if blocks is None:
                    raise ValueError("regression data failed")
                if moments:
                    m = fit_from_moments([blocks[i] for i in tr_idx], cprior, cfg.ridge_k)
                else:
                    data = {md: R.ModeData(H=np.concatenate([blocks[i][md].H for i in tr_idx]),
                                           y=np.concatenate([blocks[i][md].y for i in tr_idx]),
                                           names=blocks[0][md].names) for md in mmg.MODES}
                    m = R.fit([runs[i] for i in tr_idx], cprior, free, cfg, data=data).model
            except (ShipidError, np.linalg.LinAlgError, ValueError):
                failed[cname], m = True, None
            if bad.intersection(g):
                failed[cname] = True
            fitted[cname].append((g, m))
            if progress is not None:
                progress()
    # rows: (candidate, fold, run) blocks of horizons, batched per structure group
    se = {c: {"psi": 0.0, "pos": 0.0} for c in candidates}
    cnt = {c: 0 for c in candidates}
    by_group: dict[str, list[tuple[str, mmg.MmgModel, int]]] = {}
    for cname, lst in fitted.items():
        for g, m in lst:
            if m is None:
                continue
            for i in g:
                if hz[i] is not None:
                    by_group.setdefault(_group_key(m), []).append((cname, m, i))
    for blocks in by_group.values():
        model0 = blocks[0][1]
        Lmax = max(hz[i]["U"].shape[1] for _, _, i in blocks)

        def pad(a, fill):
            w = [(0, 0), (0, Lmax - a.shape[1])] + [(0, 0)] * (a.ndim - 2)
            return np.pad(a, w, mode="edge") if fill is None else np.pad(a, w, constant_values=fill)

        x0 = np.concatenate([hz[i]["x0"] for _, _, i in blocks])
        U = np.concatenate([pad(hz[i]["U"], None) for _, _, i in blocks])
        h = np.concatenate([pad(np.repeat(hz[i]["h"][None], hz[i]["count"], 0), None) for _, _, i in blocks])
        Th = {md: np.concatenate([np.repeat(m.theta(md)[None], hz[i]["count"], 0) for _, m, i in blocks])
              for md in mmg.MODES}
        P = simulate_rows(model0, Th, x0, U, h)
        r0 = 0
        for cname, _, i in blocks:
            H = hz[i]
            n = H["count"]
            E = V._errors(P[r0:r0 + n, :H["U"].shape[1]], H["Z"])
            r0 += n
            for q in ("psi", "pos"):
                e = E[q][H["valid"]]
                ms = float(np.mean(e * e)) if np.all(np.isfinite(e)) else float("inf")
                se[cname][q] += n * ms
            cnt[cname] += n
    table: dict[str, dict] = {}
    for cname in candidates:
        n = cnt[cname]
        rms = {q: (float(np.sqrt(se[cname][q] / n)) if n else float("nan")) for q in ("psi", "pos")}
        score = R.horizon_score(rms) if n and not failed[cname] else float("inf")
        if not np.isfinite(score):
            score = float("inf")
        row = {"score": float(score), "folds": len(groups)}
        row.update({f"{q}_rms": v for q, v in rms.items()})
        row["count"] = int(n)
        table[cname] = row
    return table


__all__ = ["cross_validate_horizons", "run_horizons", "simulate_rows"]
