"""Diagnostic (not a timing benchmark): the two tests of the ``refine="auto"`` rule on tuning seeds.

Fishing vessel, three datasets per realisation (``SeedSequence([s, 0])`` for ``s`` in FIRST..LAST, 300-s records
by default), in the regimes of :mod:`shipid.methods.masscm.coverage` plus ``none`` (noise-free, as Table 3).
Printed per regime: the range (min, 5 %, median, 95 %, max over realisations) of the sensor-noise level of
:func:`shipid.methods.masscm.refine.sensor_noise_level` and of the wave-colour level of
:func:`shipid.methods.masscm.refine.wave_colour`, how many realisations exceed each threshold, the decisions of
:func:`shipid.methods.masscm.refine.choose` (z_f known) and the median milliseconds of the two tests together.
The thresholds of :mod:`shipid.methods.masscm.refine` were chosen on seeds 100..199 with this script.

Usage:  python benchmarks/diag_masscm_refine_rule.py [FIRST=100] [LAST=199] [DURATION=300]
        python benchmarks/diag_masscm_refine_rule.py --smoke     (one seed, 60-s records)
"""

import sys
import time

import numpy as np

from shipid.numerics.linalg import one_blas_thread
from shipid.methods.masscm.coverage import REGIMES
from shipid.methods.masscm.refine import SENSOR_NOISE_MIN, WAVE_Z_MIN, choose
from shipid.models.roll_sim import NoiseSpec, simulate_datasets


def main(first=100, last=199, duration=300.0):
    regs = dict(REGIMES)
    regs["none"] = NoiseSpec()
    print(f"seeds {first}..{last}, {duration:g} s; thresholds: sensor level {SENSOR_NOISE_MIN:g}, wave z {WAVE_Z_MIN:g}")
    for name, spec in regs.items():
        sl, wz, ms, dec = [], [], [], {}
        for s in range(first, last + 1):
            d = list(simulate_datasets("fishing-vessel", seed=np.random.SeedSequence([s, 0]), duration=duration,
                                       noise=spec).items())
            with one_blas_thread():
                t0 = time.perf_counter()
                eng, rec = choose(d, None, -0.028)
                ms.append(1e3 * (time.perf_counter() - t0))
            sl.append(rec["sensor_test"]["level"])
            wz.append(rec["wave_test"]["level"])
            dec[eng] = dec.get(eng, 0) + 1

        def rng(v):
            return " ".join(f"{x:.3g}" for x in np.percentile(v, [0, 5, 50, 95, 100]))
        print(f"{name:8s} sensor level [{rng(sl)}] above {sum(x > SENSOR_NOISE_MIN for x in sl)}/{len(sl)}; "
              f"wave z [{rng(wz)}] above {sum(x > WAVE_Z_MIN for x in wz)}/{len(wz)}; decisions {dec}; "
              f"{np.median(ms):.1f} ms", flush=True)


if __name__ == "__main__":
    a = sys.argv[1:] if "--smoke" not in sys.argv else ["100", "100", "60"]
    main(int(a[0]) if a else 100, int(a[1]) if len(a) > 1 else 199, float(a[2]) if len(a) > 2 else 300.0)
