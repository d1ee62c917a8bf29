"""Sensitivity to initial values: the Monte Carlo study of Linder et al. (2015) §5, Table 3.

The three datasets are synthesised once per process (seeded, noise-free, 60 s at 50 Hz) and the
black-box instruments of the initialising iteration (which do not depend on the initial values) are
built once (:func:`prepared`, :func:`initial_moments`); each run then draws the nine initial values uniformly
between the sensible Table 3 bounds (the printed U/L rows are swapped for K_delta, K_r and zm_bar: we use each
parameter's [min, max], see the vessel file ``[table3_bounds]``) and runs Algorithm 1.

``z_f`` handling (``zf_mode``):

* ``"known"`` (default): z_f is given (its true value), as the identifiability analysis requires
  for ``m`` to mean anything; its initial draw is ignored.
* ``"free"``: as in the paper, z_f is estimated; the exact-fit family is flat in z_f, so the
  reported m is where the search stopped (see :mod:`shipid.methods.masscm.estimator`).

Implausible-solution rule (counted apart, not in the means): :func:`shipid.methods.masscm.estimator.implausible_reasons`
(m <= 1e-6 M, |zm_bar| > 10 m, A_x <= 0, d <= 0, k - K_vdot g <= 0, A1 or A2 <= 0 in any dataset, non-finite), or a run
that did not converge. The summary counts ``flagged_reasons`` (how often each rule fired) and
``not_converged_settled`` (runs flagged only as not converged whose zm_bar and rho vary by less than 1e-4 relative
over the last 10 iterates, :func:`_identifiable_drift`).

Measured figures, with the commands that regenerate them: ``docs/validation/mass-cm.md``.

:func:`run_one` uses the compiled path (``compute="fast"``: :mod:`shipid.methods.masscm.step`,
:mod:`shipid.methods.masscm.search`, :mod:`shipid.estimate.fir_kernels`); the same Algorithm 1 as the reference
path, compared run by run in the tests (largest per-run difference of m 2.8e-7, the study's own spread 9e-8).
Timings are printed by ``benchmarks/bench_masscm_study.py``. The numba kernels are compiled once per machine
(cached on disk, ``cache=True``) and loaded by each worker; :func:`warm_up` does that before a campaign.

:func:`run_one` is the per-run task, with the campaign-engine signature
``run_one(i, seedseq, **kwargs) -> dict`` (:mod:`shipid.campaign.engine`).
"""

from __future__ import annotations

import copy
import functools
import time
import warnings
from dataclasses import replace

import numpy as np

from shipid.numerics.linalg import one_blas_thread
from shipid.methods.masscm.estimator import (MassCMOptions, estimate_mass_cm, implausible_reasons, initial_state,
                                             iterate, prepare, rho_of)
from shipid.models.roll_reduced import THETA_NAMES, KnownParams
from shipid.models.roll_sim import NoiseSpec, simulate_datasets
from shipid.vessels import load_vessel

#: Order of parameters in Table 3.
TABLE3_ORDER = ("A_x", "d", "k", "K_delta", "K_r", "K_vdot", "z_f", "m", "zm_bar")
_NAME_MAP = {"K_delta": "K_delta", "K_r": "K_r", "K_vdot": "K_vdot"}
_CACHE: dict = {}


@functools.lru_cache(maxsize=4)
def _zf_true(vessel: str) -> float:
    return float(load_vessel(vessel).value("general", "z_f"))


@functools.lru_cache(maxsize=4)
def table3(vessel: str = "fishing-vessel") -> dict:
    """True values, bounds and published mean/std of Table 3 from the vessel file."""
    v = load_vessel(vessel)
    return {n: {"true": float(v.value("table3_true", n)),
                "bounds": [float(x) for x in v.value("table3_bounds", n)],
                "paper_mean": float(v.value("table3_result", n)[0]),
                "paper_std": float(v.value("table3_result", n)[1])} for n in TABLE3_ORDER}


@functools.lru_cache(maxsize=16)
def _key(data_seed: int, vessel: str, options: MassCMOptions):
    # ``compute`` changes how the iterations are computed, not the datasets or the first-iteration state
    # (whose prefilter is not FIR), so both ways share one cache entry
    return (data_seed, vessel, replace(options, compute="fast"))


def prepared(data_seed: int, vessel: str, options: MassCMOptions):
    key = _key(data_seed, vessel, options)
    if key not in _CACHE:
        d = simulate_datasets(vessel, seed=data_seed)
        _CACHE.clear()
        prep = prepare(list(d.items()), options)
        _CACHE[key] = (prep, KnownParams.from_vessel(vessel), initial_state(prep, options))
    return _CACHE[key][:2]


