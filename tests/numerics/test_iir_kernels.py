"""The compiled rational filter of :mod:`shipid.numerics.iir_kernels` against ``scipy.signal.lfilter``.

Equality is ``numpy.array_equal`` (every bit, except that it treats -0.0 and 0.0 as equal: the module's one
documented difference), on random filters of the shapes Algorithm 1 uses (AR numerators over ``(1 - c q^-2)^k``,
all-pole, second-order bilinear) and on arbitrary ones (a[0] != 1, numerator shorter than denominator, records
shorter than the filter, leading zeros).
"""

import numpy as np
import pytest
from scipy.signal import lfilter as scipy_lfilter

from shipid.numerics.iir_kernels import BLOCK, lfilter, lfilter_into


def _stable(rng, na):
    r = 0.95 * rng.uniform(0.2, 1.0, na) * np.exp(1j * rng.uniform(0, np.pi, na))
    return np.real(np.poly(np.concatenate([r, np.conj(r)])))[: 2 * na + 1]


def test_bit_identical_on_random_filters():
    rng = np.random.default_rng(20261202)
    for trial in range(200):
        b = rng.standard_normal(int(rng.integers(1, 46)))
        a = _stable(rng, int(rng.integers(1, 3))) * (1.7 if trial % 5 == 0 else 1.0)
        n = int(rng.integers(1, 3 * BLOCK))
        x = rng.standard_normal(n)
        if trial % 4 == 0:
            x[: min(n, 60)] = 0.0
        assert np.array_equal(lfilter(b, a, x), scipy_lfilter(b, a, x)), trial


@pytest.mark.parametrize("c, k", [(0.99, 1), (0.97, 2), (0.5, 1)])
def test_bit_identical_on_prefilter_shapes(c, k):
    """The prefilters ``D(q)/(1 - c q^-2)^k`` of the noise model (AR(40) numerator), the all-pole
    ``1/(1 - c q^-2)^k`` and a bilinear second-order system, on a record of several blocks."""
    rng = np.random.default_rng([7, k])
    den = np.ones(1)
    for _ in range(k):
        den = np.convolve(den, [1.0, 0.0, -c])
    x = np.cumsum(rng.standard_normal(5 * BLOCK + 17))
    D = np.concatenate([[1.0], 0.05 * rng.standard_normal(40)])
    for b, a in ((D, den), ([1.0], den), ([0.3, 0.0, -0.3], [1.2, -1.9, 0.8])):
        assert np.array_equal(lfilter(b, a, x), scipy_lfilter(b, a, x))


def test_fir_and_into_a_strided_row():
    """A denominator of length one is lfilter's convolution branch; the output can be a strided row."""
    rng = np.random.default_rng(3)
    x = rng.standard_normal(1000)
    b = rng.standard_normal(41)
    assert np.array_equal(lfilter(b, [2.0], x), scipy_lfilter(b, [2.0], x))
    out = np.zeros((1000, 3))
    lfilter_into(b, [1.0, -0.5, 0.2], x[::1], out[:, 1])
    assert np.array_equal(out[:, 1], scipy_lfilter(b, [1.0, -0.5, 0.2], x))
    assert not out[:, 0].any() and not out[:, 2].any()


def test_bad_coefficients():
    with pytest.raises(ValueError):
        lfilter([1.0], [0.0, 1.0], np.ones(5))
    with pytest.raises(ValueError):
        lfilter([], [1.0, 0.5], np.ones(5))
