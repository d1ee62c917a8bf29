"""The Whittle maximum-likelihood refinement (:mod:`shipid.methods.masscm.whittle`) applied to an Algorithm 1 result.

``MassCMOptions(refine="whittle")`` (Linder et al. 2015, seed 000, beyond the paper): as ``refine="pem"``
(:mod:`shipid.methods.masscm.pem_result`), with the frequency-domain likelihood, whose iterations cost the same
whatever the record length. With ``z_f`` known, the free parameters of (30), ``rho`` and the covariance of the
result are replaced by the refinement's, started from Algorithm 1's estimate; ``diagnostics["refine"]`` records the
method, the wave structure chosen, iterations, the Whittle log-likelihood and Algorithm 1's ``m, zm_bar, rho`` with
their standard errors. Where the refinement does not converge or ends outside the physical region the result keeps
Algorithm 1's estimate and one warning line says so.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from shipid.methods.masscm.whittle import FREE, WhittleOptions, refine
from shipid.models.roll_reduced import KnownParams
from shipid.result import Estimate, Result


def refine_result(result: Result, datasets, known: KnownParams, z_f: float | None,
                  options: WhittleOptions = WhittleOptions()) -> Result:
    """``result`` with the Whittle refinement's estimates (see the module docstring); needs ``z_f`` known.

    Same signature and return as :func:`shipid.methods.masscm.pem_result.refine_result`.
    """
    diag = result.diagnostics
    if z_f is None:
        diag.setdefault("warnings", []).append("refine=whittle needs z_f known: Algorithm 1's estimate is kept")
        diag["refine"] = {"method": "whittle", "applied": False, "reason": "z_f not known"}
        return result
    start = np.array([result.estimates[n].value for n in FREE])
    f = refine(list(datasets), known, z_f, start, options)
    rec = {"method": "whittle", "applied": bool(f.ok), "reason": f.reason, "waves": bool(f.waves),
           "iterations": int(f.iterations), "loglik": float(f.loglik),
           "algorithm1": {n: [float(result.estimates[n].value), float(result.estimates[n].std)]
                          for n in ("m", "zm_bar", "rho")}}
    diag["refine"] = rec
    if not f.ok:
        diag.setdefault("warnings", []).append(
            f"Whittle refinement not used ({f.reason}): Algorithm 1's estimate is kept")
        return result
    est = dict(result.estimates)
    se = np.sqrt(np.diag(f.cov))
    for k, n in enumerate(FREE):
        e = est[n]
        est[n] = Estimate(float(f.theta[k]), float(se[k]), e.unit, e.status, e.note)
    e = est["rho"]
    est["rho"] = Estimate(float(f.rho), float(f.rho_std), e.unit, e.status, e.note)
    return replace(result, estimates=est, covariance=np.array(f.cov), covariance_names=list(FREE))


__all__ = ["refine_result"]
