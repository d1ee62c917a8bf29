"""Benchmark: the Table-3 sensitivity study (Linder et al. 2015 §5) — the issue-3/-7 speed targets.

Not a test: it prints timings and ratios, asserts nothing about speed.

1. Per run, single process: ``shipid`` Algorithm 1 (:func:`shipid.methods.masscm_study.run_one`,
   z_f known, Table-3 initial values) against the named peer — a plain scipy implementation of the
   same fit without the IV machinery: the physical parameters fitted by ``scipy.optimize.least_squares``
   to the equation error of (35) on the raw samples of the three datasets (no instruments, no
   prefilter), from the same initial values, on the same datasets. Prints ms/run, the ratio and the
   accuracy of m and zm_bar of both.
2. The full study through the campaign engine (:func:`shipid.studies.engine.run_campaign`): wall time
   of RUNS runs (default 10 000, as ``shipid study mass-cm-sensitivity --runs 10000``) with 1 and 2
   local worker processes and with a 2-worker Dask ``LocalCluster``; the 1 -> 2 worker speed-up; the
   Table-3 means / stds of each (they must agree: run i depends on (seed, i) only). Goal (issues 3
   and 7): 10 000 runs in under 60 s, >= 1.8x from 1 to 2 workers on the 2-core machine.

Usage:  python benchmarks/bench_masscm_study.py [RUNS] [PEER_RUNS] [MODES]
        MODES: comma list of 1,2,dask (default all three), e.g. ``... 2000 30 2,dask``.
"""

import sys
import time
import warnings

import numpy as np
from scipy.optimize import least_squares
from threadpoolctl import threadpool_limits

from shipid.methods.masscm import MassCMOptions
from shipid.methods.masscm_study import _prepared, draw_initial, run_one, summarise
from shipid.models.roll_reduced import THETA_NAMES, discrete_coeffs, from_moment, to_moment
from shipid.studies.engine import run_campaign

ZF = -0.028
TASK = "shipid.methods.masscm_study:run_one"


def peer_run(i, seed, prep, known):
    """Plain nonlinear least squares of the equation error (no IV), z_f known, same initial values."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, i]))
    th0 = draw_initial(rng)
    th0[6] = ZF
    th0 = to_moment(th0)
    free = np.ones(9, bool); free[6] = False
    conds = [d.condition for d in prep]
    Ts = np.array([d.T for d in prep])

    def res(x):
        th = th0.copy(); th[free] = x
        G = discrete_coeffs(th, known, conds, Ts, moment=True)
        return np.concatenate([d.y[20:] - d.Phi[20:] @ G[k] for k, d in enumerate(prep)])
    s = least_squares(res, th0[free], method="trf", x_scale="jac")
    th = th0.copy(); th[free] = s.x
    return from_moment(th)


def per_run(n1):
    warnings.simplefilter("ignore")
    with threadpool_limits(1):
        prep, known = _prepared(0, "fishing-vessel", MassCMOptions())
        run_one(0, 1)                                   # warm caches (datasets, first-iteration moments)
        t0, c0 = time.perf_counter(), time.process_time()
        ours = [run_one(i, 1) for i in range(n1)]
        t_ours, c_ours = (time.perf_counter() - t0) / n1, (time.process_time() - c0) / n1
        t0 = time.perf_counter()
        peer = [peer_run(i, 1, prep, known) for i in range(n1)]
        t_peer = (time.perf_counter() - t0) / n1
    s = summarise(ours)
    pm = np.array([p[THETA_NAMES.index("m")] for p in peer])
    pz = np.array([p[THETA_NAMES.index("zm_bar")] for p in peer])
    print(f"single process, {n1} runs each (z_f known, Table-3 initial values):")
    print(f"  shipid Algorithm 1 : {1e3 * t_ours:8.1f} ms/run wall ({1e3 * c_ours:.1f} CPU)  "
          f"m {s['parameters']['m']['mean']:.6f} ± {s['parameters']['m']['std']:.2g}  zm_bar "
          f"{s['parameters']['zm_bar']['mean']:.6f} ± {s['parameters']['zm_bar']['std']:.2g}  "
          f"flagged {s['flagged']}  mean iterations {s['mean_iterations']:.2f}")
    print(f"  peer scipy LS      : {1e3 * t_peer:8.1f} ms/run  m {np.median(pm):.5f} (median) "
          f"IQR {np.subtract(*np.percentile(pm, [75, 25])):.2g}  zm_bar {np.median(pz):.5f}")
    print(f"  time ratio shipid/peer = {t_ours / t_peer:.2f}", flush=True)


def campaign(runs, label, **engine):
    t0 = time.perf_counter()
    res = run_campaign(TASK, runs, seed=2, progress=False, **engine)
    wall = time.perf_counter() - t0
    outs = [r.outputs if r.status == "ok" else None for r in res.records]
    s = summarise(outs, wall_s=wall)
    failed = sum(1 for r in res.records if r.status != "ok")
    print(f"{label:28s}: {runs} runs {wall:7.1f} s  ({1e3 * wall / runs:.1f} ms/run; "
          f"10 000 runs ~ {wall / runs * 1e4:.0f} s, goal < 60 s)  flagged {s['flagged']}  failed {failed}",
          flush=True)
    return wall, s


def main():
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 10_000
    n1 = int(sys.argv[2]) if len(sys.argv) > 2 else 50
    modes = sys.argv[3].split(",") if len(sys.argv) > 3 else ["1", "2", "dask"]
    if n1 > 0:
        per_run(n1)
    walls, sums = {}, {}
    if "1" in modes:
        walls["1"], sums["1"] = campaign(runs, "local, 1 worker", workers=1)
    if "2" in modes:
        walls["2"], sums["2"] = campaign(runs, "local, 2 workers", workers=2)
    if "dask" in modes:
        walls["dask"], sums["dask"] = campaign(runs, "dask LocalCluster, 2 workers", executor="dask-local",
                                               workers=2)
    if "1" in walls and "2" in walls:
        print(f"speed-up 1 -> 2 local workers: {walls['1'] / walls['2']:.2f}x (goal >= 1.8x)")
    if "2" in walls and "dask" in walls:
        print(f"dask LocalCluster / local pool (2 workers): {walls['dask'] / walls['2']:.2f}")
    for k, s in sums.items():
        print(f"Table 3 ({k}):  " + "  ".join(
            f"{n} {s['parameters'][n]['mean']:.6g} ± {s['parameters'][n]['std']:.2g}"
            for n in ("m", "zm_bar", "k", "K_vdot", "A_x", "d")) + f"  flagged {s['flagged']}")


if __name__ == "__main__":
    main()
