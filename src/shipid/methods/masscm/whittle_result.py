"""The Whittle maximum-likelihood refinement (:mod:`shipid.methods.masscm.whittle`) applied to an Algorithm 1 result.

``MassCMOptions(refine="whittle")`` (Linder et al. 2015, beyond the paper): as ``refine="pem"``
(:mod:`shipid.methods.masscm.pem_result`), with the frequency-domain likelihood, whose iterations cost the same
whatever the record length. With ``z_f`` known, the free parameters of (30), ``rho`` and the covariance of the
result are replaced by the refinement's, started from Algorithm 1's estimate; ``diagnostics["refine"]`` records the
method, the wave structure chosen, iterations, the Whittle log-likelihood and Algorithm 1's ``m, zm_bar, rho`` with
their standard errors. Where the refinement does not converge or ends outside the physical region the result keeps
Algorithm 1's estimate and one warning line says so.
"""

from __future__ import annotations

from shipid.methods.masscm.pem_result import apply_fit
from shipid.methods.masscm.whittle import WhittleOptions, refine
from shipid.models.roll_reduced import KnownParams
from shipid.result import Result


def refine_result(result: Result, datasets, known: KnownParams, z_f: float | None,
                  options: WhittleOptions = WhittleOptions()) -> Result:
    """``result`` with the Whittle refinement's estimates (see the module docstring); needs ``z_f`` known.

    Same signature and return as :func:`shipid.methods.masscm.pem_result.refine_result`.
    """
    return apply_fit(result, datasets, known, z_f, "whittle", "Whittle",
                     lambda d, s: refine(d, known, z_f, s, options))


__all__ = ["refine_result"]
