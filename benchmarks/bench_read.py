"""Benchmark: :func:`shipid.io.read_trial` of a CSV trial against ``pandas.read_csv`` of the same file.

Not a test: it prints timings and ratios and asserts nothing.

The files are the three one-hour, 50-Hz records of ``bench_masscm_long_cli.py`` (nominal,
calibration, loaded: issue-3 noise, seed ``SeedSequence([17, 0])``, written by
:func:`shipid.io.write_trial`, ``name [unit]`` headers, ~18 MB each), simulated once into a
temporary folder, or the CSV files given on the command line. Per round and file, in one
process and alternating the order: ``read_trial(path)`` (parse, convert to SI, validate) and
``pandas.read_csv(path)`` (the C engine, float64 columns, nothing checked), each timed in CPU
seconds of this process (both read on one thread). Printed: the median time of each over the rounds, their ratio (target <= 1.5), the sum over the files,
and the peak resident set of this process.

Usage:  python benchmarks/bench_read.py [ROUNDS=5] [DURATION_S=3600] [FILE.csv ...]
"""

from __future__ import annotations

import os
import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from shipid.io.files import read_trial, write_trial

#: The issue's target: read_trial at most this many times pandas.read_csv of the same file.
TARGET = 1.5


def make_files(duration: float) -> list[Path]:
    from shipid.models.roll_sim import NoiseSpec, simulate_datasets

    tmp = Path(tempfile.mkdtemp(prefix="bench_read_"))
    d = simulate_datasets("fishing-vessel", seed=np.random.SeedSequence([17, 0]), duration=duration,
                          noise=NoiseSpec.combined())
    out = []
    for cond, tr in d.items():
        out.append(tmp / f"{cond}.csv")
        write_trial(tr, out[-1])
    return out


def timed(f) -> float:
    """CPU seconds of ``f()`` (both readers run on one thread here; wall time on a shared machine is noise)."""
    t0 = time.process_time()
    f()
    return time.process_time() - t0


def main() -> None:
    args = [a for a in sys.argv[1:] if a != "--smoke"]
    if len(args) < len(sys.argv) - 1:          # --smoke: the test suite's smallest run
        args = ["1", "60"]
    rounds = int(args[0]) if len(args) > 0 else 5
    duration = float(args[1]) if len(args) > 1 else 3600.0
    files = [Path(a) for a in args[2:]] or make_files(duration)
    read_trial(files[0])
    pd.read_csv(files[0])        # warm: imports, the pint registry, the page cache
    mb = sum(f.stat().st_size for f in files) / 1e6
    print(f"read_trial vs pandas.read_csv, {len(files)} CSV files ({mb:.1f} MB), {rounds} rounds, medians")
    tot_s = tot_p = 0.0
    for f in files:
        ts, tp = [], []
        for k in range(rounds):
            pair = [("s", lambda: read_trial(f)), ("p", lambda: pd.read_csv(f))]
            for who, fn in (pair if k % 2 == 0 else pair[::-1]):
                (ts if who == "s" else tp).append(timed(fn))
        s, p = float(np.median(ts)), float(np.median(tp))
        tot_s += s
        tot_p += p
        print(f"  {f.name:24s} read_trial {s:7.3f} s   pandas.read_csv {p:7.3f} s   ratio {s / p:5.2f}")
    print(f"  {'all files':24s} read_trial {tot_s:7.3f} s   pandas.read_csv {tot_p:7.3f} s   ratio "
          f"{tot_s / tot_p:5.2f}  (target <= {TARGET:g})")
    print(f"load {os.getloadavg()[0]:.1f}; peak RSS of this process {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MiB")


if __name__ == "__main__":
    main()
