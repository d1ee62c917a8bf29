"""Diagnostic (not a timing benchmark): the two tests of the ``refine="auto"`` rule on tuning seeds.

Fishing vessel, three datasets per realisation (``SeedSequence([s, 0])`` for ``s`` in SEEDS, 300-s records by
default), in the regimes of :mod:`shipid.methods.masscm.coverage` plus ``none`` (noise-free, as Table 3). Printed
per regime: the range (min, 5 %, median, 95 %, max) of the sensor-noise level of
:func:`shipid.methods.masscm.refine.sensor_noise_level` and the milliseconds it took; with ``ALG1=N`` also, for the
first N seeds of the sensors and both regimes, how often Algorithm 1's noise model (compute "fast", default
options) carries a wave factor (:func:`shipid.methods.masscm.refine.waves_detected`) and what the rule decides.
The thresholds of :mod:`shipid.methods.masscm.refine` were chosen on seeds 100..199 with this script.

Usage:  python benchmarks/diag_masscm_refine_rule.py [FIRST=100] [LAST=199] [DURATION=300] [ALG1=0]
"""

import sys
import time
import warnings

import numpy as np

from shipid.estimate.linalg import one_blas_thread
from shipid.methods.masscm.coverage import REGIMES
from shipid.methods.masscm.estimator import MassCMOptions
from shipid.methods.masscm.assemble import estimate_mass_cm as algorithm1
from shipid.methods.masscm.refine import SENSOR_NOISE_MIN, choose, sensor_noise_level
from shipid.models.roll_reduced import KnownParams
from shipid.models.roll_sim import NoiseSpec, simulate_datasets
from shipid.vessels import load_vessel


def main(first=100, last=199, duration=300.0, alg1=0):
    regs = dict(REGIMES)
    regs["none"] = NoiseSpec()
    known = KnownParams.from_vessel("fishing-vessel")
    z_f = float(load_vessel("fishing-vessel").value("general", "z_f"))
    print(f"seeds {first}..{last}, {duration:g} s, threshold {SENSOR_NOISE_MIN:g}")
    for name, spec in regs.items():
        lv, ms, waves, dec = [], [], 0, {}
        for s in range(first, last + 1):
            d = simulate_datasets("fishing-vessel", seed=np.random.SeedSequence([s, 0]), duration=duration, noise=spec)
            with one_blas_thread():
                t0 = time.perf_counter()
                lv.append(sensor_noise_level(list(d.items()))["level"])
                ms.append(1e3 * (time.perf_counter() - t0))
            if name in ("sensors", "both") and s < first + alg1:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    r = algorithm1(list(d.items()), known, z_f=z_f, noise_check=False,
                                   options=MassCMOptions(compute="fast", refine="none"))
                eng, rec = choose(list(d.items()), r, z_f)
                waves += rec["waves"]["detected"]
                dec[eng] = dec.get(eng, 0) + 1
        q = np.percentile(lv, [0, 5, 50, 95, 100])
        print(f"{name:8s} level " + " ".join(f"{x:.2e}" for x in q) + f"  above threshold {sum(x > SENSOR_NOISE_MIN for x in lv)}/{len(lv)}"
              f"  median {np.median(ms):.1f} ms" + (f"  wave factor {waves}/{min(alg1, len(lv))}, decisions {dec}"
                                                    if name in ("sensors", "both") and alg1 else ""), flush=True)


if __name__ == "__main__":
    a = sys.argv[1:]
    main(int(a[0]) if a else 100, int(a[1]) if len(a) > 1 else 199, float(a[2]) if len(a) > 2 else 300.0,
         int(a[3]) if len(a) > 3 else 0)