def initial_moments(data_seed: int, vessel: str, options: MassCMOptions):
    """First-iteration IV moments of the cached datasets (independent of the initial values)."""
    prepared(data_seed, vessel, options)
    return _CACHE[_key(data_seed, vessel, options)][2]



def draw_initial(rng: np.random.Generator, vessel: str = "fishing-vessel") -> np.ndarray:
    """Initial values uniform between the Table 3 bounds, in :data:`THETA_NAMES` order."""
    t3 = table3(vessel)
    return np.array([rng.uniform(*t3[n]["bounds"]) for n in THETA_NAMES])



@functools.lru_cache(maxsize=8)
def _run_options(max_iter: int, compute: str) -> MassCMOptions:
    """The options of :func:`run_one` (a frozen dataclass, made once)."""
    return MassCMOptions(max_iter=max_iter, compute=compute, noise_model="ar")


def run_one(i: int, seed=0, *, zf_mode: str = "known", data_seed: int = 0, init: str = "given",
            vessel: str = "fishing-vessel", max_iter: int = 50, compute: str = "fast") -> dict:
    """One Monte Carlo run: draw initial values from ``SeedSequence([seed, i])`` and run Algorithm 1.

    ``seed`` may be an int (the campaign seed) or the run's ``SeedSequence`` (campaign engine).
    Returns the estimates (physical parameters), ``converged``, ``iterations``, ``implausible``.
    ``compute``: ``"fast"`` (compiled kernels) or ``"reference"`` (the straightforward numpy/scipy path);
    how Algorithm 1 is computed, not what (:class:`~shipid.methods.masscm.estimator.MassCMOptions`).
    """
    ss = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence([int(seed), int(i)])
    rng = np.random.default_rng(ss)
    # the paper's noise-free protocol with the AR(40) noise model (the fused compiled path; Table 3 as measured)
    options = _run_options(max_iter, compute)
    with one_blas_thread():      # the cached datasets too: their AR fits must not depend on the BLAS threads
        prep, known = prepared(data_seed, vessel, options)
        state0 = initial_moments(data_seed, vessel, options)
        theta0 = draw_initial(rng, vessel)
        z_f = _zf_true(vessel) if zf_mode == "known" else None
        out = _iterate_one(prep, known, theta0, z_f, options, init, state0)
    out["theta0"] = [float(x) for x in theta0]
    return out


