"""Noise models and prefilters of Algorithm 1 (Linder et al. 2015, steps A(a) and B(b), eqs. 42–43).

The residuals (42) get a noise model whose inverse is the prefilter ``L`` (43) of the next iteration:
``"ar"`` AR(p) by least squares, ``L = A(q)``; ``"ar-structured"`` AR(p) of ``eps / (1 - c q^-2)``,
``L = A(q)/(1 - c q^-2)``; ``"arma"`` a structured ARMA by Hannan–Rissanen; ``"auto"`` (default) and ``"bj"``
the Box–Jenkins model ``(1 - c q^-2)^k / D(q)`` of :mod:`shipid.methods.masscm.noise_bj`, ``(c, k)`` with the
smallest innovation variance among :data:`~shipid.methods.masscm.noise_bj.BJ_CANDIDATES` (the refined-IV noise
model of Young, Automatica 52, 2015). The first iteration uses ``L = 1/(1 - c q^-2)``
(:func:`initial_prefilter`; the paper: ``L = 1``).
"""

from __future__ import annotations

import numpy as np

from shipid.estimate.arma import ARMA, fit_ar, hannan_rissanen
from shipid.numerics.iir_kernels import lfilter
from shipid.methods.masscm.noise_bj import noise_model_bj
from shipid.methods.masscm.options import MassCMOptions

def initial_prefilter(options: MassCMOptions):
    """Prefilter of the first iteration (step A(a)).

    The paper sets ``L = 1``. Our choice (*): ``L = 1/(1 - c q^-2)`` with ``c = options.initial_c``
    (0.99 by default; 0 gives the paper's ``L = 1``). Reason: the disturbance and the noise on
    ``a_s``, ``r`` enter (35) through the same ``(1 - q^-2)`` factor as the inputs (bilinear transform
    of a moment entering (23)), so the equation error has almost no power at low frequencies where the
    rudder response lives. With ``L = 1`` the first criterion is dominated by high-frequency wave noise
    and can prefer the trivial "smooth signal" relation ``y_t ~ 2 y_{t-1} - y_{t-2}``, from which the
    ARMA iterations never recover; this prefilter approximates the final ARMA prefilter instead.
    """
    if not options.prefilter or options.initial_c == 0:
        return None
    return ARMA(np.ones(1), np.array([1.0, 0.0, -options.initial_c]), 1.0)


def fit_noise_model(eps: np.ndarray, options: MassCMOptions):
    """ARMA noise model of the residuals (42) and its inverse as prefilter (43).

    (*) The disturbance and the a_s / r noise reach the equation error through ``(1 - q^-2)``
    (zeros on the unit circle, which a Hannan–Rissanen fit cannot invert). We therefore fit the
    ARMA(na, nc) model to ``eps / (1 - c q^-2)`` (``c = options.initial_c``) and use
    ``L = A / (C (1 - c q^-2))``; with ``c = 0`` this is the plain ARMA prefilter of the paper.
    """
    if options.noise_model in ("auto", "bj"):
        return noise_model_bj(eps, options)
    if options.noise_model == "ar":
        if options.compute == "fast":
            return fit_ar(eps, options.ar_order)         # the same AR fit by compiled kernels
        return hannan_rissanen(eps, options.ar_order, 0, n_long=options.ar_order)
    c = options.initial_c
    if options.noise_model == "ar-structured" and c != 0:
        # (*) the AR(ar_order) model of eps / (1 - c q^-2), prefilter L = A / (1 - c q^-2): the unit-circle
        # zeros of (1 - q^-2) are divided out before the AR fit, as in the structured ARMA below
        den = np.array([1.0, 0.0, -c])
        e2 = lfilter([1.0], den, eps)
        m = (fit_ar(e2, options.ar_order) if options.compute == "fast"
             else hannan_rissanen(e2, options.ar_order, 0, n_long=options.ar_order))
        return ARMA(m.a, den, m.lam)
    if c == 0:
        return hannan_rissanen(eps, options.arma_na, options.arma_nc)
    den = np.array([1.0, 0.0, -c])
    e2 = lfilter([1.0], den, eps)
    m = hannan_rissanen(e2, options.arma_na, options.arma_nc)
    return ARMA(m.a, np.convolve(m.c, den), m.lam)


#: From this iteration on the ``"auto"`` noise model keeps each dataset's ``(c, k)`` of the previous iteration (the
#: choice between candidates, a discrete step, otherwise can keep an iteration from settling).
AUTO_HOLD = 3


__all__ = ["initial_prefilter", "fit_noise_model", "AUTO_HOLD"]
