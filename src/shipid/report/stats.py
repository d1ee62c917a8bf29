"""Residual checks shown in the report: autocorrelation, whiteness, innovation consistency.

A well-fitted model leaves residuals that are white: their sample
autocorrelation at lags k ≥ 1 lies inside ±1.96/√N in about 95 % of lags
(Box, Jenkins & Reinsel, *Time Series Analysis*, 4th ed., §2.1.6), and the
Ljung–Box statistic Q = N(N+2) Σ_{k=1}^{h} ρ_k² / (N−k) is χ²(h) distributed
(Ljung & Box 1978). For a Kalman filter the innovations should in addition lie
inside their predicted ±2σ in about 95 % of samples (the innovation checks of Fossen, Sagatun & Sørensen 1996).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats as _st

Z95 = 1.959963984540054


def default_max_lag(n: int) -> int:
    """Lags shown and tested: 50, or a tenth of the record when longer (at most 500, at most n/4).

    Densely sampled records (20 Hz model tests) need lags spanning seconds, not 50 samples,
    for the autocorrelation to say anything about the residual's time scale.
    """
    if n < 8:
        return max(n - 1, 0)
    return int(min(n // 4, max(50, n // 10), 500))


def acf(x, max_lag: int | None = None) -> np.ndarray:
    """Sample autocorrelation ρ_0..ρ_max_lag of ``x`` (NaNs dropped, mean removed, biased estimator).

    Computed with an FFT so long residual records stay cheap.
    """
    x = np.asarray(x, dtype=float)
    x = x[np.isfinite(x)]
    n = x.size
    if n < 2:
        return np.array([1.0])
    if max_lag is None:
        max_lag = default_max_lag(n)
    max_lag = int(min(max_lag, n - 1))
    x = x - x.mean()
    denom = float(np.dot(x, x))
    if denom == 0.0:
        out = np.zeros(max_lag + 1)
        out[0] = 1.0
        return out
    nfft = 1 << int(np.ceil(np.log2(2 * n - 1)))
    f = np.fft.rfft(x, nfft)
    r = np.fft.irfft(f * np.conj(f), nfft)[: max_lag + 1]
    return r / denom


@dataclass(frozen=True)
class ResidualStats:
    n: int
    mean: float
    rms: float
    std: float
    acf_bound: float
    frac_outside: float     # fraction of lags 1..h with |ρ_k| > 1.96/√N
    max_lag: int
    ljung_box_q: float
    ljung_box_p: float
    frac_in_2sigma: float   # NaN when no predicted σ was given


def residual_stats(values, std=None, max_lag: int | None = None) -> tuple[ResidualStats, np.ndarray]:
    """Whiteness and consistency statistics of one residual record; returns (stats, acf)."""
    v = np.asarray(values, dtype=float)
    ok = np.isfinite(v)
    x = v[ok]
    n = int(x.size)
    r = acf(x, max_lag)
    h = r.size - 1
    bound = Z95 / np.sqrt(n) if n > 0 else float("nan")
    if h >= 1 and n > h:
        lags = np.arange(1, h + 1)
        q = float(n * (n + 2) * np.sum(r[1:] ** 2 / (n - lags)))
        p = float(_st.chi2.sf(q, h))
        frac = float(np.mean(np.abs(r[1:]) > bound))
    else:
        q = p = frac = float("nan")
    in2 = float("nan")
    if std is not None:
        s = np.asarray(std, dtype=float)
        if s.shape == v.shape:
            m = ok & np.isfinite(s) & (s > 0)
            if m.any():
                in2 = float(np.mean(np.abs(v[m]) <= 2.0 * s[m]))
    return ResidualStats(
        n=n,
        mean=float(x.mean()) if n else float("nan"),
        rms=float(np.sqrt(np.mean(x ** 2))) if n else float("nan"),
        std=float(x.std(ddof=1)) if n > 1 else float("nan"),
        acf_bound=float(bound), frac_outside=frac, max_lag=h,
        ljung_box_q=q, ljung_box_p=p, frac_in_2sigma=in2,
    ), r
