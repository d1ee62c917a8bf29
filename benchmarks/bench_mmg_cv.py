"""Benchmark: ``identify mmg`` with cross-validation on the Esso Osaka 3 m runs.

Peer: the previous code path, measured in the same run — step 1 by the reference
:func:`shipid.estimate.cd_ekf.cd_ekf` + :func:`shipid.estimate.smoothers.rts_smoother`
(``smooth_run(compiled=False)``) instead of the compiled
:func:`shipid.methods.mmg.kernels.kinematic_filter_smoother`, the CV folds fitted by
stacking their rows (``cross_validate_horizons(moments=False)``) instead of from per-run
moments (:mod:`shipid.methods.mmg.moments`), and every simulation of the model (CV horizons,
output-error refinement, validation) by the Python reference (``compiled=False``:
:func:`shipid.methods.mmg.manoeuvres.rows_rk4`, :func:`shipid.models.mmg.simulate_batch`'s loop)
instead of the compiled copy :mod:`shipid.models.mmg_kernels`. Both paths give the same numbers
to round-off (printed: the largest differences).

Data: 32 training runs — all 41 runs less the union of both papers' test runs
(8 runs) and one random run (``random_31-Jul-2020_14_52_18``, this benchmark's choice of
the ninth held-out run; ``--runs`` takes fewer). Needs ``$SHIPID_DATA`` (or ../shared/data).

1. Step 1 of every run: compiled vs reference, process CPU time, ratio.
2. The batched CV table, ``--folds`` folds over all 12 candidates: moments vs stacked fits.
3. ``identify`` (step 1, CV, final fit) without the output-error refinement: wall and CPU time of
   the current path and of the previous one; the ratio. Then as ``shipid identify mmg --folds 4``
   runs it (``--refine auto``: with enough horizons the staged selection of
   :mod:`shipid.methods.mmg.staged`, output-error CVs included): wall and CPU time, and the ratio
   to the same identify without the refinement measured just before; then the same with the reference
   simulation (3c): wall and CPU time, ratio, largest relative estimate difference.
4. With ``--oe-reference``: the 4-fold output-error CV
   (:func:`shipid.methods.mmg.staged.cv_refinement`) of one candidate of the staged selection
   (``hull+rudder+thrust/nondimensional+prop-side+wind-gain``) and its final fit on the training runs,
   compiled and with the reference simulation: CPU time, ratio, largest relative differences.

Run: ``python benchmarks/bench_mmg_cv.py [--runs 32] [--folds 4] [--oe-reference] [--skip-cv] [--smoke]``
(``--smoke``: 3 runs, 2 folds, steps 1-3a only).
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import os
import time

NINTH_HELDOUT = "random/random_31-Jul-2020_14_52_18.csv"


def _runs(limit: int | None):
    import sys
    from pathlib import Path

    from shipid.io.basins import esso_dir

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))
    from esso_runs import SPLITS  # the papers' splits, as the study scripts list them

    d = esso_dir(None)
    test = set(SPLITS["miyauchi2022"]["test"]) | set(SPLITS["wakita2022"]["test"]) | {NINTH_HELDOUT}
    rel = sorted(f"{p.parent.name}/{p.name}" for p in d.glob("*/*.csv"))
    rel = [r for r in rel if r not in test]
    return rel[:limit] if limit else rel


@contextlib.contextmanager
def reference_simulation():
    """Every simulation of the model by the Python reference: no structure has a compiled copy, and the
    output-error refinement runs with ``compiled=False``."""
    from shipid.methods.mmg import output_error as OE, pipeline as P
    from shipid.models import mmg_kernels

    saved = mmg_kernels.supported, OE.refined_fit, P.refined_fit
    orig = saved[1]

    def refined_fit(*a, **k):
        k["compiled"] = False
        return orig(*a, **k)

    mmg_kernels.supported = lambda structure: False
    OE.refined_fit = P.refined_fit = refined_fit
    try:
        yield
    finally:
        mmg_kernels.supported, OE.refined_fit, P.refined_fit = saved


@contextlib.contextmanager
def previous_path():
    """Run the pipeline with the reference step 1, stacked fold fits and the reference simulation (the peer)."""
    from shipid.methods.mmg import cv_fast, estimator as R, pipeline as P  # noqa: F401

    saved = R.smooth_run, cv_fast.cross_validate_horizons
    R.smooth_run = functools.partial(saved[0], compiled=False)
    cv_fast.cross_validate_horizons = functools.partial(saved[1], moments=False)
    try:
        with reference_simulation():
            yield
    finally:
        R.smooth_run, cv_fast.cross_validate_horizons = saved


def _timed(fn):
    c0, w0 = time.process_time(), time.perf_counter()
    out = fn()
    return out, time.process_time() - c0, time.perf_counter() - w0




def _max_rel(a, b):
    return max(abs(a[k] - b[k]) / max(abs(b[k]), 1e-300) for k in b)


def _oe_chosen():
    from shipid.io.basins import read_esso
    from shipid.methods.mmg import estimator as R, pipeline as P, staged as SG
    from shipid.methods.mmg.candidates_asym import asym_variants
    from shipid.methods.mmg.candidates_surge import surge_variants
    from shipid.models import mmg

    trials = [read_esso(f) for f in _runs(None)]
    prior = mmg.load_published("esso_osaka_3m")
    runs = [R.smooth_run(tr) for tr in trials]
    pool = dict(R.CANDIDATES[prior.structure])
    base = "hull+rudder+thrust/nondimensional"
    pool.update(asym_variants(base, pool[base]))
    pool.update(surge_variants(base + "+prop-side", pool[base + "+prop-side"]))
    chosen = base + "+prop-side+wind-gain"

    def go():
        cv = SG.cv_refinement(trials, runs, prior, [chosen], folds=4, pool=pool)
        res = P.identify(trials, prior, structure=chosen, select=False, candidates=pool, refine="output-error")
        return cv, {k: e.value for k, e in res.estimates.items()}, res.diagnostics["output_error"]["cost_end"]

    new, c1, _ = _timed(go)
    with reference_simulation():
        ref, c0, _ = _timed(go)
    q = ("score", "psi_rms", "pos_rms", "psi_mean_of_runs", "pos_mean_of_runs")
    dcv = max(abs(new[0][k][x] / ref[0][k][x] - 1) for k in ref[0] for x in q)
    print(f"5. output-error CV of '{chosen}' (4 folds) + its final fit: compiled {c1:.1f} s, reference "
          f"{c0:.1f} s CPU, ratio {c0 / c1:.1f}x; output-error CV score "
          f"{new[0][chosen + '/output-error']['score']:.4f}; "
          f"largest relative differences: CV {dcv:.1e}, fitted coefficient {_max_rel(new[1], ref[1]):.1e}, "
          f"horizon cost {abs(new[2] / ref[2] - 1):.1e}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=None)
    ap.add_argument("--folds", type=int, default=4)
    ap.add_argument("--oe-reference", action="store_true",
                    help="The chosen candidate's output-error CV and final fit, compiled vs reference.")
    ap.add_argument("--skip-cv", action="store_true", help="Skip steps 1-3 (only step 4).")
    ap.add_argument("--smoke", action="store_true", help="3 runs, 2 folds, steps 1-3a (the test suite's smoke test).")
    a = ap.parse_args()
    if a.smoke:
        a.runs, a.folds = 3, 2

    import numpy as np

    from shipid.methods.mmg import cv_fast, estimator as R, kernels, pipeline as P  # noqa: F401  (compiles / loads the cache)
    from shipid.io.basins import read_esso
    from shipid.models import mmg

    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs")
    if not a.skip_cv:
        names = _runs(a.runs)
        trials = [read_esso(r) for r in names]
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
              f"previous path {w0:.1f} s wall ({c0:.1f} s CPU); ratio {w0 / w1:.1f}x wall, {c0 / c1:.1f}x CPU; "
                  f"chosen "
              f"'{res.model['structure_candidate']}' (previous '{res0.model['structure_candidate']}'), largest "
              f"relative estimate difference {rel:.1e}")
        if a.smoke:
            return
        rp = "auto"
        res2, c2, w2 = _timed(lambda: P.identify(trials, prior, folds=a.folds, refine=rp))
        oe = res2.diagnostics.get("output_error", {})
        print(f"3b. identify as 'shipid identify mmg --folds {a.folds}' (refine '{rp}'): {w2:.1f} s wall "
              f"({c2:.1f} s CPU), {w2 / w1:.2f}x the wall time without the refinement; horizon cost "
              f"{oe.get('cost_start', float('nan')):.4g} -> {oe.get('cost_end', float('nan')):.4g} in "
              f"{oe.get('iterations', 0)} iterations")
        with reference_simulation():
            res3, c3, w3 = _timed(lambda: P.identify(trials, prior, folds=a.folds, refine=rp))
        e2 = {k: e.value for k, e in res2.estimates.items()}
        e3 = {k: e.value for k, e in res3.estimates.items()}
        oe3 = res3.diagnostics.get("output_error", {})
        print(f"3c. the same with the reference simulation (compiled=False): {w3:.1f} s wall ({c3:.1f} s CPU); "
              f"ratio {c3 / c2:.1f}x CPU, {w3 / w2:.1f}x wall; chosen '{res2.model['structure_candidate']}' "
              f"(reference '{res3.model['structure_candidate']}'); largest relative estimate difference "
              f"{_max_rel(e2, e3):.1e}, horizon cost {abs(oe.get('cost_end', 0) / oe3.get('cost_end', 1) - 1):.1e}")
    if a.oe_reference:
        _oe_chosen()

if __name__ == "__main__":
    main()
