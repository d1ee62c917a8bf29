"""Box–Jenkins noise model of the equation error (35) with a structured unit-circle MA part (Algorithm 1 of
Linder et al. 2015, steps B(b), eqs. 42–43; the refined-IV noise model of Young & Jakeman).

The equation error of (35) is ``eps = C(q)/D(q) e`` with ``e`` white, and the prefilter of the next iteration is
its inverse ``L = D(q)/C(q)`` (RIV: the prefilter ``D/(C A)`` of the output-error form is ``D/C`` on the equation
error, where ``A(q)`` already multiplies the output). The MA part is structured:

    C(q) = (1 - c q^-2)^k,   k in {0, 1, 2},   D(q) = AR(ar_order) by least squares on eps / C(q).

Why ``k = 2``: the wave roll moment ``tau`` enters (23) as a moment, so the bilinear form (35) carries it as
``(2/T)(1 - q^-2) tau`` (the same factor as the moments ``a_s``, ``r``, ``delta``); and the wave filter of
:func:`shipid.models.roll_sim.wave_moment` (a Tustin-discretised ``2 zeta w s/(s^2 + 2 zeta w s + w^2)``) puts
another ``(1 - q^-2)`` into ``tau`` itself. The wave part of the equation error is therefore
``K (1 - q^-2)^2 / a_w(q) e``: its spectrum falls as ``w^4`` towards 0 and Nyquist (measured on simulated
noise-only records: 1e-12 at 0.025 Hz against 1e-5 at the 1-Hz wave peak). A model with one factor
(``k = 1``) overstates the noise at the low frequencies where the rudder response lives
by orders of magnitude, so its prefilter discards most of the rudder information. White sensor noise, which
reaches (35) through ``A(q)`` and ``(1 - q^-2)``, fills the notch (``k = 1`` or ``k = 0``, ``c`` smaller).

Order selection (the stated criterion): for every candidate ``(c, k)`` of :data:`BJ_CANDIDATES` the AR part is
fitted and the innovations ``D(q) eps / C(q)`` are evaluated over a common window (after the start-up transient
of the slowest candidate, at most ``transient_max`` of the record); the smallest innovation variance wins. With
the same ``eps`` and monic, minimum-phase ``C`` and ``D`` this is the Gaussian innovation likelihood, and every
candidate has the same number of estimated coefficients (``ar_order``; ``c`` and ``k`` come from a fixed grid),
so likelihood, AIC and BIC rank them alike.
"""

from __future__ import annotations

import numpy as np

from shipid.estimate.arma import ARMA, ar_gram, ar_solve_normal, fit_ar
from shipid.numerics.iir_kernels import lfilter
from shipid.methods.masscm.options import MassCMOptions

#: The candidate MA structures ``(c, k)``: ``C(q) = (1 - c q^-2)^k``. ``(0, 0)`` is the plain AR model; the
#: ``k = 1`` ones the unit-circle factor once; ``k = 2`` the wave-roll structure (module docstring).
BJ_CANDIDATES = ((0.0, 0), (0.5, 1), (0.9, 1), (0.97, 1), (0.99, 1), (0.9, 2), (0.97, 2), (0.99, 2))


def ma_poly(c: float, k: int) -> np.ndarray:
    """``(1 - c q^-2)^k`` as coefficients in ``q^-1``."""
    p = np.ones(1)
    for _ in range(int(k)):
        p = np.convolve(p, [1.0, 0.0, -c])
    return p


def ma_structure(L) -> tuple[float, int]:
    """``(c, k)`` of a prefilter ``D(q)/(1 - c q^-2)^k`` (``(0, 0)`` for a FIR prefilter or none)."""
    if L is None or L.c.size < 3:
        return 0.0, 0
    k = (L.c.size - 1) // 2
    c = float(-L.c[2]) / k
    return c, k


