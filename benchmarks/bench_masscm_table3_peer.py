"""Benchmark: the Table-3 study (Linder et al. 2015 §5, noise-free) against a named peer tree, in the same run.

Not a test: it prints timings and ratios and asserts nothing about speed.

What ``shipid study mass-cm-sensitivity --runs RUNS --workers WORKERS`` runs (z_f known, init "given", data
seed 0, campaign seed 0, the task's ``warm_up``), through :func:`shipid.campaign.engine.run_campaign`, once in
this tree and once in the peer tree (default ``/tmp/peer17/src``: a checkout of the commit before issue 17's
first change, 83c235a, made with ``git worktree add --detach /tmp/peer17 83c235a``), each in a fresh process
with ``PYTHONPATH`` set to its ``src``. Rounds alternate the order (this, peer / peer, this, ...) so that the
shared machine's drifting speed does not favour one tree; a first unmeasured round of 50 runs per tree fills
the numba on-disk caches. Printed per round: wall time of each tree, the ratio this/peer; then the median
ratio, the flagged count of each tree, and whether the per-run estimates of the nine parameters, the
iteration counts and the flags are bit-identical between the trees (the noise-free Table-3 path must not
have changed).

Measured 2026-12-02, 10 000 runs, 2 workers, against 83c235a: at load 2-4, this/peer 0.512, 0.885, 0.653 (median
0.653; this 44.3 s, peer 86.6 s median); at load 5-9 an earlier run gave 0.692, 0.787, 1.724. Both trees flag 0
of 10 000. Not bit-identical: 2279 runs differ in their iteration count and the per-run estimates by up to 3-4 x
the (tiny) spread across runs (m 2.9e-7, K_vdot 2.7e-6), the convergence tolerance's scale; the Table-3 means
agree to 7 significant digits (m 0.3997776, zm_bar -0.1820948, K_vdot 0.09987015 vs 0.09987016). The per-run
differences start at 55cd5d5 (IV moments of the IIR initial prefilter from the lag structure; 200 runs of
55cd5d5 against 83c235a already differ); 7624e4c (main just before issue 17's merge) gives the same 200-run
mean of m as 83c235a (0.399777593).

With WORKERS = 1 the runs go in the child process itself; the sum of the runs' own wall times (the engine's
per-run ``wall_s``, without the warm-up) over RUNS is the cost of one run of Algorithm 1; the runs' CPU
time (``cpu_s``) likewise, the steadier measure on a loaded machine. It is printed against
the flop floor of one run: ``FLOPS_PER_RUN`` (an estimate, about 98 Mflop for the fishing vessel's three 60-s
datasets at 50 Hz: the 50 x 50 instrument moments, the eigen-decompositions, the FIR prefilters) at the
single-thread DGEMM rate measured in the same run (512 x 512 matrices, one BLAS thread), on the same clock
(wall or CPU time) as the runs.

Usage:  python benchmarks/bench_masscm_table3_peer.py [RUNS=10000] [WORKERS=2] [ROUNDS=3] [PEER_SRC=/tmp/peer17/src]
        python benchmarks/bench_masscm_table3_peer.py 500 1 3 /tmp/old/src     (ms per run, one process)
        python benchmarks/bench_masscm_table3_peer.py --smoke    (4 runs in one process, this tree as its peer)
"""

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

NAMES = ("k", "A_x", "d", "K_r", "K_vdot", "K_delta", "z_f", "m", "zm_bar")
#: Floating-point operations of one Table-3 run (Algorithm 1 on three 60-s datasets at 50 Hz).
FLOPS_PER_RUN = 98e6

DGEMM = r"""
import json, time
import numpy as np
from threadpoolctl import threadpool_limits
a, b = np.random.default_rng(0).standard_normal((2, 512, 512))
def rate(clock):
    best = float("inf")
    for _ in range(5):
        t0 = clock()
        for _ in range(10):
            a @ b
        best = min(best, (clock() - t0) / 10)
    return 2 * 512 ** 3 / best / 1e9
with threadpool_limits(1):
    a @ b
    print(json.dumps({"wall": rate(time.perf_counter), "CPU": rate(time.process_time)}))
"""

CHILD = r"""
import importlib, json, os, sys, time, warnings
import numpy as np
import shipid
from shipid.campaign.engine import run_campaign
warnings.simplefilter("ignore")
runs, workers, out = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
try:
    importlib.import_module("shipid.methods.masscm.study")
    mod = "shipid.methods.masscm.study"
except ImportError:                       # the layout before the masscm package split
    mod = "shipid.methods.masscm_study"
names = ("k", "A_x", "d", "K_r", "K_vdot", "K_delta", "z_f", "m", "zm_bar")
t0 = time.perf_counter()
res = run_campaign(f"{mod}:run_one", runs, seed=0, kwargs={"zf_mode": "known", "data_seed": 0, "init": "given"},
                   workers=workers, progress=False, warm_up=f"{mod}:warm_up")
wall = time.perf_counter() - t0
outs = [r.outputs if r.status == "ok" else None for r in res.records]
arr = np.array([[o[n] for n in names] if o else [np.nan] * 9 for o in outs], dtype=float)
its = np.array([o["iterations"] if o else -1 for o in outs])
flag = np.array([bool(o is None or o["implausible"]) for o in outs])
np.savez(out, theta=arr, iterations=its, flagged=flag)
run_wall = float(sum(r.wall_s or 0.0 for r in res.records))
run_cpu = float(sum(r.cpu_s or 0.0 for r in res.records))
print(json.dumps({"src": shipid.__file__, "wall_s": wall, "run_wall_s": run_wall, "run_cpu_s": run_cpu, "flagged": int(flag.sum()), "runs": runs,
                  "m_mean": float(np.nanmean(arr[~flag, 7])), "load": os.getloadavg()[0]}))
"""


