"""Benchmark: ``shipid identify mass-cm`` on the three one-hour files against ``pandas.read_csv`` of them.

Not a test: it prints timings, ratios and memory and asserts nothing.

The files are those of ``bench_masscm_long_cli.py`` (nominal, calibration, loaded: 3600 s at 50 Hz,
issue-3 noise, seed ``SeedSequence([17, 0])``, z_f known; ~55 MB of CSV), simulated once into a
temporary folder, or an existing folder holding ``nominal.csv``, ``calibration.csv``,
``loaded.csv`` and ``known.toml``. Every measurement runs in a fresh process limited to one thread
(:data:`ONE_CORE`), CPU time = user + sys of the child (``os.wait4``), rounds alternating the order:

* ``peer``: ``pandas.read_csv`` of the three files, the read itself (``import pandas`` not counted),
  and, as a second figure, that whole process (interpreter start, ``import pandas``, the read);
* ``command``: ``python -m shipid identify mass-cm ... -o FILE`` (everything a user waits for), with
  its peak resident set;
* ``split``: the same work in stages inside one process (imports, reading the three trials,
  Algorithm 1 with its report series, the refinement), CPU time per stage, to say where the time goes.

Printed: each, the ratios command / peer (the target, <= 5, is against the whole pandas process: a user of
the command waits for the interpreter and its imports too), the peak RSS against 300 MB, and the split.
``BENCH_BEFORE=SRC`` also times the command with another source tree (an older checkout's ``src``) in the same
rounds, so that before/after ratios come from one run.

Bytecode: every child runs as an installed package does, from compiled bytecode (``pip install`` writes it; an
editable checkout writes ``__pycache__`` on first import): ``PYTHONDONTWRITEBYTECODE`` is dropped and the
bytecode goes to a temporary ``PYTHONPYCACHEPREFIX`` (nothing is written into the source trees), filled by one
untimed warm-up run of each child. Where the environment forbids bytecode (``PYTHONDONTWRITEBYTECODE=1``) the
command would otherwise compile its own modules from source on every start (about 0.1 s of CPU) while pandas,
installed, would not. ``BENCH_NO_BYTECODE=1`` times the children with the environment as it is (no warm-up).

Usage:  python benchmarks/bench_read_masscm_cli.py [ROUNDS=3] [FOLDER or - for a new one] [DURATION_S=3600]
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

#: One core: every thread pool of the child limited to one thread.
ONE_CORE = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1",
            "SHIPID_NO_PROGRESS": "1"}
TARGET_RATIO, TARGET_MB = 5.0, 300.0
SRC = os.environ.get("BENCH_SRC") or str(Path(__file__).resolve().parents[1] / "src")  # BENCH_SRC: another tree
BEFORE = os.environ.get("BENCH_BEFORE")     # a second tree timed in the same rounds
AS_IS = os.environ.get("BENCH_NO_BYTECODE") == "1"
PYCACHE = None if AS_IS else tempfile.mkdtemp(prefix="bench_pycache_")   # bytecode as an installed package has it

PEER = """
import sys, time, resource
t0 = resource.getrusage(resource.RUSAGE_SELF)
import pandas as pd
t1 = resource.getrusage(resource.RUSAGE_SELF)
for f in sys.argv[1:]:
    pd.read_csv(f)
t2 = resource.getrusage(resource.RUSAGE_SELF)
cpu = lambda a, b: (b.ru_utime + b.ru_stime) - (a.ru_utime + a.ru_stime)
print(cpu(t1, t2))
"""

SPLIT = """
import json, sys, time, resource
def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime
out = {}
c = cpu()
from shipid.io.files import read_trial
from shipid.methods.masscm.known import read_known
from shipid.methods.masscm.estimator import MassCMOptions, REQUIRED, fit_mass_cm
from shipid.methods.masscm.refine import apply as apply_refine
from shipid.methods.masscm.series import with_series
out["imports"] = cpu() - c; c = cpu()
d = sys.argv[1]
kn = read_known(d + "/known.toml")
data = [(k, read_trial(f"{d}/{k}.csv", required=["t", *REQUIRED], method="mass-cm"))
        for k in ("nominal", "calibration", "loaded")]
out["read 3 trials"] = cpu() - c; c = cpu()
fit = fit_mass_cm(data, kn["known"], theta0=kn["theta0"], z_f=kn["z_f"], z_f_prior=kn["z_f_prior"],
                  options=MassCMOptions(), init="given" if kn["theta0"] is not None else "linear")
