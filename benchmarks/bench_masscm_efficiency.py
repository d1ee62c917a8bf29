"""Benchmark (issue 3, beyond the paper): statistical efficiency of Algorithm 1 against the Cramér–Rao bound.

100 noise realisations of three 300-s datasets (gyro noise 0.002 rad/s, a_s noise 0.02 m/s^2, biases
0.001 rad/s and 0.01 m/s^2, 0.5 deg wave roll), z_f known. Prints, for zm_bar, rho and m: the CRLB
(shipid.methods.masscm.crlb), the spread and mean of the estimates, the ratio spread/bound, and
the same for the named peer "plain IV" (Algorithm 1 without the ARMA prefilters (42)–(43)).
Issue target: spread within 1.3 x the bound, means within one spread of the truth.

Usage:  python benchmarks/bench_masscm_efficiency.py [RUNS] [WORKERS] [DURATION]
        python benchmarks/bench_masscm_efficiency.py --smoke     (3 runs of 60 s, 1 worker)
"""

import sys
import time

import numpy as np

from shipid.methods.masscm.crlb import crlb
from shipid.models.roll_sim import NoiseSpec
from shipid.campaign.engine import run_campaign


def main():
    argv = sys.argv[1:] if "--smoke" not in sys.argv else ["3", "1", "60"]
    runs = int(argv[0]) if len(argv) > 0 else 100
    workers = int(argv[1]) if len(argv) > 1 else 2
    duration = float(argv[2]) if len(argv) > 2 else 300.0
    b = crlb(duration=duration, noise=NoiseSpec.combined())["bounds"]
    rows = {}
    for label, pf in (("Algorithm 1 (ARMA prefilters)", True), ("peer: plain IV (no prefilter)", False)):
        t0 = time.perf_counter()
        res = run_campaign("shipid.methods.masscm.study:efficiency_run", runs, seed=11,
                           kwargs={"duration": duration, "prefilter": pf}, workers=workers, progress=False)
        wall = time.perf_counter() - t0
        outs = [r.outputs for r in res.records if r.status == "ok" and r.outputs["converged"]]
        rows[label] = (outs, wall, runs - len(outs))
    print(f"{runs} realisations of 3 x {duration:g} s, issue-3 noise, z_f known")
    for label, (outs, wall, bad) in rows.items():
        print(f"{label}: {wall:.1f} s, {bad} not converged/failed")
        for k in ("zm_bar", "rho", "m"):
            v = np.array([o[k] for o in outs])
            v = v[np.isfinite(v)]
            sd, mu = v.std(ddof=1), v.mean()
            print(f"  {k:7s} true {b[k]['true']:.4g}  CRLB {b[k]['std']:.3g}  mean {mu:.4g}  spread {sd:.3g}  "
                  f"spread/CRLB {sd / b[k]['std']:.2f}  |mean-true|/spread {abs(mu - b[k]['true']) / sd:.2f}  "
                  f"mean reported std {np.nanmean([o[k + '_std'] for o in outs]):.3g}")


if __name__ == "__main__":
    main()
