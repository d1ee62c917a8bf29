"""Esso Osaka 3 m, 9 held-out runs: the product path (``identify mmg`` defaults, then ``validate``).

The split: the test runs are both papers' test runs (Miyauchi et al. 2022, Wakita et al. 2022; 8 runs)
plus one random run, ``random_03-Aug-2020_11_04_37``; the other 32 runs of the data set train. The model
is what ``shipid identify mmg --trial ... --format esso --folds 4`` gives on the 32 training runs
(``shipid.identify("mmg", ..., fmt="esso", folds=4)``, the same function); each test run is then
predicted by ``shipid validate MODEL.json --trial RUN`` (``shipid.validate``), and by the published set
(``published:esso_osaka_3m``) as a reference: mean over the 9 runs of the RMS heading and position errors
over 60-s horizons restarted every 60 s. Uses the public API only.

    SHIPID_DATA=/path/to/data python studies/esso_heldout9/run.py [--train-only] [--model MODEL.json]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import shipid

TEST = ["random/random_06-Aug-2020_16_24_25_3.csv", "turning/turn_14-Sep-2020_14_50_41.csv",
        "zigzag/zigzag_31-Jul-2020_14_10_05.csv", "berthing/berthing_12-Nov-2020_11_49_21.csv",
        "berthing/berthing_12-Nov-2020_13_21_03.csv", "turning/turn_14-Oct-2020_15_06_53.csv",
        "zigzag/zigzag_31-Jul-2020_13_42_53.csv", "berthing/berthing_12-Nov-2020_11_38_50.csv",
        "random/random_03-Aug-2020_11_04_37.csv"]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--train-only", action="store_true", help="identify only; read no test run")
    ap.add_argument("--model", default="esso_heldout9_MODEL.json", help="where the identified model is written")
    a = ap.parse_args(argv)
    root = Path(os.environ.get("SHIPID_DATA", "../shared/data")) / "esso_osaka_3m" / "data"
    runs = sorted(str(p.relative_to(root)) for p in root.glob("*/*.csv"))
    train = [r for r in runs if r not in TEST]
    assert len(train) == 32 and len(TEST) == 9 and not set(train) & set(TEST)
    t0, c0 = time.perf_counter(), time.process_time()
    res = shipid.identify("mmg", [str(root / r) for r in train], fmt="esso", folds=4)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    Path(a.model).write_text(res.to_json(), encoding="utf-8")
    sel = res.diagnostics.get("structure_selection") or {}
    print(f"identify: {wall:.0f} s wall, {cpu:.0f} s CPU (load average {os.getloadavg()[0]:.1f}); "
          f"selection: {sel.get('criterion')}; {sel.get('why')}")
    print(f"identified on {len(train)} runs: structure {res.model.get('structure_candidate')}, "
          f"refined: {bool((res.diagnostics.get('output_error') or {}).get('refined'))}, "
          f"re-timed: {res.model.get('retime') is not None}; model written to {a.model}")
    for w in res.warnings:
        print(f"  warning: {w}")
    if a.train_only:
        return 0
    rows = []
    print(f"{'test run':<48} {'identified psi [deg] / pos [m]':>32} {'published':>20}")
    for r in TEST:
        vi = shipid.validate(a.model, str(root / r), fmt="esso")
        vp = shipid.validate("published:esso_osaka_3m", str(root / r), fmt="esso")
        hi, hp = vi.horizons, vp.horizons
        rows.append((hi["psi"]["rms"], hi["pos"]["rms"], hp["psi"]["rms"], hp["pos"]["rms"]))
        print(f"{r:<48} {hi['psi']['rms']:20.2f} / {hi['pos']['rms']:.3f} {hp['psi']['rms']:11.2f} / "
              f"{hp['pos']['rms']:.3f}")
    n = len(rows)
    mi = (sum(x[0] for x in rows) / n, sum(x[1] for x in rows) / n)
    mp = (sum(x[2] for x in rows) / n, sum(x[3] for x in rows) / n)
    better = sum(x[0] < x[2] for x in rows)
    print(f"mean over the {n} runs: identified {mi[0]:.2f} deg / {mi[1]:.3f} m, published {mp[0]:.2f} deg / "
          f"{mp[1]:.3f} m; ratio {mi[0] / mp[0]:.2f} / {mi[1] / mp[1]:.2f}; heading better on {better} of {n}")
    Path(a.model).with_suffix(".scores.json").write_text(json.dumps(
        {"identified": mi, "published": mp, "heading_better": better, "per_run": dict(zip(TEST, rows))}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
