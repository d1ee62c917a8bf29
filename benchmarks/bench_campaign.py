"""Campaign engine wall time: 1 local worker vs 2 local workers vs a 2-worker Dask LocalCluster.

Issue 7 asks for the 10 000-run Table-3 study (seed 000, Linder et al. 2015, §5) timed
with 1 and 2 local workers and with a 2-worker LocalCluster, goal <= 60 s and >= 1.8x
from 1 to 2 workers on a 2-core machine. The per-run function of that study is looked
up in :mod:`shipid.methods.masscm.estimator` (``--task`` names another); when none exists the
benchmark falls back to the toy task (:func:`shipid.campaign.toy.toy_run`) and says so.

The three executions must give identical outputs (checked here, bit for bit); the
script prints wall times and the ratios against the 1-worker run, which is the peer
measured in the same process run.

Usage::

    .venv/bin/python benchmarks/bench_campaign.py                 # Table-3 task if present, 10 000 runs
    .venv/bin/python benchmarks/bench_campaign.py --runs 200 --skip-dask   # a quick, extrapolated look
    .venv/bin/python benchmarks/bench_campaign.py --runs 2000 --task shipid.campaign.toy:toy_run \\
        --kwargs '{"n": 20000}'
    .venv/bin/python benchmarks/bench_campaign.py --store        # also time the 2-worker run into a store
    .venv/bin/python benchmarks/bench_campaign.py --smoke        # 4 runs, no Dask (the test suite's smoke test)
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import sys
import tempfile
import time

from shipid.campaign.engine import available_cpus, run_campaign

# where the Table-3 per-run function may live (first found wins), with the kwargs of
# `shipid study mass-cm-sensitivity` defaults (z_f known, initial values as drawn, data seed 0)
TABLE3_CANDIDATES = (("shipid.methods.masscm.study", "run_one"),
                     ("shipid.methods.masscm.estimator", "table3_run"), ("shipid.methods.masscm.estimator", "sensitivity_run"))
TABLE3_KWARGS = {"zf_mode": "known", "data_seed": 0, "init": "given"}
TOY = "shipid.campaign.toy:toy_run"


def find_table3_task() -> str | None:
    for mod_name, fn in TABLE3_CANDIDATES:
        try:
            mod = importlib.import_module(mod_name)
        except Exception:  # noqa: BLE001 - absent or broken: try the next, else the toy
            continue
        if callable(getattr(mod, fn, None)):
            return f"{mod_name}:{fn}"
    return None


def timed(label: str, **kw):
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    res = run_campaign(progress=False, **kw)
    wall = time.perf_counter() - t0
    run_cpu = sum(r.cpu_s or 0.0 for r in res.records)   # CPU time spent inside the runs, all workers
    print(f"  {label:<42s} {wall:8.2f} s wall  {run_cpu:8.2f} s run CPU ({100 * run_cpu / (wall * res.workers):3.0f} % "
          f"of {res.workers} worker{'s' if res.workers != 1 else ''})  load {load0:4.1f}->{os.getloadavg()[0]:4.1f}"
          f"  [{res.n_ok} ok, {res.n_failed} failed, {res.executor}]", flush=True)
    if res.mixed_code:
        print(f"  WARNING: {res.mixed_code} runs came from workers started on other shipid source "
              "(files edited during the benchmark): outputs may legitimately differ", flush=True)
    return wall, res


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=10_000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--task", default=None, help="module:function (default: the Table-3 task, else the toy)")
    ap.add_argument("--kwargs", default=None, help="JSON of fixed keyword arguments for the task "
                    "(default: the Table-3 study's defaults, or none for the toy)")
    ap.add_argument("--store", action="store_true", help="also time the 2-worker run writing a store")
    ap.add_argument("--skip-dask", action="store_true")
    ap.add_argument("--smoke", action="store_true", help="4 runs, no Dask (the test suite's smoke test)")
    args = ap.parse_args(argv)
    if args.smoke:
        args.runs, args.skip_dask = 4, True

    task = args.task or find_table3_task()
    note = ""
    if task is None:
        task = TOY
        note = ("NOTE: no Table-3 per-run function found (looked for "
                f"{', '.join(m + ':' + f for m, f in TABLE3_CANDIDATES)}); timing the toy task instead")
    kwargs = json.loads(args.kwargs) if args.kwargs is not None else (TABLE3_KWARGS if task != TOY else {})
    print(f"campaign benchmark: task {task}, {args.runs} runs, seed {args.seed}, kwargs {kwargs}")
    print(f"machine: {available_cpus()} CPUs available to this process, python {sys.version.split()[0]}, "
          f"load average {os.getloadavg()[0]:.1f} (wall-time ratios mean little when it exceeds the CPUs)")
    if note:
        print(note)
    common = dict(task=task, n_runs=args.runs, seed=args.seed, kwargs=kwargs)

    t1, r1 = timed("1 local worker (in-process)", workers=1, **common)
    t2, r2 = timed("2 local workers (process pool)", workers=2, **common)
    rows = {"local_1": t1, "local_2": t2}
    same = {"local_2": r2.outputs == r1.outputs}
    if args.store:
        with tempfile.TemporaryDirectory() as tmp:
            ts, rs = timed("2 local workers + SQLite store", workers=2, store=os.path.join(tmp, "b.sqlite"),
                           **common)
        rows["local_2_store"] = ts
        same["local_2_store"] = rs.outputs == r1.outputs
    if not args.skip_dask:
        td, rd = timed("2-worker Dask LocalCluster (incl. start)", executor="dask-local", workers=2, **common)
        rows["dask_local_2"] = td
        same["dask_local_2"] = rd.outputs == r1.outputs

    print("ratios (1-worker wall time / this wall time; > 1 is faster):")
    for k, v in rows.items():
        if k != "local_1":
            print(f"  {k:<16s} x{t1 / v:5.2f}   identical outputs to 1 worker: {same[k]}")
    print(f"per run (1 worker): {1e3 * t1 / max(1, args.runs):.3f} ms wall, "
          f"{1e3 * sum(r.cpu_s or 0.0 for r in r1.records) / max(1, args.runs):.3f} ms CPU")
    if args.runs != 10_000:
        print(f"extrapolated to 10 000 runs (linear in runs): 1 worker {t1 * 1e4 / args.runs:.0f} s, "
              + ", ".join(f"{k} {v * 1e4 / args.runs:.0f} s" for k, v in rows.items() if k != "local_1"))
    goal = ("goal (issue 7): 10 000 runs <= 60 s and >= 1.8x from 1 to 2 workers: "
            f"{'met' if (min(t2, rows.get('dask_local_2', t2)) <= 60 and t1 / t2 >= 1.8) else 'NOT met'}"
            f" (2 workers {t2:.1f} s, x{t1 / t2:.2f})")
    if args.runs == 10_000 and task != TOY:
        print(goal)
    print(json.dumps({"task": task, "runs": args.runs, "wall_s": rows,
                      "speedup_vs_1": {k: t1 / v for k, v in rows.items()}, "identical": same}))
    return 0 if all(same.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
