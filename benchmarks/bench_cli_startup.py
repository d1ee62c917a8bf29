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
* ``shipid validate ESSO`` — ``shipid validate published:esso_osaka_3m --trial RUN`` on one Esso Osaka zig-zag
  of the shared data (the MMG simulation, compiled; left out when the data are not found);

and prints, over ``--repeat`` runs, the median CPU time (user + system of the child, ``os.wait4``: the machine
is shared, so wall time is noise) and wall time of each, the ratio of each CPU median to the eager peer and to
``import numpy, scipy, pandas``, and whether numba was imported. The command-line cases end as the console
script does (:func:`shipid.cli.exit_now`). Every timed command is run
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

#: How a command-line case ends: as the console script does (an older tree without ``exit_now``: ``sys.exit``).
EXIT = "; import shipid.cli as _c, sys as _s; getattr(_c, 'exit_now', _s.exit)(rc)"

CASES = {
    "python": "pass",
    "import shipid": "import shipid",
    "shipid --help": "from shipid.cli import main; main(['--help'])",
    "shipid vessels": "from shipid.cli import main; rc = main(['vessels']){probe}" + EXIT,
    "eager --help": "import shipid.cli as c; c.load_all_commands(); c.main(['--help'])",
    "numpy+scipy+pandas": "import numpy, scipy, pandas",
    "shipid.identify": "import shipid; shipid.identify",
    "identify mass-cm": "import shipid; shipid.identify; from shipid import registry; registry.get('mass-cm').identify",
    "shipid check FILE": "from shipid.cli import main; rc = main(['check', {file!r}]){probe}" + EXIT,
    "shipid validate ESSO": "from shipid.cli import main; rc = main(['validate', 'published:esso_osaka_3m', "
                            "'--trial', {esso!r}]){probe}" + EXIT,
}
#: The Esso Osaka run of the validate case (shared data, ``shipid.io.paths.data_root``).
ESSO_RUN = ("esso_osaka_3m", "data", "zigzag", "zigzag_31-Jul-2020_13_04_24.csv")
TRIAL = "t [s],u [m/s],r [rad/s],delta [rad]\n" + "".join(
    f"{0.1 * i:.1f},1,{0.001 * i:.3f},{0.01 * (i % 7):.2f}\n" for i in range(200))
PROBE = "; import sys; sys.stderr.write('NUMBA=%s' % ('numba' in sys.modules))"


def _env(src: str = SRC) -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([src, *filter(None, [env.get("PYTHONPATH")])])
    return env


def run_once(code: str, env: dict) -> tuple[float, float, bool]:
    """CPU time (user + system) and wall time of one fresh interpreter running ``code``, and whether it
    imported numba."""
    code = code.replace("{probe}", PROBE) if "{probe}" in code else code + PROBE
    t0 = time.perf_counter()
    p = subprocess.Popen([sys.executable, "-c", code], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                         text=True)
    err = p.stderr.read()
    _, status, ru = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    if os.waitstatus_to_exitcode(status):
        raise SystemExit(f"exit {os.waitstatus_to_exitcode(status)}: {code}\n{err[-2000:]}")
    return ru.ru_utime + ru.ru_stime, wall, "NUMBA=True" in err


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
    from shipid.io.paths import data_root

    esso = data_root()
    esso = esso.joinpath(*ESSO_RUN) if esso is not None else None
    cases = {k: v.format(file=str(trial), esso=str(esso), probe="{probe}") for k, v in CASES.items()
             if "{esso" not in v or (esso is not None and esso.is_file())}
    trees = {"": _env()}
    if args.compare:
        trees["before "] = _env(args.compare)
    if not args.smoke:
        for env in trees.values():
            for code in cases.values():             # warm numba's cache and the file cache
                run_once(code, env)
    times: dict[str, list[float]] = {t + k: [] for t in trees for k in cases}
    walls: dict[str, list[float]] = {t + k: [] for t in trees for k in cases}
    numba: dict[str, bool] = {}
    for _ in range(repeat):                         # interleaved, so a change in machine load hits all cases
        for tag, env in trees.items():
            for name, code in cases.items():
                cpu, wall, numba[tag + name] = run_once(code, env)
                times[tag + name].append(cpu)
                walls[tag + name].append(wall)
    tmp.cleanup()
    med = {k: statistics.median(v) for k, v in times.items()}
    print(f"shipid start-up, median of {repeat} fresh interpreters ({sys.executable}); CPU = user + system of "
          f"the child; load {os.getloadavg()[0]:.1f}")
    print(f"{'case':<28} {'CPU s':>7} {'wall s':>7} {'/ eager':>8} {'/ np+sp+pd':>10}  numba imported")
    for tag in trees:
        peer, base = med[tag + "eager --help"], med[tag + "numpy+scipy+pandas"]
        for name in cases:
            k = tag + name
            print(f"{k:<28} {med[k]:7.3f} {statistics.median(walls[k]):7.3f} {med[k] / peer:8.3f} "
                  f"{med[k] / base:10.3f}  {numba[k]}")
    for tag in trees:
        peer, base = med[tag + "eager --help"], med[tag + "numpy+scipy+pandas"]
        print(f"{tag or 'this tree: '}lazy 'shipid --help' is {peer / med[tag + 'shipid --help']:.1f}x faster than "
              f"the eager peer; 'import shipid; shipid.identify' = {med[tag + 'shipid.identify'] / base:.2f} x "
              f"'import numpy, scipy, pandas' (target <= 1.5); 'shipid check FILE' = "
              f"{med[tag + 'shipid check FILE'] / base:.2f} x (target <= 2)"
              + (f"; 'shipid validate ESSO' = {med[tag + 'shipid validate ESSO'] / base:.2f} x (target <= 2)"
                 if tag + "shipid validate ESSO" in med else "; validate: the shared data not found") + " (CPU)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
