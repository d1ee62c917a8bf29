"""Benchmark: ``identify mmg`` structure cross-validation, batched (cv_fast) against the reference loop.

Data: the Esso Osaka 3 m runs that are training runs of both papers' splits and are
not random runs (the held-out split of issue 19 is the union of both papers' test
runs plus one random run, so no random run is read): turning, zig-zag and berthing
runs, 25 in all (``--runs`` to take fewer). Needs ``$SHIPID_DATA`` (or ../shared/data).

1. Step 1 (EKF + smoother) of every run: process CPU time.
2. The CV table with ``--folds`` folds over ``--ref-candidates`` candidates by both
   paths (``select_structure(batched=True | False)``), interleaved ``--repeat`` times,
   best CPU time of each; the ratio reference / batched and the largest relative
   difference of the scores.
3. ``identify`` as the CLI runs it (all 12 candidates, batched CV, final fit) on all
   runs: CPU and wall time; the reference's time for all candidates is extrapolated
   from its per-candidate time in 2 (printed as such, not measured).
4. With ``--loo``: the batched leave-one-run-out CV over all candidates (the studies' scheme).

Run: ``python benchmarks/bench_mmg_cv.py [--runs 25] [--folds 4] [--ref-candidates 2] [--repeat 1] [--loo]``
"""

from __future__ import annotations

import argparse
import os
import time


def _runs(limit: int | None):
    from shipid.methods.mmg import study as S

    d = S._esso_dir(None)
    test = set(S.SPLITS["miyauchi2022"]["test"]) | set(S.SPLITS["wakita2022"]["test"])
    rel = sorted(f"{p.parent.name}/{p.name}" for p in d.glob("*/*.csv") if p.parent.name != "random")
    rel = [r for r in rel if r not in test]
    # interleave manoeuvre types so that a prefix mixes them
    by = {}
    for r in rel:
        by.setdefault(r.split("/")[0], []).append(r)
    mixed = [r for grp in zip(*[by[k] + [None] * (max(map(len, by.values())) - len(by[k])) for k in sorted(by)])
             for r in grp if r]
    return mixed[:limit] if limit else mixed


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=None)
    ap.add_argument("--folds", type=int, default=4)
    ap.add_argument("--ref-candidates", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--loo", action="store_true", help="Also time the batched leave-one-run-out CV.")
    a = ap.parse_args()

    from shipid.methods.mmg import estimator as R
    from shipid.models import mmg
    from shipid.methods.mmg import study as S

    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs")
    names = _runs(a.runs)
    trials = [S.read_esso(r) for r in names]
    print(f"{len(trials)} runs, {sum(len(t) for t in trials)} samples, {a.folds} folds")
    c0 = time.process_time()
    runs = [R.smooth_run(tr) for tr in trials]
    print(f"step 1 (EKF + RTS) of all runs: {time.process_time() - c0:.1f} s CPU")
    prior = mmg.load_published("esso_osaka_3m")
    allc = R.CANDIDATES[prior.structure]
    sub = dict(list(allc.items())[:a.ref_candidates])
    best = {True: float("inf"), False: float("inf")}
    tables = {}
    for _ in range(a.repeat):
        for batched in (False, True):
            c0 = time.process_time()
            _, tables[batched] = R.select_structure(trials, runs, prior, sub, folds=a.folds, batched=batched)
            best[batched] = min(best[batched], time.process_time() - c0)
    diff = max(abs(tables[True][k]["score"] - tables[False][k]["score"]) / abs(tables[False][k]["score"])
               for k in sub)
    print(f"CV over {len(sub)} candidates: reference {best[False]:.2f} s, batched {best[True]:.2f} s CPU, "
          f"ratio {best[False] / best[True]:.1f}x; largest relative score difference {diff:.1e}")
    c0, w0 = time.process_time(), time.perf_counter()
    res = R.identify(trials, prior, folds=a.folds)
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    per_cand = best[False] / len(sub)
    print(f"identify (step 1 + batched CV over {len(allc)} candidates + fit): {cpu:.1f} s CPU, {wall:.1f} s wall; "
          f"chosen '{res.model['structure_candidate']}'")
    print(f"reference CV over {len(allc)} candidates, extrapolated from {len(sub)}: ~{per_cand * len(allc):.0f} s CPU "
          "(plus step 1)")
    if a.loo:
        c0 = time.process_time()
        R.select_structure(trials, runs, prior, allc, folds=None)
        print(f"batched leave-one-run-out CV over {len(allc)} candidates (the studies' scheme): "
              f"{time.process_time() - c0:.1f} s CPU")


if __name__ == "__main__":
    main()
