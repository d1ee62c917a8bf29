"""Noise generators: seeded, with the stated variance, correlation and spectral peak.

Statistical tolerances are about 4 standard errors of the estimator for the sample
sizes used (effective sample counts noted beside each check).
"""

import numpy as np
import pytest
from scipy.signal import welch

from shipid.io.trial import Trial
from shipid.simulate.noise import (MeasurementModel, as_generator, gauss_markov, gauss_markov_process,
                                   wave_process, wave_process_model, white_noise)


def test_seed_is_required_and_reproducible():
    with pytest.raises(TypeError):
        as_generator(None)
    np.testing.assert_array_equal(white_noise(10, 1.0, 3), white_noise(10, 1.0, 3))
    np.testing.assert_array_equal(gauss_markov(50, 0.1, 2.0, 1.0, 4, order=2),
                                  gauss_markov(50, 0.1, 2.0, 1.0, 4, order=2))
    assert not np.array_equal(wave_process(50, 0.1, 1.0, 0.1, 1.0, 1), wave_process(50, 0.1, 1.0, 0.1, 1.0, 2))


def test_white_noise_std():
    w = white_noise(100_000, np.array([0.5, 2.0]), np.random.default_rng(0))
    assert w.shape == (100_000, 2)
    # std of a sample std ≈ σ/√(2n) = 0.22 %
    np.testing.assert_allclose(w.std(axis=0), [0.5, 2.0], rtol=0.01)
    assert abs(np.corrcoef(w[:-1, 0], w[1:, 0])[0, 1]) < 0.015


def test_gauss_markov_first_order_exact_discretisation():
    dt, tau, std = 0.1, 2.0, 0.7
    proc = gauss_markov_process(tau, std, dt, order=1)
    # first order: Φ = e^{-dt/τ}, Q_d = σ²(1 - e^{-2dt/τ})
    assert proc.Phi[0, 0] == pytest.approx(np.exp(-dt / tau), rel=1e-14)
    assert proc.Qd_sqrt[0, 0] ** 2 == pytest.approx(std ** 2 * (1 - np.exp(-2 * dt / tau)), rel=1e-12)
    assert proc.variance == pytest.approx(std ** 2, rel=1e-12)


@pytest.mark.parametrize("order", [1, 2, 3])
def test_gauss_markov_variance_and_correlation(order):
    dt, tau, std = 0.1, 1.0, 0.7
    proc = gauss_markov_process(tau, std, dt, order=order)
    lags = np.array([0, 5, 10, 20, 30])
    rho = proc.autocorrelation(lags)
    s = lags * dt / tau
    analytic = {1: np.exp(-s), 2: (1 + s) * np.exp(-s), 3: (1 + s + s ** 2 / 3) * np.exp(-s)}[order]
    np.testing.assert_allclose(rho, analytic, rtol=1e-10, atol=1e-13)
    y = proc.sample_paths(1000, 400, np.random.default_rng(order))   # 400 paths × 100 s
    # ~400 × 100 s / (2·order·τ) ≳ 6700 effective samples: var s.e. ≲ 2 %
    assert y.var() == pytest.approx(std ** 2, rel=0.08)
    emp = [np.mean(y[k:] * y[: y.shape[0] - k]) / y.var() for k in lags]
    np.testing.assert_allclose(emp, analytic, atol=0.05)
    if order == 1:   # correlation time: autocorrelation e^{-1} at lag τ
        assert emp[2] == pytest.approx(np.exp(-1), abs=0.04)


def test_wave_process_rms_and_spectral_peak():
    dt, w0, zeta, rms = 0.1, 0.8, 0.1, 0.05
    proc = wave_process_model(w0, zeta, rms, dt)
    assert proc.variance == pytest.approx(rms ** 2, rel=1e-12)
    y = proc.sample_paths(4000, 200, np.random.default_rng(7))   # 200 paths × 400 s
    # correlation time 1/(ζω0) = 12.5 s → ~200 × 16 = 3200 effective samples: s.e. 2.5 %
    assert np.sqrt(y.var()) == pytest.approx(rms, rel=0.06)
    f, P = welch(y, fs=1 / dt, nperseg=2048, axis=0)
    Pm = P.mean(axis=1)
    w_peak = 2 * np.pi * f[np.argmax(Pm)]
    bin_w = 2 * np.pi * (f[1] - f[0])
    assert abs(w_peak - w0 * np.sqrt(1 - 2 * zeta ** 2)) <= 1.5 * bin_w   # |H(iω)|² peak
    # narrow band: half the power within ±2ζω0 of the peak
    band = np.abs(2 * np.pi * f - w0) < 2 * zeta * w0
    assert Pm[band].sum() / Pm.sum() > 0.5


def test_unstable_or_bad_parameters_rejected():
    with pytest.raises(ValueError):
        wave_process_model(1.0, 0.0, 1.0, 0.1)
    with pytest.raises(ValueError):
        gauss_markov_process(-1.0, 1.0, 0.1)


def _trial(n=20_000, dt=0.1):
    t = np.arange(n) * dt
    return Trial(t, {"psi": np.sin(0.01 * t), "r": 0.01 * np.cos(0.01 * t), "x": t})


def test_measurement_model_noise_bias_drift():
    tr = _trial()
    mm = MeasurementModel(noise={"psi": 0.002}, bias={"r": 0.001}, drift={"x": 0.05})
    a = mm.apply(tr, 9)
    b = mm.apply(tr, np.random.default_rng(9))
    np.testing.assert_array_equal(a["psi"], b["psi"])
    e_psi = a["psi"] - tr["psi"]
    assert e_psi.std() == pytest.approx(0.002, rel=0.03)       # n = 20 000: s.e. 0.5 %
    assert abs(e_psi.mean()) < 4 * 0.002 / np.sqrt(tr.t.size)
    np.testing.assert_allclose(a["r"] - tr["r"], 0.001, rtol=0, atol=1e-15)   # constant bias only
    drift = a["x"] - tr["x"]
    assert drift[0] == 0.0
    inc = np.diff(drift)
    assert inc.var() == pytest.approx(0.05 ** 2 * 0.1, rel=0.05)   # random walk: var = q² dt
    np.testing.assert_array_equal(a.t, tr.t)
    assert a.units == tr.units


def test_measurement_model_missing_channel():
    from shipid.errors import InputError
    with pytest.raises(InputError, match="phi"):
        MeasurementModel(noise={"phi": 0.1}).apply(_trial(), 0)
    out = MeasurementModel(noise={"phi": 0.1, "psi": 0.1}).apply(_trial(), 0, missing_ok=True)
    assert "phi" not in out
