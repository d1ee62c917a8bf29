"""Benchmark: the Table-3 sensitivity study (Linder et al. 2015 §5) — the issue-3/-7 speed targets.

Not a test: it prints timings and ratios, asserts nothing about speed.

1. Per run, single process, interleaved in blocks so that both see the same machine load
   (``os.getloadavg()`` printed alongside; the machine is shared):
   * ``shipid`` Algorithm 1, compiled path (:func:`shipid.methods.masscm.study.run_one`,
     ``compute="fast"``, the default: numba kernels for the FIR moments, AR fits and searches);
   * the same Algorithm 1 on the straightforward numpy/scipy path (``compute="reference"``: the
     "before" implementation, kept as the reference the tests compare against);
   * the named peer — a plain scipy implementation of the same fit without the IV machinery: the
     physical parameters fitted by ``scipy.optimize.least_squares`` to the equation error of (35) on
     the raw samples of the three datasets (no instruments, no prefilter), from the same initial values.
   Prints ms/run (wall and CPU), the ratios, and the Table-3 means/stds (fast and reference must agree
   run by run: the largest per-run difference of m is printed).
2. The study through the campaign engine (:func:`shipid.campaign.engine.run_campaign`, with the task's
   ``warm_up`` as ``shipid study mass-cm-sensitivity`` runs it): wall time of RUNS runs with 1 and 2
   local worker processes and with a 2-worker Dask ``LocalCluster``; the 1 -> 2 worker speed-up; the
   Table-3 means / stds of each; the mean CPU time per run measured inside the workers (how much two
   busy cores slow each other). With RUNS < 10 000 the 10 000-run time is extrapolated (labelled so).
   The numba kernels are compiled (or loaded from the on-disk cache) once before timing; the workers
   are forked from a forkserver that ran the warm-up once (:mod:`shipid.campaign.worker_preload`; its
   start is inside the timing of the first multi-worker campaign). ROUNDS > 1 repeats the modes in
   alternating order (1,2,dask / dask,2,1 / ...) so that a drift of the shared machine's speed (it moves
   by up to ~30 % between minutes) does not favour one mode; the speed-up is printed per round and as
   the median. Goal (issues 3 and 7): 10 000 runs in under 60 s, >= 1.8x from 1 to 2 workers on the
   2-core machine.

Usage:  python benchmarks/bench_masscm_study.py [RUNS] [PER_RUN_RUNS] [MODES] [ROUNDS]
        MODES: comma list of 1,2,dask (default all three), e.g. ``... 2000 200 2,dask``;
        PER_RUN_RUNS 0 skips part 1, RUNS 0 skips part 2; ROUNDS default 1.
        python benchmarks/bench_masscm_study.py --smoke     (4 runs, 2 per path, one worker)
"""

import os
import sys
import time
import warnings

import numpy as np
from scipy.optimize import least_squares
from threadpoolctl import threadpool_limits

from shipid.methods.masscm.estimator import MassCMOptions
from shipid.methods.masscm.study import prepared, draw_initial, run_one, summarise, warm_up
from shipid.models.roll_reduced import THETA_NAMES, discrete_coeffs, from_moment, to_moment
from shipid.campaign.engine import run_campaign