res = with_series(fit)
del fit
out["Algorithm 1 + series"] = cpu() - c; c = cpu()
res = apply_refine(res, data, kn["known"], kn["z_f"], "auto")
out["refinement (auto)"] = cpu() - c; c = cpu()
out["peak RSS MiB"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps(out))
"""


def child(cmd: list[str], stdout=subprocess.PIPE, src: str = SRC) -> tuple[dict, str]:
    env = dict(os.environ, PYTHONPATH=src, **ONE_CORE)
    if PYCACHE is not None:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env["PYTHONPYCACHEPREFIX"] = PYCACHE
    p = subprocess.Popen(cmd, env=env, stdout=stdout, stderr=subprocess.PIPE, text=True)
    out = p.stdout.read() if p.stdout else ""
    _, status, ru = os.wait4(p.pid, 0)
    err = p.stderr.read()
    rc = os.waitstatus_to_exitcode(status)
    if rc:
        raise SystemExit(f"{' '.join(cmd[:6])} ...: exit {rc}: {err[-400:]}")
    return {"cpu_s": ru.ru_utime + ru.ru_stime, "maxrss_mib": ru.ru_maxrss / 1024}, out


def make_files(folder: Path, duration: float = 3600.0) -> None:
    from shipid.io.files import write_trial
    from shipid.models.roll_reduced import KnownParams
    from shipid.models.roll_sim import NoiseSpec, simulate_datasets

    sys.path.insert(0, str(Path(__file__).parent))
    from bench_masscm_long_cli import KNOWN

    d = simulate_datasets("fishing-vessel", seed=np.random.SeedSequence([17, 0]), duration=duration,
                          noise=NoiseSpec.combined())
    for cond, tr in d.items():
        write_trial(tr, folder / f"{cond}.csv", force=True)
    kn = KnownParams.from_vessel("fishing-vessel")
    (folder / "known.toml").write_text(KNOWN.format(**{k: getattr(kn, k) for k in
                                                       ("U", "M", "zg_bar", "m_c", "zc_bar", "zs_bar", "g")}))


def main() -> None:
    argv = [a for a in sys.argv[1:] if a != "--smoke"]
    if len(argv) < len(sys.argv) - 1:          # --smoke: the test suite's smallest run
        argv = ["1", "-", "300"]
    rounds = int(argv[0]) if len(argv) > 0 else 3
    folder = Path(argv[1]) if len(argv) > 1 and argv[1] != "-" else \
        Path(tempfile.mkdtemp(prefix="bench_read_masscm_"))
    duration = float(argv[2]) if len(argv) > 2 else 3600.0
    if not (folder / "loaded.csv").is_file():
        make_files(folder, duration)
    files = [str(folder / f"{k}.csv") for k in ("nominal", "calibration", "loaded")]
    mb = sum(Path(f).stat().st_size for f in files) / 1e6
    print(f"shipid identify mass-cm vs pandas.read_csv, 3 files at 50 Hz ({mb:.0f} MB), one thread, "
          f"{rounds} rounds")
    cmd = [sys.executable, "-m", "shipid", "identify", "mass-cm", "--nominal", files[0], "--calibration", files[1],
           "--loaded", files[2], "--known", str(folder / "known.toml"), "-o", str(folder / "result.json"),
           "--force"]
    if PYCACHE is not None:            # untimed: writes the bytecode of every child (and warms numba's cache)
        child([sys.executable, "-c", PEER, *files])
        for src in [SRC] + ([BEFORE] if BEFORE else []):
            child(cmd, stdout=subprocess.DEVNULL, src=src)
    print("bytecode: " + ("as the environment has it (BENCH_NO_BYTECODE=1)" if AS_IS else
                          "compiled once, as installed (PYTHONPYCACHEPREFIX, one warm-up run each)"))
    peer, peer_proc, command, before = [], [], [], []
    for k in range(rounds):
        order = ["peer", "command"] + (["before"] if BEFORE else [])
        for who in (order if k % 2 == 0 else order[::-1]):
            if who == "peer":
                r, out = child([sys.executable, "-c", PEER, *files])
                peer.append(float(out.strip().splitlines()[-1]))
                peer_proc.append(r["cpu_s"])
            else:
                r, _ = child(cmd, stdout=subprocess.DEVNULL, src=SRC if who == "command" else BEFORE)
                (command if who == "command" else before).append(r)
        was = (f"; before {before[-1]['cpu_s']:.2f} s CPU, max RSS {before[-1]['maxrss_mib']:.1f} MiB"
               if before else "")
        print(f"  round {k + 1}: pandas.read_csv {peer[-1]:.3f} s CPU (its whole process {peer_proc[-1]:.2f} s); command {command[-1]['cpu_s']:.2f} s CPU, "
              f"max RSS {command[-1]['maxrss_mib']:.1f} MiB{was}; load {os.getloadavg()[0]:.1f}", flush=True)
    p = float(np.median(peer))
    pp = float(np.median(peer_proc))
    for tag, runs in (("command", command), ("before", before)):
        if not runs:
            continue
        c = float(np.median([r["cpu_s"] for r in runs]))
        rss = max(r["maxrss_mib"] for r in runs)
        print(f"{tag} / pandas.read_csv (CPU, medians): {c:.2f} / {p:.3f} s = {c / p:.1f}")
        print(f"{tag} / the whole pandas process (interpreter, import pandas, read_csv): {c:.2f} / {pp:.2f} s = "
              f"{c / pp:.1f} (target <= {TARGET_RATIO:g})")
        print(f"{tag} peak RSS {rss:.1f} MiB = {rss * 2**20 / 1e6:.1f} MB (target <= {TARGET_MB:g} MB)")
    r, out = child([sys.executable, "-c", SPLIT, str(folder)])
    split = json.loads(out.strip().splitlines()[-1])
    print("split (one process, CPU s): " + ", ".join(f"{k} {v:.2f}" for k, v in split.items()))


if __name__ == "__main__":
    try:
        main()
    finally:
        if PYCACHE is not None:
            shutil.rmtree(PYCACHE, ignore_errors=True)