def measure(src: str, runs: int, workers: int, out: str) -> dict:
    env = dict(os.environ, PYTHONPATH=src, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    p = subprocess.run([sys.executable, "-c", CHILD, str(runs), str(workers), out], env=env, capture_output=True,
                       text=True)
    if p.returncode:
        raise SystemExit(f"child for {src} failed:\n{p.stderr[-3000:]}")
    return json.loads(p.stdout.strip().splitlines()[-1])


def main():
    here = str(Path(__file__).resolve().parents[1] / "src")
    smoke = "--smoke" in sys.argv
    argv = sys.argv[1:] if not smoke else ["4", "1", "1", here]
    runs = int(argv[0]) if len(argv) > 0 else 10_000
    workers = int(argv[1]) if len(argv) > 1 else 2
    rounds = int(argv[2]) if len(argv) > 2 else 3
    peer = argv[3] if len(argv) > 3 else "/tmp/peer17/src"
    if not Path(peer).is_dir():
        raise SystemExit(f"no peer tree at {peer}")
    trees = {"this": here, "peer": peer}
    tmp = tempfile.mkdtemp(prefix="bench_t3_")
    for label, src in trees.items():                     # fill the numba caches, unmeasured
        if not smoke:
            measure(src, 50, 1, os.path.join(tmp, f"warm_{label}.npz"))
    walls = {k: [] for k in trees}
    run_walls = {k: [] for k in trees}
    run_cpus = {k: [] for k in trees}
    last = {}
    print(f"Table 3 (z_f known, init given, data seed 0, seed 0): {runs} runs, {workers} workers, {rounds} rounds")
    for r in range(rounds):
        order = list(trees) if r % 2 == 0 else list(trees)[::-1]
        row = {}
        for label in order:
            row[label] = measure(trees[label], runs, workers, os.path.join(tmp, f"{label}.npz"))
            walls[label].append(row[label]["wall_s"])
            run_walls[label].append(row[label]["run_wall_s"])
            run_cpus[label].append(row[label]["run_cpu_s"])
            last[label] = row[label]
        print(f"  round {r + 1} (order {', '.join(order)}): this {row['this']['wall_s']:.1f} s, peer "
              f"{row['peer']['wall_s']:.1f} s, ratio this/peer {row['this']['wall_s'] / row['peer']['wall_s']:.3f}  "
              f"(load {row[order[0]]['load']:.2f}, {row[order[1]]['load']:.2f})", flush=True)
    ratios = np.array(walls["this"]) / np.array(walls["peer"])
    print(f"median ratio this/peer: {np.median(ratios):.3f} (each {', '.join(f'{x:.3f}' for x in ratios)}); "
          f"median wall this {np.median(walls['this']):.1f} s, peer {np.median(walls['peer']):.1f} s")
    if workers == 1:
        env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
        gfs = json.loads(subprocess.run([sys.executable, "-c", DGEMM], env=env, capture_output=True, text=True,
                                        check=True).stdout)
        for what, d in (("wall", run_walls), ("CPU", run_cpus)):
            gf = gfs[what]                                # the same clock for the runs and the DGEMM rate
            floor = FLOPS_PER_RUN / (gf * 1e9)
            per = {k: np.median(d[k]) / runs for k in trees}
            cpu_ratios = np.array(d["this"]) / np.array(d["peer"])
            print(f"one process, run {what} time: this {1e3 * per['this']:.2f} ms/run, peer {1e3 * per['peer']:.2f} "
                  f"ms/run (this/peer median {np.median(cpu_ratios):.3f}); flop floor {1e3 * floor:.2f} ms "
                  f"({FLOPS_PER_RUN / 1e6:.0f} Mflop at {gf:.1f} GFLOP/s single-thread DGEMM, measured now): "
                  f"this {per['this'] / floor:.2f} x the floor, peer {per['peer'] / floor:.2f} x")
    a, b = (np.load(os.path.join(tmp, f"{k}.npz")) for k in ("this", "peer"))
    same = {k: bool(np.array_equal(a[k], b[k], equal_nan=(k == "theta"))) for k in ("theta", "iterations", "flagged")}
    dmax = float(np.nanmax(np.abs(a["theta"] - b["theta"]))) if a["theta"].shape == b["theta"].shape else float("nan")
    print(f"flagged: this {last['this']['flagged']}, peer {last['peer']['flagged']} of {runs}; m mean this "
          f"{last['this']['m_mean']:.9f}, peer {last['peer']['m_mean']:.9f}")
    print(f"per-run bit-identical to the peer: " + ", ".join(f"{k} {v}" for k, v in same.items())
          + f"; largest per-run |difference| of the nine parameters {dmax:.3g}")
    if a["theta"].shape == b["theta"].shape and not same["theta"]:
        d = np.abs(a["theta"] - b["theta"])
        spread = np.nanstd(b["theta"][~b["flagged"]], axis=0, ddof=1)
        print("  largest per-run |this - peer| (and over the peer's spread across runs): " + ", ".join(
            f"{n} {x:.2g} ({x / s:.2g})" for n, x, s in zip(NAMES, np.nanmax(d, axis=0), spread))
              + f"; runs differing in their iteration count: {int(np.sum(a['iterations'] != b['iterations']))}")
        diffs = {n: (float(np.nanmean(a["theta"][:, k][~a["flagged"]])), float(np.nanmean(b["theta"][:, k][~b["flagged"]])))
                 for k, n in enumerate(NAMES)}
        print("  Table-3 means this / peer: " + ", ".join(f"{n} {x:.7g} / {y:.7g}" for n, (x, y) in diffs.items()))
    print(f"(this: {last['this']['src']}; peer: {last['peer']['src']})")


if __name__ == "__main__":
    main()
