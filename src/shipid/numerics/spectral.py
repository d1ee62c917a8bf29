"""Welch's averaged periodogram (Welch 1967) of a real signal, as ``scipy.signal.welch`` computes it with its
defaults (periodic Hann window, half-overlapping segments, each segment's mean removed, one-sided density),
in numpy, so that a caller needing only a spectral peak does not import ``scipy.signal`` (which imports
``scipy.stats`` and ``scipy.interpolate``).

Segments of ``nperseg`` samples start every ``nperseg - nperseg // 2`` samples, ``(n - nperseg // 2) // hop`` of
them (scipy's count); each is detrended by its mean, multiplied by the window ``0.5 - 0.5 cos(2 pi k / nperseg)``
and transformed; ``|X_k|^2 / (fs sum w^2)``, doubled at every bin but DC (and Nyquist for even ``nperseg``), is
averaged over the segments. The values agree with scipy's to rounding (~1e-15 relative; the FFTs are numpy's, not
``scipy.fft``'s), and the peak bin is the same (``tests/numerics/test_spectral.py``).
"""

from __future__ import annotations

import numpy as np


def welch(x: np.ndarray, fs: float = 1.0, nperseg: int = 256) -> tuple[np.ndarray, np.ndarray]:
    """``(f, Pxx)``: the frequencies (Hz) and the one-sided power spectral density of ``x`` (1-D, real) by
    Welch's method with ``scipy.signal.welch``'s defaults (module docstring). ``nperseg`` longer than ``x`` is
    shortened to its length, as scipy does."""
    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or x.size == 0:
        raise ValueError("welch: x must be a non-empty 1-D array")
    n = x.size
    nperseg = min(int(nperseg), n)
    if nperseg < 1:
        raise ValueError("welch: nperseg must be a positive integer")
    noverlap = nperseg // 2
    hop = nperseg - noverlap
    nseg = max((n - noverlap) // hop, 1)
    k = np.arange(nperseg)
    win = 0.5 - 0.5 * np.cos(2.0 * np.pi * k / nperseg)
    scale = 1.0 / (fs * float(np.sum(win * win)))
    P = np.zeros(nperseg // 2 + 1)
    for i in range(nseg):
        seg = x[i * hop:i * hop + nperseg]
        X = np.fft.rfft((seg - seg.mean()) * win)
        P += X.real ** 2 + X.imag ** 2
    P *= scale / nseg
    P[1:-1 if nperseg % 2 == 0 else None] *= 2
    return np.fft.rfftfreq(nperseg, 1.0 / fs), P


__all__ = ["welch"]
