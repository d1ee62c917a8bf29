"""Benchmark: the whole ``shipid identify mass-cm`` command on three long records, this tree against a peer tree.

Not a test: it prints timings, memory and sizes and asserts nothing.

Three datasets (nominal, calibration, loaded) of ``DURATION`` s at 50 Hz each with the issue-3 noise
(:meth:`shipid.models.roll_sim.NoiseSpec.issue3`, seed ``SeedSequence([17, 0])`` as ``bench_masscm_long.py``)
are written once as CSV files (by this tree), with the vessel's known quantities (z_f given) as TOML. Then
``python -m shipid identify mass-cm --nominal N --calibration C --loaded L --known K`` runs in a fresh process
per tree (``PYTHONPATH`` = its ``src``; BLAS limited to one thread): this tree with ``-o FILE`` (the result
JSON), the peer (default ``/tmp/peer17/src``, a checkout of 83c235a, before issue 17's first change) with
``--json``. Printed per tree and round: wall time of the process (imports, reading the CSV files, the estimate,
writing), its peak resident set (``os.wait4``), the size of what it wrote; rounds alternate the order. What a
user of the command sees, where ``bench_masscm_long.py`` isolates the estimate.

Measured 2026-12-02 at load 2 (2 rounds): this tree 7.76 / 8.80 s, max RSS 468 MiB, result JSON 1.02 MB; peer
15.58 / 16.95 s, 763 MiB; time ratio median 0.51. Of this tree's ~8 s, reading the three CSV files takes ~3-4.5 s
(a Python float() per cell in ``data.io._read_csv``), the imports ~1.5-3 s, the estimate ~1.8 s
(``bench_masscm_long.py``). Earlier at load 8-10: this tree 30.97 / 63.86 s, max RSS
468 MiB (491 MB), result JSON 1.02 MB; peer (83c235a) 33.14 / 99.27 s, max RSS 763 MiB, ``--json`` output 91.3 MB
(the issue's "0.79 GB and 92 MB" are these whole-process figures); time ratio median 0.79. Of this tree's 468
MiB: 196 MiB after the imports (numpy 25, scipy +73, numba +53, the package +45), the estimate's own allocation
peak 185 MiB (``bench_masscm_long.py``), and what reading the 55 MB of CSV leaves behind (reading alone takes the
process to 410 MiB: ``data.io._read_csv`` holds every row's cell strings at once).

With numpy's compiled reader for rows of the header's field count (``data.io._read_csv``), against the tree just
before it (2026-12-02, load 3-5, 2 rounds): 16.65 / 26.77 s vs 36.66 / 34.07 s, time ratio median 0.62; max RSS
437 MiB in both, so the peak is the estimate's, not the reading's.

Usage:  python benchmarks/bench_masscm_long_cli.py [DURATION_S=3600] [PEER_SRC=/tmp/peer17/src] [ROUNDS=2]
"""

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from shipid.data.io import write_trial
from shipid.models.roll_reduced import KnownParams
from shipid.models.roll_sim import NoiseSpec, simulate_datasets

KNOWN = """U = {U}
M = {M}
zg_bar = {zg_bar}
m_c = {m_c}
zc_bar = {zc_bar}
zs_bar = {zs_bar}
g = {g}
z_f = -0.028
"""


def run(src: str, files: dict, out: str | None, json_path: str) -> dict:
    env = dict(os.environ, PYTHONPATH=src, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    cmd = [sys.executable, "-m", "shipid", "identify", "mass-cm", "--nominal", files["nominal"],
           "--calibration", files["calibration"], "--loaded", files["loaded"], "--known", files["known"]]
    cmd += ["-o", out, "--force"] if out else ["--json"]
    t0 = time.perf_counter()
    with open(json_path, "w") as fh:
        p = subprocess.Popen(cmd, env=env, stdout=fh, stderr=subprocess.PIPE, text=True)
        _, status, ru = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    p.returncode = os.waitstatus_to_exitcode(status)
    size = Path(out).stat().st_size if out else Path(json_path).stat().st_size
    return {"wall_s": wall, "maxrss_mib": ru.ru_maxrss / 1024, "bytes": size, "rc": p.returncode,
            "stderr": p.stderr.read()[-400:]}


def main():
    duration = float(sys.argv[1]) if len(sys.argv) > 1 else 3600.0
    peer = sys.argv[2] if len(sys.argv) > 2 else "/tmp/peer17/src"
    rounds = int(sys.argv[3]) if len(sys.argv) > 3 else 2
    here = str(Path(__file__).resolve().parents[1] / "src")
    tmp = Path(tempfile.mkdtemp(prefix="bench_long_cli_"))
    d = simulate_datasets("fishing-vessel", seed=np.random.SeedSequence([17, 0]), duration=duration,
                          noise=NoiseSpec.issue3())
    files = {}
    for cond, tr in d.items():
        files[cond] = str(tmp / f"{cond}.csv")
        write_trial(tr, files[cond])
    kn = KnownParams.from_vessel("fishing-vessel")
    (tmp / "known.toml").write_text(KNOWN.format(**{k: getattr(kn, k) for k in
                                                    ("U", "M", "zg_bar", "m_c", "zc_bar", "zs_bar", "g")}))
    files["known"] = str(tmp / "known.toml")
    mb = sum(Path(files[c]).stat().st_size for c in d) / 1e6
    print(f"shipid identify mass-cm, 3 CSV files x {duration:g} s at 50 Hz ({mb:.0f} MB), issue-3 noise, z_f known, "
          f"one BLAS thread")
    trees = [("this tree", here, str(tmp / "this.json")), ("peer", peer, None)]
    if not Path(peer).is_dir():
        trees = trees[:1]
    walls = {t[0]: [] for t in trees}
    for k in range(rounds):
        for label, src, out in (trees if k % 2 == 0 else trees[::-1]):
            r = run(src, files, out, str(tmp / f"{label.replace(' ', '_')}.stdout"))
            if r["rc"]:
                print(f"  {label}: exit {r['rc']}: {r['stderr']}")
                continue
            walls[label].append(r["wall_s"])
            print(f"  {label:10s} wall {r['wall_s']:7.2f} s  max RSS {r['maxrss_mib']:7.1f} MiB  "
                  f"{'result JSON (-o)' if out else 'stdout (--json)'} {r['bytes'] / 1e6:.3f} MB  "
                  f"load {os.getloadavg()[0]:.1f}", flush=True)
    if len(walls) == 2 and walls["peer"] and walls["this tree"]:
        ratios = np.array(walls["this tree"]) / np.array(walls["peer"])
        print(f"time ratio this/peer: median {np.median(ratios):.2f} (each {', '.join(f'{x:.2f}' for x in ratios)})")


if __name__ == "__main__":
    main()
