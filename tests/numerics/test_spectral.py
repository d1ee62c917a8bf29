"""Welch's periodogram of :mod:`shipid.numerics.spectral` against ``scipy.signal.welch`` (its defaults): the same
frequencies, the density to rounding, the same peak bin."""

import numpy as np
import pytest
from scipy.signal import welch as scipy_welch

from shipid.numerics.spectral import welch


@pytest.mark.parametrize("seed", range(40))
def test_welch_is_scipys(seed):
    rng = np.random.default_rng([31, seed])
    n = int(rng.integers(64, 20_000))
    nperseg = min(2048, n) if seed % 3 else int(rng.integers(8, n + 1))
    fs = float(rng.choice([1.0, 10.0, 50.0, 1 / 0.03]))
    t = np.arange(n)
    x = (np.convolve(rng.standard_normal(n), [1.0, 0.9, 0.5, -0.3], mode="same")
         + 0.5 * np.sin(2 * np.pi * rng.uniform(0.01, 0.45) * t) + rng.uniform(-3, 3))
    f_ref, p_ref = scipy_welch(x, fs=fs, nperseg=nperseg)
    f, p = welch(x, fs=fs, nperseg=nperseg)
    assert np.array_equal(f, f_ref)
    # numpy's FFT against scipy.fft's: rounding only
    np.testing.assert_allclose(p, p_ref, rtol=1e-12, atol=1e-14 * float(np.max(p_ref)))
    assert int(np.argmax(p[1:])) == int(np.argmax(p_ref[1:]))


def test_segment_longer_than_the_signal_is_shortened():
    x = np.random.default_rng(2).standard_normal(300)
    with pytest.warns(UserWarning):
        f_ref, p_ref = scipy_welch(x, fs=2.0, nperseg=512)
    f, p = welch(x, fs=2.0, nperseg=512)
    assert np.array_equal(f, f_ref)
    np.testing.assert_allclose(p, p_ref, rtol=1e-12)
