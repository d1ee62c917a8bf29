"""Benchmark: ``identify mmg`` with cross-validation on the Esso Osaka 3 m runs, and the Esso held-out study.

Peer: the previous code path, measured in the same run — step 1 by the reference
:func:`shipid.estimate.cd_ekf.cd_ekf` + :func:`shipid.estimate.smoothers.rts_smoother`
(``smooth_run(compiled=False)``) instead of the compiled
:func:`shipid.methods.mmg.kernels.kinematic_filter_smoother`, and the CV folds fitted by
stacking their rows (``cross_validate_horizons(moments=False)``) instead of from per-run
moments (:mod:`shipid.methods.mmg.moments`). Both paths give the same numbers (printed:
the largest differences).

Data: 32 training runs — all 41 runs less the union of both papers' test runs
(8 runs) and one random run (``random_31-Jul-2020_14_52_18``, this benchmark's choice of
the ninth held-out run; ``--runs`` takes fewer). Needs ``$SHIPID_DATA`` (or ../shared/data).

1. Step 1 of every run: compiled vs reference, process CPU time, ratio.
2. The batched CV table, ``--folds`` folds over all 12 candidates: moments vs stacked fits.
3. ``identify`` (step 1, CV, final fit) without the output-error refinement: wall and CPU time of
   the current path and of the previous one; the ratio. Then as ``shipid identify mmg --folds 4``
   runs it (``--refine auto``: the output-error refinement of
   :mod:`shipid.methods.mmg.output_error` for the Esso structure): wall and CPU time, and the ratio
   to the same identify without the refinement measured just before.
4. With ``--study``: ``shipid study esso-osaka-heldout`` (both splits, leave-one-run-out CV,
   held-out evaluation) wall time; with ``--study-reference`` also the previous path's (slow).

Run: ``python benchmarks/bench_mmg_cv.py [--runs 32] [--folds 4] [--study] [--study-reference]``
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import os
import time

NINTH_HELDOUT = "random/random_31-Jul-2020_14_52_18.csv"


def _runs(limit: int | None):
    from shipid.methods.mmg import study as S

    d = S._esso_dir(None)
    test = set(S.SPLITS["miyauchi2022"]["test"]) | set(S.SPLITS["wakita2022"]["test"]) | {NINTH_HELDOUT}
    rel = sorted(f"{p.parent.name}/{p.name}" for p in d.glob("*/*.csv"))
    rel = [r for r in rel if r not in test]
    return rel[:limit] if limit else rel


@contextlib.contextmanager
def previous_path():
    """Run the pipeline with the reference step 1 and stacked fold fits (the peer)."""
    from shipid.methods.mmg import cv_fast, estimator as R, pipeline as P

    saved = R.smooth_run, cv_fast.cross_validate_horizons
    R.smooth_run = functools.partial(saved[0], compiled=False)
    cv_fast.cross_validate_horizons = functools.partial(saved[1], moments=False)
    try:
        yield
    finally:
        R.smooth_run, cv_fast.cross_validate_horizons = saved


def _timed(fn):
    c0, w0 = time.process_time(), time.perf_counter()
    out = fn()
    return out, time.process_time() - c0, time.perf_counter() - w0


def _study():
    from shipid.methods.mmg import study as S

    out = {}
    for sp in ("miyauchi2022", "wakita2022"):
        out[sp] = S.esso_train(sp)
    for sp in out:
        out[sp]["heldout"] = S.esso_evaluate(out[sp])
    return {sp: (o["structure"], o["heldout"]["pooled"]["identified"]["psi"]["rms"],
                 o["heldout"]["pooled"]["identified"]["pos"]["rms"]) for sp, o in out.items()}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=None)
    ap.add_argument("--folds", type=int, default=4)
    ap.add_argument("--study", action="store_true", help="Also time the full Esso held-out study.")
    ap.add_argument("--study-reference", action="store_true", help="... and the previous path's study (slow).")
    a = ap.parse_args()

    import numpy as np

    from shipid.methods.mmg import cv_fast, estimator as R, kernels, pipeline as P  # noqa: F401  (compiles / loads the cache)
    from shipid.methods.mmg import study as S
    from shipid.models import mmg

    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs")
    names = _runs(a.runs)
    trials = [S.read_esso(r) for r in names]
    print(f"{len(trials)} runs, {sum(len(t) for t in trials)} samples, {a.folds} folds")
    R.smooth_run(trials[0])                                    # compile / load the cache outside the timing
    new, c_new, _ = _timed(lambda: [R.smooth_run(tr) for tr in trials])
    ref, c_ref, _ = _timed(lambda: [R.smooth_run(tr, compiled=False) for tr in trials])
    dmax = max(float(np.max(np.abs(x.s - y.s) / (np.abs(y.s).max(axis=0) + 1e-300))) for x, y in zip(new, ref))
    print(f"1. step 1 (EKF + RTS) of all runs: compiled {c_new:.2f} s, reference {c_ref:.1f} s CPU, "
          f"ratio {c_ref / c_new:.1f}x; largest relative state difference {dmax:.1e}")
    prior = mmg.load_published("esso_osaka_3m")
    cands = R.CANDIDATES[prior.structure]
    tab = {}
    cpu = {}
    for mom in (True, False):
        tab[mom], cpu[mom], _ = _timed(lambda: cv_fast.cross_validate_horizons(trials, new, prior, cands,
                                                                               folds=a.folds, moments=mom))
    diff = max(abs(tab[True][k]["score"] - tab[False][k]["score"]) / abs(tab[False][k]["score"]) for k in cands)
    print(f"2. CV table ({len(cands)} candidates, {a.folds} folds): moments {cpu[True]:.1f} s, stacked "
          f"{cpu[False]:.1f} s CPU, ratio {cpu[False] / cpu[True]:.2f}x; largest relative score difference "
          f"{diff:.1e}")
    res, c1, w1 = _timed(lambda: P.identify(trials, prior, folds=a.folds))
    with previous_path():
        res0, c0, w0 = _timed(lambda: P.identify(trials, prior, folds=a.folds))
    th = np.array([e.value for e in res.estimates.values()])
    th0 = np.array([e.value for e in res0.estimates.values()])
    rel = float(np.max(np.abs(th - th0) / np.maximum(np.abs(th0), 1e-300)))
    print(f"3. identify (step 1 + CV over {len(cands)} candidates + fit): {w1:.1f} s wall ({c1:.1f} s CPU); "
          f"previous path {w0:.1f} s wall ({c0:.1f} s CPU); ratio {w0 / w1:.1f}x wall; chosen "
          f"'{res.model['structure_candidate']}' (previous '{res0.model['structure_candidate']}'), largest "
          f"relative estimate difference {rel:.1e}")
    rp = "auto"
    res2, c2, w2 = _timed(lambda: P.identify(trials, prior, folds=a.folds, refine=rp))
    oe = res2.diagnostics.get("output_error", {})
    print(f"3b. identify as 'shipid identify mmg --folds {a.folds}' (refine '{rp}'): {w2:.1f} s wall "
          f"({c2:.1f} s CPU), {w2 / w1:.2f}x the wall time without the refinement; horizon cost "
          f"{oe.get('cost_start', float('nan')):.4g} -> {oe.get('cost_end', float('nan')):.4g} in "
          f"{oe.get('iterations', 0)} iterations")
    if a.study or a.study_reference:
        out, cs, ws = _timed(_study)
        print(f"4. study esso-osaka-heldout (both splits, LOO CV, held-out evaluation): {ws:.1f} s wall "
              f"({cs:.1f} s CPU)")
        for sp, (st, psi, pos) in out.items():
            print(f"   {sp}: '{st}', held-out pooled {psi:.2f} deg / {pos:.3f} m")
        if a.study_reference:
            with previous_path():
                out0, cs0, ws0 = _timed(_study)
            same = all(out0[sp][0] == out[sp][0] and abs(out0[sp][1] - out[sp][1]) < 1e-6
                       and abs(out0[sp][2] - out[sp][2]) < 1e-6 for sp in out)
            print(f"   previous path: {ws0:.1f} s wall ({cs0:.1f} s CPU); ratio {ws0 / ws:.1f}x wall; "
                  f"same structures and held-out errors (to 1e-6): {same}")


if __name__ == "__main__":
    main()
