"""Benchmark (issue 17): cost of one ``identify mass-cm`` on long records, against a named peer, in the same run.

Three datasets (nominal, calibration, loaded) of ``DURATION`` s at 50 Hz each with the issue-3 noise
(white gyro / accelerometer noise, biases, 0.5 deg wave roll; :meth:`shipid.models.roll_sim.NoiseSpec.combined`),
z_f known, default options (what ``shipid identify mass-cm`` runs, noise-model cross-check included).
Each code tree is measured in a fresh process, one after the other (one core: BLAS limited to one thread):

* ``this tree``: the ``shipid`` this script imports (``PYTHONPATH``);
* ``peer``: another checkout's ``src`` (default ``/work/main/src``, the code before this change), if present.

Printed per tree: wall time of :func:`shipid.methods.masscm.estimator.estimate_mass_cm` (without ``tracemalloc``,
whose bookkeeping slows it), the peak of memory allocated during a second, identical estimate (``tracemalloc``,
numpy included), the process's peak resident set (after the simulation and after the timed estimate), the size
of the result JSON, and the estimate of m; then the ratios this/peer. ROUNDS > 1 repeats the pair in
alternating order and prints the median time ratio. Targets of issue 17 for 1 h: <= 5 s, <= 400 MB, JSON <= 2 MB.

Measured 2026-12-01 on the shared 2-core VM (load 8-9 from other jobs, so absolute times are inflated;
compare the ratio): this tree 8.48 s, allocation peak 185 MiB, JSON 0.66 MB; peer (/work/main) 17.19 s,
227 MiB, 58.85 MB; time ratio 0.49. An earlier run at lower load, before the default noise model became
"auto": 2.95 s vs 5.71 s.

Measured 2026-12-02 at load 2 against the commit before issue 17's first change (83c235a, ``/tmp/peer17/src``;
2 rounds): this tree 1.82 / 1.65 s, peer 3.59 / 3.73 s, time ratio 0.51 / 0.44 (median 0.47); memory and JSON as
below. Earlier at load 9-10 (times inflated several-fold): this tree 20.49 / 6.49 s,
peer 34.00 / 18.71 s, time ratio 0.60 / 0.35; allocation peak 185 vs 227 MiB (0.82); whole-process max RSS 479
vs 837 MiB, of which 282 vs 190 MiB before the estimate (imports and the simulation of the data); JSON 0.01 vs
58.85 MB. ``bench_masscm_long_cli.py`` measures the whole command instead.

Measured 2026-12-02 at load 7-8 against 83c235a (``/tmp/peer83/src``), with the moments formed block by block
(``moments.lag_products``) and no numba start-up on the numpy path: this tree 4.47 s, allocation peak 95.0 MiB
(185 MiB before), max RSS 313.8 MiB (251.9 before the estimate), JSON 0.01 MB; peer 6.34 s, 226.6 MiB, 837.9
MiB, 58.85 MB; ratios: time 0.71, allocation peak 0.42. ``bench_masscm_long_cli.py`` measures the whole command.

Usage:  python benchmarks/bench_masscm_long.py [DURATION_S=3600] [PEER_SRC=/work/main/src] [ROUNDS=1]
        python benchmarks/bench_masscm_long.py --smoke    (60-s records, this tree only, one round)
        python benchmarks/bench_masscm_long.py --smoke    (60 s records, this tree only, one round)
"""

import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

