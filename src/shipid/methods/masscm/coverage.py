"""Coverage study of Algorithm 1 (Linder et al. 2015) per noise regime: bias, spread, bound, coverage.

Beyond the paper (whose §5 study is noise-free): Monte Carlo on the campaign engine
(:func:`shipid.campaign.engine.run_campaign`) over fresh noise realisations. Each run synthesises the
three datasets (nominal, calibration, loaded; :func:`shipid.models.roll_sim.simulate_datasets`, seed
``SeedSequence([seed, i])``: a new rudder and noise realisation per run) of ``duration`` s at 50 Hz in
one regime:

* ``waves``: 0.5 deg wave roll (1-s peak period, relative damping 0.1), noise-free sensors;
* ``sensors``: white gyro noise 0.002 rad/s, accelerometer noise 0.02 m/s^2, biases 0.001 rad/s and
  0.01 m/s^2, no waves;
* ``both``: the two together (the combined wave and sensor noise, :meth:`~shipid.models.roll_sim.NoiseSpec.combined`).

and runs :func:`shipid.methods.masscm.estimator.estimate_mass_cm` with z_f known (the vessel file's value), the
linear initialisation and the options given (the estimator is told neither the noise levels nor the true
parameters). Per quantity (``m`` with z_f known, ``zm_bar``, ``rho``) the summary gives the true value, the
mean, the bias and its Monte Carlo standard error, the spread (std over runs), the mean reported standard
error, the coverage of the ±2-std interval (with its binomial standard error), and the spread over the
bound of :func:`shipid.methods.masscm.crlb.crlb` for the same regime and record length (with the
relative standard error of a spread, ``1/sqrt(2 (n-1))``). Runs flagged implausible or not converged are
counted; ``quantities`` are over all runs that returned finite estimates (flagging is reported, not used
to drop runs, so that coverage is not flattered), ``quantities_unflagged`` over the converged, unflagged ones.

Measured figures, with the commands that regenerate them: ``docs/validation/mass-cm.md``.
"""

from __future__ import annotations

import functools
import math
import time
import warnings

import numpy as np

from shipid.methods.masscm.crlb import crlb, true_theta
from shipid.methods.masscm.estimator import MassCMOptions, estimate_mass_cm
from shipid.methods.masscm.refine import REFINE_MODES
from shipid.methods.masscm.refine import apply as apply_refine
from shipid.models.roll_reduced import THETA_NAMES, KnownParams
from shipid.models.roll_sim import NoiseSpec, simulate_datasets
from shipid.vessels import load_vessel

#: The noise of each regime (see the module docstring).
REGIMES = {
    "waves": NoiseSpec(wave_roll_deg=0.5),
    "sensors": NoiseSpec(gyro_std=0.002, acc_std=0.02, gyro_bias=0.001, acc_bias=0.01),
    "both": NoiseSpec.combined(),
}
QUANTITIES = ("m", "zm_bar", "rho")
NUISANCE = ("K_vdot", "K_r", "K_delta")


@functools.lru_cache(maxsize=4)
def _truth(vessel: str) -> dict:
    th = true_theta(vessel)
    known = KnownParams.from_vessel(vessel)
    z_f, m, zm = (th[THETA_NAMES.index(n)] for n in ("z_f", "m", "zm_bar"))
    return {"z_f": float(z_f), "m": float(m), "zm_bar": float(zm),
            "rho": float(m * (zm + z_f) / (known.m_c * (known.zc_bar + z_f)))}


