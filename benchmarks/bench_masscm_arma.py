"""Benchmark: Hannan–Rissanen ARMA (shipid.estimate.arma) against statsmodels' maximum-likelihood ARIMA.

Algorithm 1 refits a noise model for every dataset at every iteration of every Monte Carlo run, so the
fit must be cheap. Same data (an ARMA(2,2) record of 3000 samples, as a 60-s dataset at 50 Hz), same
orders; prints time per fit, the ratio and the largest coefficient difference.

Usage:  python benchmarks/bench_masscm_arma.py [--smoke]   (needs statsmodels; --smoke: two fits of each)
"""

import sys
import time
import warnings

import numpy as np
from scipy.signal import lfilter

from shipid.estimate.arma import hannan_rissanen


def main():
    from statsmodels.tsa.arima.model import ARIMA

    rng = np.random.default_rng(0)
    a_true, c_true = np.array([1.0, -1.5, 0.8]), np.array([1.0, 0.3, -0.2])
    x = lfilter(c_true, a_true, rng.standard_normal(3000))
    smoke = "--smoke" in sys.argv[1:]
    n, n_sm = (2, 1) if smoke else (20, 3)
    t0 = time.perf_counter()
    for _ in range(n):
        m = hannan_rissanen(x, na=2, nc=2)
    t_hr = (time.perf_counter() - t0) / n
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0 = time.perf_counter()
        for _ in range(n_sm):
            res = ARIMA(x, order=(2, 0, 2), trend="n").fit()
        t_sm = (time.perf_counter() - t0) / n_sm
    a_sm = np.concatenate([[1.0], -res.arparams])
    c_sm = np.concatenate([[1.0], res.maparams])
    print(f"Hannan–Rissanen (shipid): {1e3 * t_hr:7.2f} ms/fit  a={np.round(m.a, 3)}  c={np.round(m.c, 3)}")
    print(f"statsmodels ARIMA (ML)  : {1e3 * t_sm:7.2f} ms/fit  a={np.round(a_sm, 3)}  c={np.round(c_sm, 3)}")
    print(f"ratio statsmodels/shipid = {t_sm / t_hr:.0f}x;  max |coef diff| = "
          f"{max(np.max(np.abs(m.a - a_sm)), np.max(np.abs(m.c - c_sm))):.3f}  (truth a={a_true}, c={c_true})")
    t0 = time.perf_counter()
    for _ in range(n):
        hannan_rissanen(x, na=40, nc=0)
    print(f"AR(40) as used by Algorithm 1: {1e3 * (time.perf_counter() - t0) / n:.2f} ms/fit")


if __name__ == "__main__":
    main()
