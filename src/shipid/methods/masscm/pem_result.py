"""The maximum-likelihood refinement (:mod:`shipid.methods.masscm.pem`) applied to an Algorithm 1 result.

``MassCMOptions(refine="pem")`` (Linder et al. 2015, beyond the paper): with ``z_f`` known, the free
parameters of (30), ``rho`` and the covariance of the result are replaced by the refinement's, started from
Algorithm 1's estimate; ``diagnostics["refine"]`` records the method, the wave structure chosen, iterations and the
log-likelihood, and Algorithm 1's ``m, zm_bar, rho`` with their standard errors. Where the refinement does not
converge or ends outside the physical region the result keeps Algorithm 1's estimate and one warning line says so.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from shipid.methods.masscm.pem import FREE, PEMOptions, refine
from shipid.models.roll_reduced import KnownParams
from shipid.result import Estimate, Result


def refine_result(result: Result, datasets, known: KnownParams, z_f: float | None,
                  options: PEMOptions = PEMOptions()) -> Result:
    """``result`` with the PEM refinement's estimates (see the module docstring); needs ``z_f`` known."""
    return apply_fit(result, datasets, known, z_f, "pem", "PEM", lambda d, s: refine(d, known, z_f, s, options))


def apply_fit(result: Result, datasets, known: KnownParams, z_f: float | None, method: str, label: str,
              fit) -> Result:
    """``result`` with the estimates of ``fit(datasets, start) -> PEMFit`` (a refinement engine started from
    Algorithm 1's free ``theta``), recorded as ``method`` in ``diagnostics["refine"]``; a fit that fails, or
    ``z_f`` unknown, keeps Algorithm 1's estimate with one warning line naming ``label``."""
    diag = result.diagnostics
    if z_f is None:
        diag.setdefault("warnings", []).append(f"refine={method} needs z_f known: Algorithm 1's estimate is kept")
        diag["refine"] = {"method": method, "applied": False, "reason": "z_f not known"}
        return result
    start = np.array([result.estimates[n].value for n in FREE])
    f = fit(list(datasets), start)
    rec = {"method": method, "applied": bool(f.ok), "reason": f.reason, "waves": bool(f.waves),
           "iterations": int(f.iterations), "loglik": float(f.loglik),
           "algorithm1": {n: [float(result.estimates[n].value), float(result.estimates[n].std)]
                          for n in ("m", "zm_bar", "rho")}}
    diag["refine"] = rec
    if not f.ok:
        diag.setdefault("warnings", []).append(
            f"{label} refinement not used ({f.reason}): Algorithm 1's estimate is kept")
        return result
    est = dict(result.estimates)
    se = np.sqrt(np.diag(f.cov))
    for k, n in enumerate(FREE):
        e = est[n]
        est[n] = Estimate(float(f.theta[k]), float(se[k]), e.unit, e.status, e.note)
    e = est["rho"]
    est["rho"] = Estimate(float(f.rho), float(f.rho_std), e.unit, e.status, e.note)
    return replace(result, estimates=est, covariance=np.array(f.cov), covariance_names=list(FREE))


__all__ = ["refine_result", "apply_fit"]