def run_one(i: int, seed=0, *, regime: str = "both", duration: float = 300.0, vessel: str = "fishing-vessel",
            noise_model: str | None = None, compute: str = "fast", refine: str = "auto") -> dict:
    """One realisation: datasets from ``SeedSequence([seed, i])`` in ``regime``, then Algorithm 1 (z_f known).

    Returns ``m, zm_bar, rho`` and their standard errors, ``K_vdot, K_r, K_delta``, ``converged``,
    ``implausible`` (with ``implausible_reasons``), ``nuisance_outside_physical``, ``iterations``.
    ``noise_model`` is Algorithm 1's (``None``: the estimator's default, as ``study mass-cm-coverage`` runs it).
    ``compute`` is how Algorithm 1 is computed, not what (:class:`~shipid.methods.masscm.estimator.MassCMOptions`).
    ``refine`` (:data:`shipid.methods.masscm.refine.REFINE_MODES`): ``"auto"`` (the estimator's default) refines
    where the rule of :mod:`shipid.methods.masscm.refine` says so, ``"pem"`` always by
    :mod:`shipid.methods.masscm.pem`; ``refine_decision`` is the engine the rule chose (``"none"`` or one), and
    where a refinement ran ``pem_ok`` / ``pem_reason`` say whether it was used (else the run keeps Algorithm 1's
    estimate). Algorithm 1's own ``m, zm_bar, rho`` and standard errors are kept as ``iv_<name>``.
    """
    if regime not in REGIMES:
        raise ValueError(f"regime must be one of {', '.join(REGIMES)}")
    if refine not in REFINE_MODES:
        raise ValueError(f"refine must be one of {', '.join(REFINE_MODES)}")
    noise_model = MassCMOptions().noise_model if noise_model is None else noise_model
    ss = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence([int(seed), int(i)])
    d = simulate_datasets(vessel, seed=ss, duration=duration, noise=REGIMES[regime])
    known = KnownParams.from_vessel(vessel)
    z_f = float(load_vessel(vessel).value("general", "z_f"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = estimate_mass_cm(list(d.items()), known, z_f=z_f, noise_check=False,
                             options=MassCMOptions(noise_model=noise_model, compute=compute, refine="none"))
    iv = {k: (float(r.value(k)), float(r.std(k))) for k in QUANTITIES}
    rr = apply_refine(r, list(d.items()), known, z_f, refine)
    out = {}
    for k in QUANTITIES:
        out[k], out[f"{k}_std"] = float(rr.value(k)), float(rr.std(k))
        out[f"iv_{k}"], out[f"iv_{k}_std"] = iv[k]
    rec = rr.diagnostics["refine"]
    out["refine_decision"] = rec["decision"]
    if rec["decision"] != "none":
        out.update({"pem_ok": rec["applied"], "pem_reason": rec["reason"], "pem_waves": rec.get("waves"),
                    "pem_iterations": rec.get("iterations")})
    if refine == "auto":
        out["sensor_level"] = rec["sensor_test"]["level"]
    for k in NUISANCE:                   # weakly determined (finite-sample IV bias): reported, not judged
        out[k] = float(r.value(k))
    out.update({"converged": bool(r.diagnostics["converged"]), "iterations": int(r.diagnostics["iterations"]),
                "implausible": bool(r.diagnostics["implausible"]),
                "implausible_reasons": list(r.diagnostics.get("implausible_reasons", [])),
                "nuisance_outside_physical": bool(r.diagnostics.get("nuisance_outside_physical")),
                "noise_model": r.diagnostics.get("noise_model_selected", noise_model)})
    return out


def warm_up(**_kwargs) -> float:
    """Compile / load the numba kernels once (campaign ``warm_up``); returns the seconds it took."""
    t0 = time.perf_counter()
    run_one(0, 0, regime="sensors", duration=60.0)
    return time.perf_counter() - t0


def summarise(outputs: list, *, regime: str, duration: float, vessel: str = "fishing-vessel",
              bound: dict | None = None) -> dict:
    """Bias, spread, spread/bound and ±2-std coverage per quantity (see the module docstring)."""
    ok = [o for o in outputs if o is not None]
    fin = [o for o in ok if all(np.isfinite(o[k]) and np.isfinite(o[f"{k}_std"]) for k in QUANTITIES)]
    good = [o for o in fin if o["converged"] and not o["implausible"]]
    return {"study": "mass-cm-coverage", "regime": regime, "noise": REGIMES[regime].__dict__,
            "duration_s": duration, "runs": len(outputs), "failed": len(outputs) - len(ok), "used": len(fin),
            "flagged_implausible": sum(1 for o in ok if o["implausible"]),
            "flag_rate": _rate(sum(1 for o in ok if o["implausible"]), len(ok)),
            "nuisance_outside_physical": sum(1 for o in ok if o.get("nuisance_outside_physical")),
            "not_converged": sum(1 for o in ok if not o["converged"]),
            "quantities": _stats(fin, vessel, bound),
            # the same over the runs the estimator itself reports as usable (converged, not flagged): what a
            # user who heeds the flags gets; coverage over all runs above is the honest headline
            "used_unflagged": len(good), "quantities_unflagged": _stats(good, vessel, bound),
            "bound_definition": None if bound is None else bound.get("definition")}


def _stats(fin: list, vessel: str, bound: dict | None) -> dict:
    truth = _truth(vessel)
    n = len(fin)
    q = {}
    for k in QUANTITIES:
        v = np.array([o[k] for o in fin], dtype=float)
        s = np.array([o[f"{k}_std"] for o in fin], dtype=float)
        spread = float(v.std(ddof=1)) if n > 1 else float("nan")
        mad = float(1.4826 * np.median(np.abs(v - np.median(v)))) if n > 1 else float("nan")
        cov = float(np.mean(np.abs(v - truth[k]) <= 2 * s)) if n else float("nan")
        b = None if bound is None else float(bound[k]["std"])
        q[k] = {"true": truth[k], "mean": float(v.mean()) if n else float("nan"),
                "bias": float(v.mean() - truth[k]) if n else float("nan"),
                "bias_se": spread / math.sqrt(n) if n > 1 else float("nan"),
                "spread": spread, "mean_std": float(s.mean()) if n else float("nan"),
                "coverage_2std": cov,
                "coverage_se": math.sqrt(max(cov * (1 - cov), 0.25 / max(n, 1)) / n) if n else float("nan"),
                "bound": b, "spread_over_bound": spread / b if b else None,
                "spread_over_bound_rel_se": 1 / math.sqrt(2 * (n - 1)) if n > 1 else None,
                "spread_over_bound_ci95": _ratio_ci(spread / b, n) if b and n > 1 else None,
                # outlier-resistant: 1.4826 x the median absolute deviation (= the std for Gaussian estimates;
                # its sampling error is ~1.65x that of the std, so the chi-square interval above is too narrow for it)
                "spread_mad": mad, "spread_mad_over_bound": mad / b if b and n > 1 else None,
                "mean_within_one_spread": bool(abs(v.mean() - truth[k]) <= spread) if n > 1 else None}
    return q


def _rate(k: int, n: int) -> dict:
    """Share ``k/n`` of flagged runs with its one-sided 95 % Clopper-Pearson upper limit."""
    from scipy.stats import beta
    upper = 1.0 if k >= n else float(beta.ppf(0.95, k + 1, n - k))
    return {"flagged": k, "of": n, "rate": k / n if n else float("nan"), "upper95": upper if n else float("nan")}


def _ratio_ci(ratio: float, n: int) -> list:
    """95 % interval of sigma/bound from a sample spread over ``n`` runs: ``(n-1) s^2 / sigma^2 ~ chi2(n-1)``."""
    from scipy.stats import chi2
    lo, hi = chi2.ppf([0.975, 0.025], n - 1)
    return [float(ratio * math.sqrt((n - 1) / lo)), float(ratio * math.sqrt((n - 1) / hi))]


def bound_for(regime: str, duration: float, vessel: str = "fishing-vessel", seed: int = 0) -> dict:
    """Bounds on ``m, zm_bar, rho`` for the regime (:func:`shipid.methods.masscm.crlb.crlb`)."""
    b = crlb(vessel, duration=duration, noise=REGIMES[regime], seed=seed)
    out = {k: b["bounds"][k] for k in QUANTITIES}
    out["definition"] = b.get("definition")
    return out


__all__ = ["REGIMES", "QUANTITIES", "run_one", "warm_up", "summarise", "bound_for"]
