"""Sensitivity to initial values: the Monte Carlo study of Linder et al. (2015) §5, Table 3.

The three datasets are synthesised once per process (seeded, noise-free, 60 s at 50 Hz) and the
black-box instruments of the initialising iteration (which do not depend on the initial values) are
built once; each run then draws the nine initial values uniformly between the sensible Table 3
bounds (the printed U/L rows are swapped for K_delta, K_r and zm_bar: we use each parameter's
[min, max], see the vessel file ``[table3_bounds]``) and runs Algorithm 1.

``z_f`` handling (``zf_mode``):

* ``"known"`` (default): z_f is given (its true value), as our identifiability analysis requires
  for ``m`` to mean anything; its initial draw is ignored.
* ``"free"``: as in the paper, z_f is estimated; the exact-fit family is flat in z_f, so the
  reported m is where the search stopped (see the method's notes).

Implausible-solution rule (counted apart, not in the means): :func:`shipid.methods.masscm.estimator.implausible_reasons`
(m <= 1e-6 M, |zm_bar| > 10 m, A_x <= 0, d <= 0, k - K_vdot g <= 0, A1 or A2 <= 0 in any dataset, non-finite), or a run
that did not converge.

Measured (data seed 0, campaign seed 1; ``shipid study mass-cm-sensitivity --json``):

* z_f known, initial values from the Table 3 bounds, 10 000 runs (2026-11-22, compiled path): 0 flagged;
  m 0.3997776 (std 9.6e-8), zm_bar -0.1820948 (std 4.2e-8), 6.42 iterations on average; every run
  reaches the same solution (the 0.05 % offsets are the bilinear-discretisation error of (32)). The
  reference path (the implementation before the compiled one, commit af299ce) gives the same per run
  (600 runs: m 0.3997776 ± 9.0e-8, largest per-run difference 2.8e-7); session 1 had printed
  m 0.399779 ± 2e-8, zm_bar -0.182094 ± 9e-9 from an earlier state of the code.
  Table 3: m 0.4007 ± 0.0018, zm_bar -0.1821 ± 0.0004.
* z_f free (paper setting), ``shipid study mass-cm-sensitivity --z-f free --init given --runs 200 --seed 1``
  (random Table-3 starts, the paper's protocol): 107 flagged with the original z_f-free search (66 A2 <= 0,
  29 m <= 0, 34 k - K_vdot g <= 0, 89 not converged; a run may trip several), **5 flagged** after the fix
  of 2026-11-22 (all "not converged", none implausible); m 0.40256 ± 0.00113, zm_bar -0.18207 ± 0.000013,
  z_f -0.062 ± 0.014 over the 195 others.
* z_f free, ``--init linear --runs 400 --seed 1``: 58 flagged before (all A2 <= 0 and not converged),
  **21 flagged** after (all "not converged"); m 0.40141 ± 0.00297, zm_bar -0.18207 ± 0.000017,
  z_f -0.051 ± 0.031 — the Table 3 pattern (tight m and zm_bar, wide k, K_vdot, z_f), explained by the
  exact-fit family in z_f (m moves along it with dm/dz_f ~ -0.08 kg/m: the paper's z_f spread 0.0225 m
  gives its m spread 0.0018 kg).

  What the fix was (details in :mod:`shipid.methods.masscm.estimator`, "z_f free"): the first (cold) search with z_f
  free stopped far from the minimum (finite-difference Jacobian on the flat direction; degenerate points on
  the physical bounds k, A_x, d >= 0 or |zm_bar| = 2), and Algorithm 1 started from such a model drifts to
  A2 -> 0. Now the free search uses the exact Jacobian, is followed by the z_f-known cold search at the
  z_f it reached (lower criterion wins), and the warm searches hold z_f (minimum-norm).
  What was left then was not the z_f-free search: every remaining flagged run had m, zm_bar at the right
  values but Algorithm 1's iteration in a period-4 cycle (relative change of the calibration set's beta0 up
  to 7e-3, m within 5e-5), stopping at ``max_iter``. The same cycle appears with z_f KNOWN at some values
  (z_f = -0.029 or -0.0275: 20 of 20 random starts not converged; the study's true -0.028 happens to
  converge), and the z_f-free runs stopped near such a z_f (all 26 between -0.02752 and -0.02745). The
  four-iterate relaxation from iteration 10 on (``MassCMOptions.cycle_after``, :mod:`shipid.methods.masscm.estimator`)
  removes it: with the same commands **0 of 200** (``--init given``; m 0.40249 ± 0.0012, zm_bar
  -0.18207 ± 1.3e-5, z_f -0.061 ± 0.015, 7.4 iterations on average) and **0 of 400** (``--init linear``;
  m 0.40132 ± 0.0029) are flagged. The full paper protocol, ``shipid study mass-cm-sensitivity --z-f free
  --init given --runs 10000 --seed 1 --json`` (2026-11-22): **11 of 10 000 flagged** (the paper: 5), now
  implausible estimates (9 A2 <= 0, 6 m <= 0, 6 k - K_vdot g <= 0, 4 A1 <= 0, 10 also not converged; a run
  may trip several), none "settled"; over the 9 989 others m 0.40255 ± 0.0012 (Table 3: 0.4007 ± 0.0018),
  zm_bar -0.18207 ± 1.3e-5 (-0.1821 ± 0.0004), z_f -0.0617 ± 0.0147 (-0.0403 ± 0.0225), k 18.4 ± 3.5
  (13.3 ± 5.4), K_vdot 0.76 ± 0.29 (0.34 ± 0.44): the Table 3 pattern, tight m and zm_bar, wide k, K_vdot
  and z_f, with our search stopping further along the flat family than the paper's. The summary JSON counts
  ``flagged_reasons`` (how often each rule fired) and ``not_converged_settled`` (runs flagged only as not
  converged whose zm_bar and rho vary by less than 1e-4 relative over the last 10 iterates,
  :func:`_identifiable_drift`).

Speed (``python benchmarks/bench_masscm_study.py 2000 300``, the 2-core shared VM, z_f known).
:func:`run_one` uses the compiled path (``compute="fast"``: :mod:`shipid.methods.masscm.step`,
:mod:`shipid.methods.masscm.search`, :mod:`shipid.estimate.fir_kernels`; the same Algorithm 1, the
reference path is kept and compared run by run). Measured 2026-11-22 00:36 UTC, load average 1.1-1.5
(other engineers' jobs; the host's speed also drifts by ~30 % between minutes, so compare only numbers
taken together): in one process, 300 runs per path interleaved, 9.6 ms/run compiled against 46.4 ms/run
on the reference path (the previous implementation), 4.8x (3.4x-4.0x in earlier runs of the same
benchmark); the same solution in every run (largest per-run difference of m 2.8e-7, the study's own
spread 9e-8). Campaigns of 2000 runs: 1 worker 22.0 s, 2 local workers 12.4 s (1 -> 2 speed-up
1.78x), 2-worker LocalCluster 13.0 s (1.05x the pool); linear extrapolation to 10 000 runs 110 s,
62 s and 65 s (it counts the ~1.2 s worker start-up five times: about 58 s for 2 workers). The one full
10 000-run study (``shipid study mass-cm-sensitivity --runs 10000 --workers 2 --seed 1 --json``,
00:22 UTC, an earlier build about 10 % slower, load 2.1-2.7, i.e. about one core left to the two
workers) took 105.6 s. Quiet re-measurement, the full 10 000 runs per mode
(``python benchmarks/bench_masscm_study.py``, 00:40 UTC, load 0.7-2.1): 1 worker 95.3 s, 2 local
workers 58.3 s, 2-worker LocalCluster 65.9 s; 1 -> 2 speed-up 1.64x, below the 1.8x goal. Part of the
loss was each worker's start (imports, numba cache, datasets: ~1.6 s, paid inside the 2-worker timing
but not the in-process 1-worker one), part the machine's speed drifting between the two sequential
measurements. Since 2026-11-22 02:10 the workers come warm from the forkserver (``run_campaign(...,
warm_up=...)``, :mod:`shipid.studies.worker_preload`) and the benchmark repeats the modes in alternating
order: ``python benchmarks/bench_masscm_study.py 10000 0 1,2,dask 3`` (02:17-02:28 UTC, load 1.0-2.2,
machine slower than at 00:40: 9.4-10.0 ms/run in one process) gave 1 worker 100.1 / 98.6 / 94.3 s,
2 local workers 51.2 / 49.3 / 51.9 s, LocalCluster 54.1 / 52.0 / 62.9 s; speed-up **1.95 / 2.00 / 1.82x,
median 1.95x**; the CPU time per run measured inside the workers is 0-9 % higher with both cores busy.
End to end, one fresh CLI process each (imports, warm-up and forkserver start included):
``shipid study mass-cm-sensitivity --runs 10000 --workers 2 --seed 1 --json`` 47.6 s, ``--workers 1``
94.6 s (1.99x). Where a run's time goes now (about 6.4 outer iterations,
16 dataset-iterations): per dataset-iteration one compiled step (~0.27 ms: FIR filter of eight
signals, lag products, AR(40) fit, closed-loop simulation) and LAPACK's 50x50 eigen-decomposition
(~0.13-0.16 ms; kept: the rank rule of :func:`shipid.estimate.iv.iv_compress_products` needs the
eigenvalues, and the subset drivers are slower at this size); the searches ~0.3 ms; Python glue ~1.5 ms.
Whether a run stops after 6 or 9 iterations (dg just around the 1e-5 tolerance at iteration 6, ~12 % of
runs take 9) varies with rounding, on either path. The numba kernels are compiled once per machine
(about 27 s for all of them at load 1; cached on disk, ``cache=True``) and loaded by each worker in about a second; :func:`warm_up`
does that before a campaign (the CLI calls it).

:func:`run_one` is the per-run task, with the campaign-engine signature
``run_one(i, seedseq, **kwargs) -> dict`` (:mod:`shipid.studies.engine`).
"""

