"""Start values of the sway and yaw rows for the maximum-likelihood refinements (Linder et al. 2015;
beyond the paper).

:func:`initial_rows` is the start of :mod:`shipid.methods.masscm.pem` and :mod:`shipid.methods.masscm.whittle`:
a least-squares fit of ``v'`` and ``r'`` on reconstructed states and the wave moment. ``phi`` integrates ``p``,
``v`` integrates ``v' = z_s p' + g phi - U r - a_s`` (8), ``p', r'`` are central differences and the wave moment
``tau`` is the remainder of the roll row (23) at ``theta``; all signals then pass the same zero-phase band-pass
(0.02-2 Hz, second-order Butterworth applied forward and backward: :mod:`shipid.numerics.butter`, scipy's
``butter`` and ``sosfiltfilt`` doubles without importing ``scipy.signal``), which keeps the linear relations and
removes the integration drift and the biases. The band-pass is
applied one signal at a time into one preallocated regressor matrix (not to a stacked copy of all eight signals),
so that on a one-hour record at 50 Hz its transient is about a third of the stacked form's.

:func:`initial_local` is the whole local start vector of a dataset (rows, wave filter, sensor variances, biases).
"""

from __future__ import annotations

import numpy as np

from shipid.models.roll_reduced import KnownParams, roll_terms
from shipid.numerics.butter import butter_bandpass_sos, sosfiltfilt


def initial_rows(s, theta, known: KnownParams) -> np.ndarray:
    """Start values ``c_v, c_r`` (12,) (coefficients of ``[phi, v, p, r, delta, tau]`` of (11)) for a dataset
    ``s`` with ``y (N, 3)`` (``p, a_s, r``), ``delta``, ``T``, ``n``, ``cond``, ``z_f`` at ``theta`` (names
    :data:`~shipid.methods.masscm.crlb_kf.FREE`); see the module docstring."""
    T = s.T
    sos = butter_bandpass_sos(2, 0.02, min(2.0, 0.4 / T), 1.0 / T)
    p, a, r = (s.y[:, i] - s.y[:, i].mean() for i in range(3))
    phi = np.cumsum(p) * T
    pd, rd = np.gradient(p, T), np.gradient(r, T)
    zs = known.zs_bar + s.z_f
    vd = zs * pd + known.g * phi - known.U * r - a
    del a
    th = list(theta[:6]) + [s.z_f] + list(theta[6:])
    t = roll_terms(np.array(th), known, [s.cond])
    B, A1, kp, dd, Kr, Kd = (t[n][0] for n in ("B", "A1", "kp", "d", "K_r", "K_delta"))
    dl = s.delta - s.delta.mean()
    X = np.empty((s.n, 6))
    X[:, 5] = sosfiltfilt(sos, A1 * pd + (kp + B * known.g) * phi + dd * p - B * vd - (Kr + B * known.U) * r
                          - Kd * dl)
    del pd
    X[:, 0] = sosfiltfilt(sos, phi)
    del phi
    X[:, 1] = sosfiltfilt(sos, np.cumsum(vd - vd.mean()) * T)
    X[:, 2] = sosfiltfilt(sos, p)
    X[:, 3] = sosfiltfilt(sos, r)
    X[:, 4] = sosfiltfilt(sos, dl)
    del p, r, dl
    Yv, Yr = sosfiltfilt(sos, vd), sosfiltfilt(sos, rd)
    sl = slice(s.n // 20, s.n - s.n // 20)
    cv = np.linalg.lstsq(X[sl], Yv[sl], rcond=None)[0]
    cr = np.linalg.lstsq(X[sl], Yr[sl], rcond=None)[0]
    return np.concatenate([cv, cr])


def initial_local(s, theta, known: KnownParams, admissible) -> np.ndarray:
    """The start of a dataset's local vector ``c_v (6) | c_r (6) | log w, log zeta, log sigma | log var (3) |
    bias (3)``: the rows of :func:`initial_rows`, a placeholder wave filter (1-s period, damping 0.1), the sensor
    variances from second differences of the outputs (``var(y'') / 6``, white noise), the biases from the means;
    the sway damping ``c_v[1]`` is then lowered by 0.05 until ``admissible(loc)`` (a stable ship; at most 30 times:
    ``v`` is the state the reconstruction determines worst)."""
    loc = np.zeros(21)
    loc[:12] = initial_rows(s, theta, known)
    loc[12:15] = np.log([2 * np.pi / 1.0, 0.1, 1e-3])
    d2 = np.diff(s.y, n=2, axis=0)
    loc[15:18] = np.log(np.maximum(np.var(d2, axis=0) / 6, 1e-12))
    loc[18:21] = s.y.mean(axis=0)
    for _ in range(30):
        if admissible(loc):
            break
        loc[1] -= 0.05
    return loc


__all__ = ["initial_rows", "initial_local"]
