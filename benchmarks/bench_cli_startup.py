"""Start-up time of the ``shipid`` command: lazy command loading against importing every command module.

``shipid.cli`` lists its commands from a generated index and imports a command's module only when
that command runs (:mod:`shipid.cli`). This script times, in fresh interpreters, each of

* ``python``               — the interpreter alone (``-c pass``), the floor no command can beat;
* ``import shipid``        — the package (its public names load on first use);
* ``shipid --help``        — the lazy path: the help of every command, nothing of the methods imported;
* ``shipid vessels``       — a shared command run through the lazy path;
* ``eager --help``         — the same help after :func:`shipid.cli.load_all_commands` (what start-up cost
  when every command module, hence every method and numba, was imported with ``shipid.cli``): the peer;
* ``numpy+scipy+pandas``   — ``import numpy, scipy, pandas``: the peer of the library's start-up;
* ``shipid.identify``      — ``import shipid; shipid.identify`` (the API, no method loaded yet);
* ``identify mass-cm``     — the same and ``registry.get("mass-cm").identify``: one method loaded;
* ``shipid check FILE``    — read and validate one small CSV trial (written to a temporary folder);

and prints the median wall time of each over ``--repeat`` runs, the ratio of each to the eager peer
and to ``import numpy, scipy, pandas``, and whether numba was imported. Every timed command is run
once first, untimed, so numba's on-disk cache and the OS file cache are warm. ``--compare SRC``
times the same cases with another source tree first on the path (an older checkout's ``src``), in
the same interleaved rounds, so that before/after ratios come from one run.

Usage::

    python benchmarks/bench_cli_startup.py               # 5 runs of each
    python benchmarks/bench_cli_startup.py --repeat 11
    python benchmarks/bench_cli_startup.py --compare /tmp/old/src
    python benchmarks/bench_cli_startup.py --smoke       # one run of each (the test suite's smoke test)
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import shipid

SRC = str(Path(shipid.__file__).resolve().parents[1])

CASES = {
    "python": "pass",
    "import shipid": "import shipid",
    "shipid --help": "from shipid.cli import main; main(['--help'])",
    "shipid vessels": "from shipid.cli import main; main(['vessels'])",
    "eager --help": "import shipid.cli as c; c.load_all_commands(); c.main(['--help'])",
    "numpy+scipy+pandas": "import numpy, scipy, pandas",
    "shipid.identify": "import shipid; shipid.identify",
    "identify mass-cm": "import shipid; shipid.identify; from shipid import registry; registry.get('mass-cm').identify",
    "shipid check FILE": "from shipid.cli import main; main(['check', {file!r}])",
}
TRIAL = "t [s],u [m/s],r [rad/s],delta [rad]\n" + "".join(
    f"{0.1 * i:.1f},1,{0.001 * i:.3f},{0.01 * (i % 7):.2f}\n" for i in range(200))
PROBE = "; import sys; sys.stderr.write('NUMBA=%s' % ('numba' in sys.modules))"


def _env(src: str = SRC) -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([src, *filter(None, [env.get("PYTHONPATH")])])
    return env


def run_once(code: str, env: dict) -> tuple[float, bool]:
    """Wall time of one fresh interpreter running ``code``, and whether it imported numba."""
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-c", code + PROBE], env=env, stdout=subprocess.DEVNULL,
                       stderr=subprocess.PIPE, text=True, check=True)
    return time.perf_counter() - t0, "NUMBA=True" in p.stderr


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=5, help="timed runs of each case (median reported)")
    ap.add_argument("--compare", metavar="SRC", help="another source tree timed in the same rounds (before)")
    ap.add_argument("--smoke", action="store_true", help="one untimed-warm-up-free run of each case")
    args = ap.parse_args(argv)
    repeat = 1 if args.smoke else args.repeat
    tmp = tempfile.TemporaryDirectory()
    trial = Path(tmp.name, "trial.csv")
    trial.write_text(TRIAL, encoding="utf-8")
    cases = {k: v.format(file=str(trial)) for k, v in CASES.items()}
    trees = {"": _env()}
    if args.compare:
        trees["before "] = _env(args.compare)
    if not args.smoke:
        for env in trees.values():
            for code in cases.values():             # warm numba's cache and the file cache
                run_once(code, env)
    times: dict[str, list[float]] = {t + k: [] for t in trees for k in cases}
    numba: dict[str, bool] = {}
    for _ in range(repeat):                         # interleaved, so a change in machine load hits all cases
        for tag, env in trees.items():
            for name, code in cases.items():
                dt, numba[tag + name] = run_once(code, env)
                times[tag + name].append(dt)
    tmp.cleanup()
    med = {k: statistics.median(v) for k, v in times.items()}
    print(f"shipid start-up, median of {repeat} fresh interpreters ({sys.executable})")
    print(f"{'case':<26} {'median s':>9} {'min s':>7} {'/ eager':>8} {'/ np+sp+pd':>10}  numba imported")
    for tag in trees:
        peer, base = med[tag + "eager --help"], med[tag + "numpy+scipy+pandas"]
        for name in cases:
            k = tag + name
            print(f"{k:<26} {med[k]:9.3f} {min(times[k]):7.3f} {med[k] / peer:8.3f} {med[k] / base:10.3f}  "
                  f"{numba[k]}")
    for tag in trees:
        peer, base = med[tag + "eager --help"], med[tag + "numpy+scipy+pandas"]
        print(f"{tag or 'this tree: '}lazy 'shipid --help' is {peer / med[tag + 'shipid --help']:.1f}x faster than "
              f"the eager peer; 'import shipid; shipid.identify' = {med[tag + 'shipid.identify'] / base:.2f} x "
              f"'import numpy, scipy, pandas' (target <= 1.5); 'shipid check FILE' = "
              f"{med[tag + 'shipid check FILE'] / base:.2f} x (target <= 2)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