from __future__ import annotations

import copy
import functools
import time
import warnings
from dataclasses import replace

import numpy as np

from shipid.estimate.linalg import one_blas_thread
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
    options = MassCMOptions(max_iter=max_iter, compute=compute, noise_model="ar")
    with one_blas_thread():      # the cached datasets too: their AR fits must not depend on the BLAS threads
        prep, known = prepared(data_seed, vessel, options)
        state0 = initial_moments(data_seed, vessel, options)
    theta0 = draw_initial(rng, vessel)
    z_f = _zf_true(vessel) if zf_mode == "known" else None
    with warnings.catch_warnings(), one_blas_thread():
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
                "reasons": why + ([] if conv else ["not converged"]), "identifiable_drift": drift,
                "theta0": [float(x) for x in theta0]})
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

    The campaign's ``warm_up`` (:func:`shipid.studies.engine.run_campaign`; it passes the campaign's
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
    """One noise realisation of the issue-3 efficiency check (beyond the paper).

    Three datasets of ``duration`` s with :meth:`NoiseSpec.issue3` noise (white gyro / accelerometer
    noise, constant biases, 0.5 deg wave roll), z_f known, linear initialisation; returns the
    estimates of m, zm_bar, rho with their standard errors.
    """
    ss = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence([int(seed), int(i)])
    d = simulate_datasets(vessel, seed=ss, duration=duration, noise=NoiseSpec.issue3())
    known = KnownParams.from_vessel(vessel)
    z_f = float(load_vessel(vessel).value("general", "z_f"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = estimate_mass_cm(list(d.items()), known, z_f=z_f, noise_check=False,   # the estimator alone
                             options=MassCMOptions(prefilter=prefilter, instruments=instruments))
    out = {k: r.value(k) for k in ("m", "zm_bar", "rho", "k", "A_x", "d", "K_r", "K_vdot", "K_delta")}
    out.update({f"{k}_std": r.std(k) for k in ("m", "zm_bar", "rho")})
    out.update({"converged": r.diagnostics["converged"], "iterations": r.diagnostics["iterations"],
                "implausible": r.diagnostics["implausible"],
                "nuisance_outside_physical": bool(r.diagnostics.get("nuisance_outside_physical"))})
    return out
__all__ = ["run_one", "warm_up", "efficiency_run", "summarise", "table3", "draw_initial", "TABLE3_ORDER"]
