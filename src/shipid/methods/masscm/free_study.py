"""Monte Carlo of the noise-free roll-row estimator (:mod:`shipid.methods.masscm.crlb_free`) in the waves regime.

Each run draws the datasets of :func:`shipid.methods.masscm.coverage.run_one` for ``regime="waves"`` (0.5 deg wave
roll, noise-free sensors; ``SeedSequence([seed, i])``), runs Algorithm 1 (``refine="none"``, z_f known) and starts
:func:`shipid.methods.masscm.crlb_free.estimate_free` from its estimate. The summary is
:func:`shipid.methods.masscm.coverage.summarise` against :func:`shipid.methods.masscm.crlb_free.crlb_free`, through
the campaign engine (:func:`shipid.campaign.engine.run_campaign`). Measured figures: the docstring of
:mod:`shipid.methods.masscm.crlb_free`. The estimator needs the exact states (``how="exact"``, an oracle); it is
not an estimator for sampled data.
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from shipid.methods.masscm.coverage import QUANTITIES, REGIMES, summarise
from shipid.methods.masscm.crlb_free import FREE, crlb_free, estimate_free, realisation
from shipid.methods.masscm.estimator import MassCMOptions, estimate_mass_cm
from shipid.models.roll_reduced import KnownParams
from shipid.models.roll_sim import simulate_datasets
from shipid.campaign.engine import run_campaign
from shipid.vessels import load_vessel


def run_free_one(i: int, seed=0, *, duration: float = 300.0, how: str = "exact", vessel: str = "fishing-vessel",
                 start: str = "algorithm1", nyquist: str = "exact") -> dict:
    """One waves-regime realisation: Algorithm 1, then the noise-free ML; ``m, zm_bar, rho`` and standard errors
    of the latter (``iv_<name>``: Algorithm 1's), ``converged``, ``seconds`` (of the noise-free ML alone)."""
    ss = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence([int(seed), int(i)])
    fresh = lambda: np.random.SeedSequence(ss.entropy, spawn_key=ss.spawn_key)   # noqa: E731 (spawn() mutates)
    noise = REGIMES["waves"]
    known = KnownParams.from_vessel(vessel)
    z_f = float(load_vessel(vessel).value("general", "z_f"))
    out = {}
    th0 = None
    if start == "algorithm1":
        d = simulate_datasets(vessel, seed=fresh(), duration=duration, noise=noise)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = estimate_mass_cm(list(d.items()), known, z_f=z_f, noise_check=False,
                                 options=MassCMOptions(refine="none"))
        th0 = np.array([r.value(n) for n in FREE])
        for k in QUANTITIES:
            out[f"iv_{k}"], out[f"iv_{k}_std"] = float(r.value(k)), float(r.std(k))
    data = realisation(vessel, seed=fresh(), duration=duration, noise=noise)
    t0 = time.process_time()
    f = estimate_free(data, vessel, theta0=th0, how=how, nyquist=nyquist)
    out["seconds"] = time.process_time() - t0
    for k in QUANTITIES:
        out[k], out[f"{k}_std"] = f[k]["value"], f[k]["std"]
    out.update({"converged": bool(f["success"]), "implausible": False, "nuisance_outside_physical": False,
                "nfev": f["nfev"], "wave": f["wave"].tolist()})
    return out


def free_study(runs: int, seed: int, *, duration: float = 300.0, how: str = "exact", workers: int = 1,
               n_rudder: int = 8, store=None, nyquist: str = "exact") -> dict:
    """Summary of ``runs`` realisations (see the module docstring), with the bound of ``n_rudder`` realisations."""
    res = run_campaign(run_free_one, runs, seed, kwargs={"duration": duration, "how": how, "nyquist": nyquist},
                       workers=workers, store=store, progress=False, name=f"free-{how}-{nyquist}-{duration:g}")
    b = crlb_free(duration=duration, n_rudder=n_rudder, how=how, seed=seed)
    bound = {k: b["bounds"][k] for k in QUANTITIES}
    bound["definition"] = b["definition"]
    outs = res.outputs
    s = summarise(outs, regime="waves", duration=duration, bound=bound)
    ok = [o for o in outs if o is not None]
    s["seconds_per_estimate"] = float(np.median([o["seconds"] for o in ok])) if ok else float("nan")
    if ok and "iv_m" in ok[0]:
        s["algorithm1_spread"] = {k: float(np.std([o[f"iv_{k}"] for o in ok], ddof=1)) for k in QUANTITIES}
    s["estimator"] = f"crlb_free.estimate_free(how={how!r}, nyquist={nyquist!r})"
    return s


__all__ = ["run_free_one", "free_study"]
