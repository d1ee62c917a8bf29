"""Is the std that ``identify mmg`` states honest? A split-half check on real training runs.

The runs are split at random into two disjoint halves, each half identified on its own by
``shipid.identify("mmg", half, prior=..., structure=...)`` (the product path with the structure given, as
``shipid identify mmg --trial ... --structure NAME``), and every coefficient estimated in both halves gives
``z = (theta_A - theta_B) / sqrt(sd_A^2 + sd_B^2)``; an honest std gives an RMS z near 1 (median |z| near
0.67), an optimistic one far above. Two stds are checked: the one MODEL.json carries (``Estimate.std``: the
run bootstrap from 5 runs on, else the HAC sandwich; plus the SIMEX and output-error terms where the defaults
apply them) and the plain ridge SE it reports beside it (``diagnostics["covariance"]["se_ridge"]``).

Cases: ``kvlcc2`` — the ten HSVA training zig-zags of the KVLCC2 overshoot study (its 20/10 and 35/5 runs
left out), prior ``kvlcc2_hsva``, candidate ``full/symmetric-gamma_R``; ``esso`` — the 35 training runs of
the Wakita et al. (2022) split, prior ``esso_osaka_3m``, candidate ``hull+rudder+thrust/nondimensional``.
Uses the public API only.

    SHIPID_DATA=/path/to/data python studies/mmg_covariance/run.py {kvlcc2,esso} [--splits 10] [--seed 0]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import random
import statistics
import sys
from pathlib import Path

import shipid

KVLCC2 = ["HSVA_CPMC_KVLCC2_Z_05_01.dat", "HSVA_CPMC_KVLCC2_Z_10_01.dat", "HSVA_CPMC_KVLCC2_Z_10_05.dat",
          "HSVA_CPMC_KVLCC2_Z_10_10_P.dat", "HSVA_CPMC_KVLCC2_Z_10_10_S.dat", "HSVA_CPMC_KVLCC2_Z_15_01.dat",
          "HSVA_CPMC_KVLCC2_Z_15_05.dat", "HSVA_CPMC_KVLCC2_Z_20_05.dat", "HSVA_CPMC_KVLCC2_Z_25_05.dat",
          "HSVA_CPMC_KVLCC2_Z_30_05.dat"]
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from esso_runs import SPLITS  # noqa: E402  (the studies' shared run lists)

WAKITA_TRAIN = SPLITS["wakita2022"]["train"]
CASES = {"kvlcc2": ("kvlcc2_hsva", "kvlcc2_hsva", "full/symmetric-gamma_R", KVLCC2),
         "esso": ("esso_osaka_3m/data", "esso_osaka_3m", "hull+rudder+thrust/nondimensional", WAKITA_TRAIN)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("case", choices=sorted(CASES))
    ap.add_argument("--splits", type=int, default=10, help="random half-splits of the runs")
    ap.add_argument("--seed", type=int, default=0, help="seed of the splits")
    ap.add_argument("--out", default=None, help="write the z values as JSON to this file")
    a = ap.parse_args(argv)
    sub, prior, cand, runs = CASES[a.case]
    root = Path(os.environ.get("SHIPID_DATA", "../shared/data")) / sub
    paths = [str(root / r) for r in runs]
    rng = random.Random(a.seed)
    z: dict[str, list[float]] = {"MODEL.json std": [], "ridge SE": []}
    for s in range(a.splits):
        perm = rng.sample(range(len(paths)), len(paths))
        halves = [sorted(perm[: len(paths) // 2]), sorted(perm[len(paths) // 2:])]
        fits = [shipid.identify("mmg", [paths[i] for i in h], prior=prior, structure=cand) for h in halves]
        est = [{k: e for k, e in f.estimates.items() if e.status == "estimated"} for f in fits]
        ridge = [f.diagnostics["covariance"]["se_ridge"] for f in fits]
        for k in sorted(set(est[0]) & set(est[1])):
            d = est[0][k].value - est[1][k].value
            for kind, sd in (("MODEL.json std", (est[0][k].std, est[1][k].std)),
                             ("ridge SE", (ridge[0][k], ridge[1][k]))):
                den = math.hypot(*sd)
                if den > 0 and math.isfinite(den):
                    z[kind].append(d / den)
        print(f"split {s + 1}/{a.splits}: halves of {len(halves[0])} and {len(halves[1])} runs", file=sys.stderr)
    print(f"{a.case}: {len(paths)} training runs, candidate '{cand}', {a.splits} random half-splits, seed {a.seed}; "
          "z = (theta_A - theta_B) / sqrt(sd_A^2 + sd_B^2)")
    print(f"  {'std':<16} {'RMS z':>7} {'median |z|':>11} {'n':>5}   (honest: RMS z ~ 1, median |z| ~ 0.67)")
    for kind, v in z.items():
        if v:
            print(f"  {kind:<16} {math.sqrt(sum(x * x for x in v) / len(v)):7.2f} "
                  f"{statistics.median(abs(x) for x in v):11.2f} {len(v):5d}")
    if a.out:
        Path(a.out).write_text(json.dumps(z, indent=1), encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
