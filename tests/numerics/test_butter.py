"""The Butterworth band-pass of :mod:`shipid.numerics.butter` gives scipy.signal's doubles (design and
zero-phase filtering), bit for bit."""

import numpy as np
import pytest
from scipy.signal import butter, sosfilt_zi as scipy_zi, sosfiltfilt as scipy_filtfilt

from shipid.numerics.butter import butter_bandpass_sos, sosfilt_zi, sosfiltfilt


@pytest.mark.parametrize("T", [0.01, 0.02, 0.025, 0.04, 0.05, 0.1, 0.2, 0.5, 1.0])
@pytest.mark.parametrize("order", [1, 2, 3, 4])
def test_design_is_scipys(T, order):
    hi = min(2.0, 0.4 / T)
    ref = butter(order, [0.02, hi], btype="bandpass", fs=1.0 / T, output="sos")
    got = butter_bandpass_sos(order, 0.02, hi, 1.0 / T)
    assert got.shape == ref.shape
    assert np.array_equal(got, ref)
    assert np.array_equal(sosfilt_zi(ref), scipy_zi(ref))


@pytest.mark.parametrize("T, order, n", [(0.02, 2, 20_000), (0.1, 2, 3001), (0.5, 3, 500), (0.02, 1, 40)])
def test_filtfilt_is_scipys(T, order, n):
    sos = butter(order, [0.02, min(2.0, 0.4 / T)], btype="bandpass", fs=1.0 / T, output="sos")
    x = np.cumsum(np.random.default_rng([order, n]).standard_normal(n)) + 3.0
    got = sosfiltfilt(sos, x)
    assert np.array_equal(got, scipy_filtfilt(sos, x))
    assert got.base is None or got.base is not x          # a new array; the input is left as it was


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="band edges"):
        butter_bandpass_sos(2, 0.02, 30.0, 50.0)
    with pytest.raises(ValueError, match="padlen"):
        sosfiltfilt(butter_bandpass_sos(2, 0.02, 2.0, 50.0), np.ones(10))