CHILD = r"""
import json, resource, sys, time, tracemalloc, warnings
from threadpoolctl import threadpool_limits
import numpy as np
import shipid
from shipid.models.roll_sim import NoiseSpec, simulate_datasets
from shipid.models.roll_reduced import KnownParams
try:
    from shipid.methods.masscm.estimator import estimate_mass_cm
except ImportError:                       # a peer from before the masscm package split
    from shipid.methods.masscm import estimate_mass_cm
warnings.simplefilter("ignore")
T = float(sys.argv[1])
d = simulate_datasets("fishing-vessel", seed=np.random.SeedSequence([17, 0]), duration=T, noise=NoiseSpec.combined())
known = KnownParams.from_vessel("fishing-vessel")
rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
with threadpool_limits(1):
    estimate_mass_cm(list(simulate_datasets("fishing-vessel", seed=1, duration=60.0).items()), known, z_f=-0.028)
    t0 = time.perf_counter()
    r = estimate_mass_cm(list(d.items()), known, z_f=-0.028)       # timed without tracemalloc (it slows numpy
    wall = time.perf_counter() - t0                                  # allocation-heavy code)
    rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    tracemalloc.start()
    estimate_mass_cm(list(d.items()), known, z_f=-0.028)              # the same estimate again, for its peak
    peak = tracemalloc.get_traced_memory()[1] / 2**20
    tracemalloc.stop()
t1 = time.perf_counter()
n_json = len(r.to_json(indent=None))
json_s = time.perf_counter() - t1
print(json.dumps({"src": shipid.__file__, "wall_s": wall, "alloc_peak_mib": peak, "json_mb": n_json / 1e6,
                  "json_s": json_s, "maxrss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                  "maxrss_before_mib": rss0, "maxrss_after_first_mib": rss1, "m": r.value("m"), "m_std": r.std("m"),
                  "implausible": r.diagnostics["implausible"]}))
"""


def measure(src: str, duration: float) -> dict:
    env = dict(os.environ, PYTHONPATH=src, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", CHILD, str(duration)], env=env, capture_output=True, text=True,
                         check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    here = str(Path(__file__).resolve().parents[1] / "src")
    argv = sys.argv[1:] if "--smoke" not in sys.argv else ["60", "--no-peer--", "1"]
    duration = float(argv[0]) if len(argv) > 0 else 3600.0
    peer = argv[1] if len(argv) > 1 else "/work/main/src"
    rounds = int(argv[2]) if len(argv) > 2 else 1
    trees = [("this tree", here)] + ([("peer", peer)] if Path(peer).is_dir() else [])
    print(f"identify mass-cm, 3 datasets x {duration:g} s at 50 Hz, issue-3 noise, z_f known, one core")
    print(f"{'':10s} {'wall s':>8s} {'alloc peak MiB':>15s} {'max RSS MiB':>12s} {'(before)':>9s} {'(1st)':>7s} "
          f"{'JSON MB':>8s} {'m':>9s}  load  src")
    ratios = []
    for k in range(rounds):                   # alternate the order so that a drifting load favours neither tree
        rows = {}
        for label, src in (trees if k % 2 == 0 else trees[::-1]):
            rows[label] = r = measure(src, duration)
            print(f"{label:10s} {r['wall_s']:8.2f} {r['alloc_peak_mib']:15.1f} {r['maxrss_mib']:12.1f} "
                  f"{r['maxrss_before_mib']:9.1f} {r['maxrss_after_first_mib']:7.1f} {r['json_mb']:8.2f} "
                  f"{r['m']:9.5f}  {os.getloadavg()[0]:4.1f}  {r['src']}", flush=True)
        if "peer" in rows:
            a, b = rows["this tree"], rows["peer"]
            ratios.append(a["wall_s"] / b["wall_s"])
            print(f"ratio this/peer: time {ratios[-1]:.2f}, allocation peak "
                  f"{a['alloc_peak_mib'] / b['alloc_peak_mib']:.2f}, JSON {a['json_mb'] / b['json_mb']:.3f}", flush=True)
    print("(wall: estimate_mass_cm without tracemalloc; alloc peak: memory allocated during the same estimate, run "
          "again under tracemalloc; max RSS: the whole process, (before) = after imports and the simulation of the "
          "data, (1st) = after the timed estimate)")
    if ratios:
        print(f"median time ratio this/peer over {len(ratios)} round(s): {statistics.median(ratios):.2f} (each {', '.join(f'{x:.2f}' for x in ratios)})")
    else:
        print(f"(no peer tree at {peer}: nothing to compare with)")


if __name__ == "__main__":
    main()
