"""Box–Jenkins prefilter of the online monitor (:mod:`shipid.methods.monitor.estimator`).

The offline Algorithm 1 (Linder et al. 2015, steps B(b), eqs. 42–43) uses by default the noise model
``eps = (1 - c q^-2)^k / D(q) e`` of :mod:`shipid.methods.masscm.noise_bj`, whose prefilter ``L = D(q)/C(q)``,
``C = (1 - c q^-2)^k``, is an IIR filter. In the monitor's block moments the two factors are applied in turn:
``1/C(q)`` with its filter state carried over block boundaries (``C`` is held, so the state stays valid), then
the FIR ``D(q)`` with ``_HIST`` samples of the ``1/C``-filtered history, as for the AR prefilter. ``D`` is
refitted to the recent equation error at every update (least squares on ``eps / C``, the structure held, as
:func:`~shipid.methods.masscm.noise_bj.held_noise_model`); ``(c, k)`` is chosen by the innovation likelihood
among :data:`~shipid.methods.masscm.noise_bj.BJ_CANDIDATES` at start-up (the offline run) and optionally again
every few updates. Started from rest, ``1/C`` has a transient (a ``k``-fold pole pair of radius ``sqrt(c)``):
:func:`transient_samples` is the number of samples dropped until it has decayed to ``transient_tol``.
"""

from __future__ import annotations

import math

import numpy as np

from shipid.methods.masscm.iteration import left_physical_region
from shipid.methods.masscm.noise_bj import ma_structure, noise_model_bj
from shipid.methods.masscm.options import MassCMOptions
from shipid.models.roll_reduced import CALIBRATION, LOADED, NOMINAL, KnownParams


def lfilter(*args, **kwargs):
    """:func:`scipy.signal.lfilter`, imported on first call (``scipy.signal`` pulls ``scipy.stats``:
    about 0.5 s of start-up for a module that only filters)."""
    from scipy.signal import lfilter as _lfilter

    return _lfilter(*args, **kwargs)


def bj_mode(options: MassCMOptions) -> bool:
    """Whether the monitor uses the Box–Jenkins prefilter (``noise_model`` "auto" or "bj")."""
    return options.noise_model in ("auto", "bj")


def transient_samples(C: np.ndarray, options: MassCMOptions, n_window: int) -> int:
    """Samples until the start-up of ``1/C(q)`` has decayed to ``options.transient_tol`` (``t^(k-1) r^t``
    with ``r = sqrt(c)``), at most ``options.transient_max`` of a window of ``n_window`` samples."""
    if C.size < 3:
        return 0
    c, k = ma_structure(_Arma(C))
    if c <= 0:
        return 0
    m = int(math.ceil(math.log(options.transient_tol) / math.log(math.sqrt(c))))
    return int(min(m * k, options.transient_max * n_window))


class _Arma:
    """The ``c`` attribute that :func:`~shipid.methods.masscm.noise_bj.ma_structure` reads."""

    def __init__(self, c: np.ndarray):
        self.c = c


def fit_bj(eps: np.ndarray, options: MassCMOptions, C: np.ndarray | None):
    """Box–Jenkins noise model of the equation error ``eps``: ``(D, lam, C)``.

    ``C``: the MA polynomial to hold (``D`` re-estimated), or None to choose ``(c, k)`` among
    :data:`~shipid.methods.masscm.noise_bj.BJ_CANDIDATES` by the innovation variance."""
    cands = () if C is None else (ma_structure(_Arma(np.asarray(C, dtype=float))),)
    L = noise_model_bj(eps, options, cands)
    Cn = np.asarray(L.c, dtype=float) if L.c.size > 1 else np.ones(1)
    return np.asarray(L.a, dtype=float), float(L.lam), Cn


def inverse_c(S: np.ndarray, sm, C: np.ndarray, hist: int) -> np.ndarray:
    """``1/C(q)`` applied to the new columns ``S[:, hist:]`` of a block, the filter state ``sm.zc`` carried over
    blocks; returns the filtered signals with ``hist`` columns of filtered history in front (``sm.ghist``)."""
    if sm.zc is None or sm.zc.shape[1] != C.size - 1:
        sm.zc, sm.ghist = np.zeros((S.shape[0], C.size - 1)), np.zeros((S.shape[0], hist))
    Gn, sm.zc = lfilter([1.0], C, S[:, hist:], axis=1, zi=sm.zc)
    G = np.hstack([sm.ghist, Gn])
    sm.ghist = G[:, -hist:].copy()
    return G


def degenerate(theta_q: np.ndarray, theta_prev_q: np.ndarray, known: KnownParams, zm_bound: float) -> bool:
    """Whether a window search went to the degenerate minimum of (40): it left the physical region
    (:func:`shipid.methods.masscm.iteration.left_physical_region`, the offline guard) or put ``zm_bar`` on its
    bound ``zm_bound`` (seen after a reset on a short window in wave roll without sensor noise)."""
    if left_physical_region(theta_q, theta_prev_q, known, [NOMINAL, CALIBRATION, LOADED]):
        return True
    return bool(abs(theta_q[8]) >= 0.999 * zm_bound)


def structure_of(C: np.ndarray) -> tuple[float, int]:
    """``(c, k)`` of the MA polynomial ``C``."""
    return ma_structure(_Arma(np.asarray(C, dtype=float)))


__all__ = ["bj_mode", "transient_samples", "fit_bj", "inverse_c", "degenerate", "structure_of"]