ZF = -0.028
TASK = "shipid.methods.masscm.study:run_one"
WARM_UP = "shipid.methods.masscm.study:warm_up"


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
        prep, known = prepared(0, "fishing-vessel", MassCMOptions())
        for mode in ("fast", "reference"):
            run_one(0, 1, compute=mode)                 # warm caches (datasets, kernels, first-iteration moments)
        load0 = os.getloadavg()
        res = {"fast": [], "reference": []}
        wall = {"fast": 0.0, "reference": 0.0}
        cpu = {"fast": 0.0, "reference": 0.0}
        block = max(1, min(25, n1))
        for b0 in range(0, n1, block):                  # interleaved blocks: both paths see the same load
            idx = range(b0, min(n1, b0 + block))
            for mode in ("reference", "fast"):
                t0, c0 = time.perf_counter(), time.process_time()
                res[mode] += [run_one(i, 1, compute=mode) for i in idx]
                wall[mode] += time.perf_counter() - t0
                cpu[mode] += time.process_time() - c0
        n_peer = max(1, n1 // 5)
        t0 = time.perf_counter()
        peer = [peer_run(i, 1, prep, known) for i in range(n_peer)]
        t_peer = (time.perf_counter() - t0) / n_peer
        load1 = os.getloadavg()
    pm = np.array([p[THETA_NAMES.index("m")] for p in peer])
    pz = np.array([p[THETA_NAMES.index("zm_bar")] for p in peer])
    print(f"single process, {n1} runs per path (z_f known, Table-3 initial values); "
          f"load average before {load0[0]:.2f}, after {load1[0]:.2f} (2 cores, shared machine)")
    for mode, label in (("fast", "shipid compiled (fast)"), ("reference", "shipid reference (before)")):
        s = summarise(res[mode])
        print(f"  {label:26s}: {1e3 * wall[mode] / n1:7.2f} ms/run wall ({1e3 * cpu[mode] / n1:.2f} CPU)  "
              f"m {s['parameters']['m']['mean']:.6f} ± {s['parameters']['m']['std']:.2g}  zm_bar "
              f"{s['parameters']['zm_bar']['mean']:.6f} ± {s['parameters']['zm_bar']['std']:.2g}  "
              f"flagged {s['flagged']}  mean iterations {s['mean_iterations']:.2f}")
    print(f"  {'peer scipy LS (no IV)':26s}: {1e3 * t_peer:7.2f} ms/run  ({n_peer} runs) m {np.median(pm):.5f} "
          f"(median) IQR {np.subtract(*np.percentile(pm, [75, 25])):.2g}  zm_bar {np.median(pz):.5f}")
    dm = max(abs(a["m"] - b["m"]) for a, b in zip(res["fast"], res["reference"]))
    print(f"  reference/fast CPU ratio = {cpu['reference'] / cpu['fast']:.2f}  (wall {wall['reference'] / wall['fast']:.2f});"
          f"  fast/peer time ratio = {wall['fast'] / n1 / t_peer:.2f};  largest per-run |m_fast - m_ref| = {dm:.2g}")
    print(f"  single-process estimate for 10 000 runs: {wall['fast'] / n1 * 1e4:.0f} s on 1 core "
          f"(~{wall['fast'] / n1 * 1e4 / 2:.0f} s on 2 ideal workers)", flush=True)


def campaign(runs, label, **engine):
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    res = run_campaign(TASK, runs, seed=2, progress=False, warm_up=WARM_UP, **engine)
    wall = time.perf_counter() - t0
    outs = [r.outputs if r.status == "ok" else None for r in res.records]
    s = summarise(outs, wall_s=wall)
    failed = sum(1 for r in res.records if r.status != "ok")
    cpu = 1e3 * np.mean([r.cpu_s for r in res.records if r.cpu_s is not None])
    est = "measured" if runs >= 10_000 else f"extrapolated from {runs}"
    print(f"{label:28s}: {runs} runs {wall:7.1f} s  ({1e3 * wall / runs:.2f} ms/run; worker CPU {cpu:.2f} ms/run; "
          f"10 000 runs {wall / runs * 1e4:.0f} s {est}, goal < 60 s)  flagged {s['flagged']}  failed {failed}  "
          f"load {load0:.2f} -> {os.getloadavg()[0]:.2f}", flush=True)
    return wall, s


MODES = {"1": ("local, 1 worker", {"workers": 1}), "2": ("local, 2 workers", {"workers": 2}),
         "dask": ("dask LocalCluster, 2 workers", {"executor": "dask-local", "workers": 2})}


def main():
    argv = sys.argv[1:] if "--smoke" not in sys.argv else ["4", "2", "1", "1"]
    runs = int(argv[0]) if len(argv) > 0 else 10_000
    n1 = int(argv[1]) if len(argv) > 1 else 200
    modes = [m for m in ("1", "2", "dask") if m in (argv[2].split(",") if len(argv) > 2 else MODES)]
    rounds = int(argv[3]) if len(argv) > 3 else 1
    print(f"warm-up (numba kernels compiled or loaded from cache, datasets): {warm_up():.1f} s", flush=True)
    if n1 > 0:
        per_run(n1)
    if runs <= 0:
        return
    walls = {m: [] for m in modes}
    sums = {}
    for r in range(rounds):
        order = modes if r % 2 == 0 else modes[::-1]
        if rounds > 1:
            print(f"round {r + 1} of {rounds} (order {', '.join(order)})", flush=True)
        for m in order:
            label, engine = MODES[m]
            w, sums[m] = campaign(runs, label, **engine)
            walls[m].append(w)
        if "1" in walls and "2" in walls:
            print(f"  speed-up 1 -> 2 local workers, this round: {walls['1'][-1] / walls['2'][-1]:.2f}x", flush=True)
    if "1" in walls and "2" in walls:
        ratios = np.array(walls["1"]) / np.array(walls["2"])
        print(f"speed-up 1 -> 2 local workers: median {np.median(ratios):.2f}x over {rounds} round(s) "
              f"(each {', '.join(f'{x:.2f}' for x in ratios)}; goal >= 1.8x)")
    if "2" in walls and "dask" in walls:
        print(f"dask LocalCluster / local pool (2 workers): median "
              f"{np.median(np.array(walls['dask']) / np.array(walls['2'])):.2f}")
    for m in modes:
        print(f"wall {MODES[m][0]}: " + ", ".join(f"{w:.1f}" for w in walls[m]) + " s")
    for k, s in sums.items():
        print(f"Table 3 ({k}):  " + "  ".join(
            f"{n} {s['parameters'][n]['mean']:.6g} ± {s['parameters'][n]['std']:.2g}"
            for n in ("m", "zm_bar", "k", "K_vdot", "A_x", "d")) + f"  flagged {s['flagged']}")


if __name__ == "__main__":
    main()