def _window(n: int, candidates, options: MassCMOptions) -> int:
    """Start of the common window: the start-up of the slowest candidate has decayed to ``transient_tol``
    (a ``k``-fold pole pair of radius ``sqrt(c)`` decays like ``t^(k-1) r^t``), at most ``transient_max n``."""
    worst = 0
    for c, k in candidates:
        if c <= 0 or k == 0:
            continue
        r = np.sqrt(c)
        m = int(np.ceil(np.log(options.transient_tol) / np.log(r)))
        worst = max(worst, m * k)
    return int(min(worst, options.transient_max * n))


def noise_model_bj(eps: np.ndarray, options: MassCMOptions, candidates: tuple = ()) -> ARMA:
    """Box–Jenkins noise model ``eps = (1 - c q^-2)^k / D(q) e`` with ``(c, k)`` chosen by the data.

    ``candidates``: the ``(c, k)`` to try (default :data:`BJ_CANDIDATES`); :func:`held_noise_model` passes the
    previous one alone once the iteration holds the structure. Returns an :class:`~shipid.estimate.arma.ARMA`
    ``(D, C, lam)``: its ``prefilter`` is ``L = D/C`` (43) and ``lam`` the innovation variance (the weight of
    the dataset in (40)).
    """
    eps = np.asarray(eps, dtype=float)
    cands = tuple(candidates) or BJ_CANDIDATES
    k0 = _window(eps.size, BJ_CANDIDATES if len(cands) > 1 else cands, options)
    best = None
    for c, k in cands:
        den = ma_poly(c, k) if (c and k) else np.ones(1)
        e2 = lfilter([1.0], den, eps) if den.size > 1 else eps
        a = fit_ar(e2, options.ar_order).a if options.compute == "fast" else ar_polynomial(e2, options.ar_order)
        inn = lfilter(a, [1.0], e2 - e2.mean())[k0:]
        lam = float(np.mean((inn - inn.mean()) ** 2))
        if best is None or lam < best[0]:
            best = (lam, ARMA(a, den, lam))
    return best[1]


def ar_polynomial(x: np.ndarray, p: int) -> np.ndarray:
    """``A(q)`` of the AR(p) least-squares fit of ``x`` (mean removed): the ``a`` of
    ``shipid.estimate.arma.hannan_rissanen(x, p, 0, n_long=p)``, the same numbers by the same steps (scaled
    normal equations :func:`~shipid.estimate.arma.ar_gram`, ridge-regularised Cholesky
    :func:`~shipid.estimate.arma.ar_solve_normal`), without the pass over the record that computes its
    innovation variance (:func:`noise_model_bj` measures the innovations on its own window)."""
    x = np.asarray(x, dtype=float)
    x = x - x.mean()
    scale = np.std(x)
    if not np.isfinite(scale) or scale == 0.0 or not p:
        return np.ones(1)
    xs = x / scale
    G, g = ar_gram(xs, p)
    return np.concatenate([[1.0], -ar_solve_normal(G, g, xs, p)])


#: (*) From iteration ``AUTO_HOLD + FREEZE_AFTER`` on the whole noise model (``D`` too) is kept: in wave roll without
#: sensor noise, re-fitting ``D`` to the residuals of every iterate lets the refined-IV iteration drift, iterate by
#: iterate, towards the degenerate minimum of :func:`shipid.methods.masscm.iteration.left_physical_region` (m growing
#: from 0.4 to 30 over 18 iterations); the later iterations are then IV with a fixed prefilter and updated
#: instruments (docs/validation/mass-cm.md).
FREEZE_AFTER = 3


def held_noise_model(eps: np.ndarray, options: MassCMOptions, L_prev) -> ARMA:
    """The noise model of a later iteration with the MA structure ``(c, k)`` of ``L_prev`` held (the choice
    between candidates, a discrete step, can otherwise keep the iteration from settling); D re-estimated."""
    return noise_model_bj(eps, options, (ma_structure(L_prev),))


__all__ = ["BJ_CANDIDATES", "FREEZE_AFTER", "ma_poly", "ma_structure", "noise_model_bj", "ar_polynomial",
           "held_noise_model"]
