"""Esso Osaka 3 m, the papers' splits: the product path (``identify mmg`` defaults, then ``validate``).

The splits are those of the data set's README (``README_upstream.md``, "Correspondence table with the
paper"): ``miyauchi2022`` (Miyauchi et al. 2022, Train-TRZ: 6 training / 5 test runs) and ``wakita2022``
(Wakita et al. 2022, Train-TZRB+: 35 / 6). The model is what ``shipid identify mmg --trial ... --format esso``
gives on the split's training runs (``shipid.identify("mmg", ..., fmt="esso")``: structure by leave-one-run-out
CV over the candidate structures, re-timing, output-error refinement where the defaults apply it). Every
selection is made and printed before a test run is read (``--train-only`` stops there). Each test run is then
predicted by ``shipid.validate`` (60-s horizons restarted every 60 s), and by the published set
(``published:esso_osaka_3m``) with the same inputs; the errors are pooled over the test runs' horizons (RMS
weighted by horizon count). Uses the public API only.

    SHIPID_DATA=/path/to/data python studies/esso_splits/run.py [--split miyauchi2022|wakita2022|both]
        [--folds K] [--train-only]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path

import shipid

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from esso_runs import SPLITS  # noqa: E402  (the studies' shared run lists)


def pooled(horizons: list[dict], q: str) -> float:
    """RMS of quantity ``q`` over all horizons of the runs (each run's RMS weighted by its horizon count)."""
    n = sum(h["count"] for h in horizons)
    return math.sqrt(sum(h["count"] * h[q]["rms"] ** 2 for h in horizons) / n)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--split", choices=[*SPLITS, "both"], default="both")
    ap.add_argument("--folds", type=int, default=None, help="CV folds [default: leave one run out]")
    ap.add_argument("--train-only", action="store_true", help="identify only; read no test run")
    ap.add_argument("--out", default="esso_splits", help="prefix of the MODEL.json files and the scores file")
    a = ap.parse_args(argv)
    root = Path(os.environ.get("SHIPID_DATA", "../shared/data")) / "esso_osaka_3m" / "data"
    splits = list(SPLITS) if a.split == "both" else [a.split]
    models = {}
    for sp in splits:                      # every selection is made (and printed) before any test run is read
        train, test = SPLITS[sp]["train"], SPLITS[sp]["test"]
        assert not set(train) & set(test)
        res = shipid.identify("mmg", [str(root / r) for r in train], fmt="esso", folds=a.folds)
        models[sp] = f"{a.out}_{sp}_MODEL.json"
        Path(models[sp]).write_text(res.to_json(), encoding="utf-8")
        sel = res.diagnostics.get("structure_selection") or {}
        print(f"{sp}: {len(train)} training runs; {sel.get('method', 'structure given')}")
        for c, row in (sel.get("table") or {}).items():
            mark = "  <-" if c == res.model.get("structure_candidate") else ""
            print(f"  {c:<60} score {row['score']:7.3f}{mark}")
        print(f"  chosen '{res.model.get('structure_candidate')}', refined by output error: "
              f"{bool((res.diagnostics.get('output_error') or {}).get('refined'))}, "
              f"re-timed: {res.model.get('retime') is not None}; model written to {models[sp]}")
        for w in res.warnings:
            print(f"  warning: {w}")
    if a.train_only:
        return 0
    scores = {}
    for sp in splits:
        hi, hp = [], []
        print(f"{sp}: held-out 60-s horizons, RMS heading [deg] / position [m], identified vs published")
        for r in SPLITS[sp]["test"]:
            vi = shipid.validate(models[sp], str(root / r), fmt="esso").horizons
            vp = shipid.validate("published:esso_osaka_3m", str(root / r), fmt="esso").horizons
            hi.append(vi)
            hp.append(vp)
            print(f"  {r:<48} {vi['psi']['rms']:6.2f} / {vi['pos']['rms']:.3f}   {vp['psi']['rms']:6.2f} / "
                  f"{vp['pos']['rms']:.3f}")
        s = {"identified": (pooled(hi, "psi"), pooled(hi, "pos")), "published": (pooled(hp, "psi"), pooled(hp, "pos"))}
        scores[sp] = s
        print(f"  pooled: identified {s['identified'][0]:.2f} / {s['identified'][1]:.3f}, "
              f"published {s['published'][0]:.2f} / {s['published'][1]:.3f}")
    Path(f"{a.out}.scores.json").write_text(json.dumps(scores, indent=1), encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