def _iterate_one(prep, known, theta0, z_f, options, init, state0) -> dict:
    """Algorithm 1 from ``theta0`` (:func:`iterate`, warnings silenced) and the run's record of :func:`run_one`
    (without ``theta0``)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            core = iterate(prep, known, theta0, z_f=z_f, options=options, init=init,
                           state0=state0, jacobian=False)
            theta = core["theta"]
            conv, its = bool(core["converged"]), int(core["iterations"])
            drift = _identifiable_drift(core["history"], known)
        except (np.linalg.LinAlgError, ValueError) as err:     # recorded as implausible, never a crash
            theta = np.full(len(THETA_NAMES), np.nan)
            conv, its = False, 0
            drift = float("nan")
            why = [f"{type(err).__name__}: {err}"]
        else:
            why = implausible_reasons(theta, known)
    out = {n: float(theta[k]) for k, n in enumerate(THETA_NAMES)}
    out.update({"converged": conv, "iterations": its, "implausible": bool(why) or not conv,
                "reasons": why + ([] if conv else ["not converged"]), "identifiable_drift": drift})
    return out


def _identifiable_drift(history: np.ndarray, known, last: int = 10) -> float:
    """Largest relative range of the identifiable zm_bar and rho = m z_m/(m_c z_c) over the last iterates.

    A diagnostic only (it changes no count): a run that stops at ``max_iter`` with a small value has its
    identifiable results settled while the iteration cycles in nuisance coefficients.
    """
    h = np.asarray(history, dtype=float)[-last:]
    if h.size == 0 or not np.all(np.isfinite(h)):
        return float("nan")
    zm = h[:, THETA_NAMES.index("zm_bar")]
    rho = np.array([rho_of(t, known) for t in h])
    return float(max(np.ptp(zm) / max(abs(zm.mean()), 1e-300), np.ptp(rho) / max(abs(rho.mean()), 1e-300)))


def warm_up(data_seed: int = 0, vessel: str = "fishing-vessel", **_run_kwargs) -> float:
    """Compile the numba kernels of the fast path (or load them from numba's on-disk cache) and build this
    process's dataset cache, by one run; returns the seconds it took.

    The campaign's ``warm_up`` (:func:`shipid.campaign.engine.run_campaign`; it passes the campaign's
    kwargs, of which only ``data_seed`` and ``vessel`` matter here): it runs in the parent first, so the
    first compilation (tens of seconds) happens once and writes the cache, then once in the forkserver
    the workers are forked from, so that no worker pays the ~1.6 s of imports, cache loading and dataset
    synthesis itself. The run it makes changes no later run (the caches are keyed by their inputs).
    """
    t0 = time.perf_counter()
    run_one(0, 0, data_seed=data_seed, vessel=vessel)
    return time.perf_counter() - t0


def summarise(outputs: list[dict], *, vessel: str = "fishing-vessel", zf_mode: str = "known",
              wall_s: float = float("nan")) -> dict:
    """Table-3 style summary: per parameter true, mean, std, bounds (plausible runs only)."""
    t3 = copy.deepcopy(table3(vessel))
    ok = [o for o in outputs if o is not None and not o["implausible"]]
    flagged = sum(1 for o in outputs if o is None or o["implausible"])
    params = {}
    for n in TABLE3_ORDER:
        vals = np.array([o[n] for o in ok], dtype=float)
        params[n] = {"true": t3[n]["true"], "mean": float(vals.mean()) if vals.size else float("nan"),
                     "std": float(vals.std(ddof=1)) if vals.size > 1 else float("nan"),
                     "bounds": t3[n]["bounds"], "paper_mean": t3[n]["paper_mean"],
                     "paper_std": t3[n]["paper_std"]}
    its = [o["iterations"] for o in ok]
    reasons: dict[str, int] = {}
    for o in outputs:                     # how often each rule fired (a run may trip several)
        for why in (["no result"] if o is None else o.get("reasons", [])):
            reasons[why] = reasons.get(why, 0) + 1
    return {"study": "mass-cm-sensitivity", "paper": "Linder et al. 2015, Table 3", "zf_mode": zf_mode,
            "runs": len(outputs), "flagged": flagged, "flagged_reasons": reasons,
            # of the runs flagged only as not converged: zm_bar and rho settled to 1e-4 over the last 10 iterates
            "not_converged_settled": sum(1 for o in outputs if o is not None and o["reasons"] == ["not converged"]
                                         and o.get("identifiable_drift", np.nan) < 1e-4),
            "used": len(ok), "parameters": params,
            "mean_iterations": float(np.mean(its)) if its else float("nan"), "wall_s": wall_s,
            "implausible_rule": ("m <= 1e-6 M, |zm_bar| > 10 m, A_x <= 0, d <= 0, k - K_vdot g <= 0, A1 or A2 <= 0 in any dataset, "
                                 "non-finite, or not converged")}





def efficiency_run(i: int, seed=0, *, duration: float = 300.0, prefilter: bool = True,
                   instruments: str = "lags", vessel: str = "fishing-vessel") -> dict:
    """One noise realisation of the efficiency check (combined wave and sensor noise) of Algorithm 1 (beyond the paper; no refinement).

    Three datasets of ``duration`` s with :meth:`NoiseSpec.combined` noise (white gyro / accelerometer
    noise, constant biases, 0.5 deg wave roll), z_f known, linear initialisation; returns the
    estimates of m, zm_bar, rho with their standard errors.
    """
    ss = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence([int(seed), int(i)])
    d = simulate_datasets(vessel, seed=ss, duration=duration, noise=NoiseSpec.combined())
    known = KnownParams.from_vessel(vessel)
    z_f = float(load_vessel(vessel).value("general", "z_f"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = estimate_mass_cm(list(d.items()), known, z_f=z_f, noise_check=False,   # Algorithm 1 alone
                             options=MassCMOptions(prefilter=prefilter, instruments=instruments, refine="none"))
    out = {k: r.value(k) for k in ("m", "zm_bar", "rho", "k", "A_x", "d", "K_r", "K_vdot", "K_delta")}
    out.update({f"{k}_std": r.std(k) for k in ("m", "zm_bar", "rho")})
    out.update({"converged": r.diagnostics["converged"], "iterations": r.diagnostics["iterations"],
                "implausible": r.diagnostics["implausible"],
                "nuisance_outside_physical": bool(r.diagnostics.get("nuisance_outside_physical"))})
    return out
__all__ = ["run_one", "warm_up", "efficiency_run", "summarise", "table3", "draw_initial", "TABLE3_ORDER"]
