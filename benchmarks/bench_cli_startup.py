"""Start-up time of the ``shipid`` command: lazy command loading against importing every command module.

``shipid.cli`` lists its commands from a generated index and imports a command's module only when
that command runs (:mod:`shipid.cli`). This script times, in fresh interpreters, each of

* ``python``               — the interpreter alone (``-c pass``), the floor no command can beat;
* ``import shipid``        — the package (its public names load on first use);
* ``shipid --help``        — the lazy path: the help of every command, nothing of the methods imported;
* ``shipid vessels``       — a shared command run through the lazy path;
* ``eager --help``         — the same help after :func:`shipid.cli.load_all_commands` (what start-up cost
  when every command module, hence every method and numba, was imported with ``shipid.cli``): the peer;

and prints the median wall time of each over ``--repeat`` runs, the ratio of each to the eager peer,
and whether numba was imported. Every timed command is run once first, untimed, so numba's on-disk
cache and the OS file cache are warm.

Usage::

    python benchmarks/bench_cli_startup.py               # 5 runs of each
    python benchmarks/bench_cli_startup.py --repeat 11
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
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
}
PROBE = "; import sys; sys.stderr.write('NUMBA=%s' % ('numba' in sys.modules))"


def _env() -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([SRC, *filter(None, [env.get("PYTHONPATH")])])
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
    args = ap.parse_args(argv)
    env = _env()
    for code in CASES.values():                     # warm numba's cache and the file cache
        run_once(code, env)
    times: dict[str, list[float]] = {k: [] for k in CASES}
    numba: dict[str, bool] = {}
    for _ in range(args.repeat):                    # interleaved, so a change in machine load hits all cases
        for name, code in CASES.items():
            dt, numba[name] = run_once(code, env)
            times[name].append(dt)
    med = {k: statistics.median(v) for k, v in times.items()}
    peer = med["eager --help"]
    print(f"shipid CLI start-up, median of {args.repeat} fresh interpreters ({sys.executable})")
    print(f"{'case':<16} {'median s':>9} {'min s':>7} {'/ eager':>8}  numba imported")
    for name in CASES:
        print(f"{name:<16} {med[name]:9.3f} {min(times[name]):7.3f} {med[name] / peer:8.3f}  {numba[name]}")
    print(f"lazy 'shipid --help' is {peer / med['shipid --help']:.1f}x faster than the eager peer; "
          f"above the bare interpreter: {med['shipid --help'] - med['python']:.3f} s lazy, "
          f"{peer - med['python']:.3f} s eager")
    return 0


if __name__ == "__main__":
    sys.exit(main())
