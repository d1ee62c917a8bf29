"""Benchmark: the Table-3 sensitivity study (Linder et al. 2015 §5) — time per run and extrapolated 10 000 runs.

Peer: a plain scipy implementation of the same fit without the IV machinery — the physical
parameters fitted by ``scipy.optimize.least_squares`` to the equation error of (35) on the raw
samples of the three datasets (least squares, no instruments, no prefilter), from the same Table-3
initial values. Both run in this process, one run after the other, on the same datasets; the
script prints time per run, the ratio, and the accuracy of m and zm_bar of both.

Usage:  python benchmarks/bench_masscm_study.py [RUNS] [WORKERS]
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


def main():
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 100
    workers = int(sys.argv[2]) if len(sys.argv) > 2 else 2
    warnings.simplefilter("ignore")
    with threadpool_limits(1):
        prep, known = _prepared(0, "fishing-vessel", MassCMOptions())
        n1 = min(runs, 50)
        t0 = time.perf_counter()
        ours = [run_one(i, 1) for i in range(n1)]
        t_ours = (time.perf_counter() - t0) / n1
        t0 = time.perf_counter()
        peer = [peer_run(i, 1, prep, known) for i in range(n1)]
        t_peer = (time.perf_counter() - t0) / n1
    s = summarise(ours)
    pm = np.array([p[THETA_NAMES.index("m")] for p in peer])
    pz = np.array([p[THETA_NAMES.index("zm_bar")] for p in peer])
    print(f"single process, {n1} runs each (z_f known, Table-3 initial values):")
    print(f"  shipid Algorithm 1 : {1e3 * t_ours:8.1f} ms/run  m {s['parameters']['m']['mean']:.5f} "
          f"± {s['parameters']['m']['std']:.2g}  zm_bar {s['parameters']['zm_bar']['mean']:.5f} "
          f"± {s['parameters']['zm_bar']['std']:.2g}  flagged {s['flagged']}")
    print(f"  peer scipy LS      : {1e3 * t_peer:8.1f} ms/run  m {np.median(pm):.5f} (median) "
          f"IQR {np.subtract(*np.percentile(pm, [75, 25])):.2g}  zm_bar {np.median(pz):.5f}")
    print(f"  time ratio shipid/peer = {t_ours / t_peer:.2f}")
    t0 = time.perf_counter()
    res = run_campaign("shipid.methods.masscm_study:run_one", runs, seed=2, workers=workers, progress=False)
    wall = time.perf_counter() - t0
    outs = [r.outputs if r.status == "ok" else None for r in res.records]
    s2 = summarise(outs, wall_s=wall)
    print(f"campaign engine, {runs} runs on {res.workers} workers: {wall:.1f} s "
          f"-> 10 000 runs ~ {wall / runs * 1e4:.0f} s (goal < 60 s); flagged {s2['flagged']}")
    for n in ("m", "zm_bar", "k", "K_vdot"):
        p = s2["parameters"][n]
        print(f"  {n:7s} true {p['true']:.5g} mean {p['mean']:.6g} std {p['std']:.2g} "
              f"(paper {p['paper_mean']:.5g} ± {p['paper_std']:.2g})")


if __name__ == "__main__":
    main()
