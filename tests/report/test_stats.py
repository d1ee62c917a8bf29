"""Residual statistics: FFT autocorrelation, whiteness bounds, Ljung-Box, innovation consistency."""

import numpy as np

from shipid.report.stats import Z95, acf, residual_stats


def test_acf_matches_direct_sum():
    rng = np.random.default_rng(11)
    x = rng.normal(size=257)
    r = acf(x, 10)
    xc = x - x.mean()
    direct = np.array([np.dot(xc[: x.size - k], xc[k:]) for k in range(11)]) / np.dot(xc, xc)
    np.testing.assert_allclose(r, direct, rtol=1e-12, atol=1e-12)


def test_ar1_lag_one_correlation():
    rng = np.random.default_rng(12)
    n, rho = 20000, 0.9
    e = rng.normal(size=n)
    x = np.empty(n)
    x[0] = e[0]
    for k in range(1, n):
        x[k] = rho * x[k - 1] + e[k]
    r = acf(x, 3)
    # theory: rho_k = rho**k (AR(1)); standard error of the estimate ~ sqrt((1-rho^2)/n) ~ 0.003
    np.testing.assert_allclose(r[1:], rho ** np.arange(1, 4), atol=0.02)
    st, _ = residual_stats(x, max_lag=50)
    assert st.ljung_box_p < 1e-6
    # 0.9**k exceeds the bound 1.96/sqrt(20000) = 0.0139 for k <= 40, i.e. 40 of the 50 lags
    assert 0.7 <= st.frac_outside <= 0.9


def test_white_noise_passes_whiteness_checks():
    rng = np.random.default_rng(13)
    v = rng.normal(0.0, 2.0, 5000)
    st, r = residual_stats(v, std=np.full(v.size, 2.0))
    assert st.acf_bound == Z95 / np.sqrt(5000)
    assert st.frac_outside <= 0.15          # ~5 % expected over 50 lags
    assert st.ljung_box_p > 0.01
    assert abs(st.frac_in_2sigma - 0.9545) < 0.01  # P(|N(0,1)| <= 2) = 0.9545
    assert abs(st.rms - 2.0) < 0.1


def test_nan_samples_are_dropped_and_constant_is_safe():
    v = np.array([1.0, np.nan, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0])
    st, r = residual_stats(v)
    assert st.n == 8 and r[0] == 1.0 and np.all(r[1:] == 0.0)


def test_default_lags_span_a_tenth_of_long_records():
    from shipid.report.stats import default_max_lag

    assert default_max_lag(100) == 25          # n/4 for short records
    assert default_max_lag(400) == 50
    assert default_max_lag(3800) == 380        # 20 Hz, 190 s: 19 s of lags
    assert default_max_lag(10 ** 6) == 500
