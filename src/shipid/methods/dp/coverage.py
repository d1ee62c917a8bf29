"""Coverage study of the DP identification's standard deviations (Fossen, Sagatun & Sørensen 1996).

Each realisation simulates the six trials of Fossen, Sagatun & Sørensen (1996) §4.2 that
``shipid study dp-supply`` uses (surge ×2, sway–yaw ×2, azimuth ×2, 1 Hz; truth: the paper's
θ of eqs. 48–49) with its own noise seed and its own noise levels, unknown to the estimator:

* measurement noise: 0.5 m position and 0.2° heading (1σ) times a scale s_m,
* process noise: white force noise q_h = 1e-8 and a *wandering* bias -- a first-order
  Gauss–Markov process with correlation time 1800 s and stationary std 3e-4 m g
  (:class:`~shipid.methods.dp.trials.TrialNoise` ``bias_tau``; the estimator models the bias as a
  random walk, eq. 37, and assumes 0.25° heading noise), all times a scale s_p (intensities s_p²),

with s_m and s_p drawn independently from {0.5, 1, 2}. :func:`identify_dp` is called with its
defaults (it is told neither scale). :func:`summarise` reports, per θ, the coverage of ±1 and
±2 std, the RMS of error/std, the bias and RMS of the relative error.

Seeds: run ``i`` of a campaign with seed S draws from ``SeedSequence([S, i])``. 

Hard regime (``--regime hard``, :func:`hard_draw`): measurement noise, white force noise, bias random
walk (eq. 37) and initial bias each scaled log-uniformly over 0.3–3, separately; sampling 1–10 Hz
(decimated by the estimator to about 1 s), trials of 600–1800 s. The measured coverage of both regimes is in
``docs/validation/dp.md``.
"""

from __future__ import annotations

import time

import numpy as np

from shipid.methods.dp.estimator import DPOptions, identify_dp
from shipid.methods.dp.trials import TrialNoise, simulate_dp_trials
from shipid.models.dp import dp_vessel
from shipid.vessels import load_vessel
from shipid.methods.dp.loglik import momentum_loglik, surge_loglik

#: Noise scales drawn per realisation (separately for measurement and process noise).
SCALES = (0.5, 1.0, 2.0)
#: Accuracy band for each θ (|relative error| within 10 %, the weak coupling θ3 within 25 %).
ACCURACY_BAND = (0.10, 0.10, 0.25, 0.10, 0.10, 0.10, 0.10, 0.10, 0.10)
#: Nominal levels of the study's simulated trials (see the module docstring).
SIGMA_POS = 0.5
SIGMA_PSI_DEG = 0.2
Q_H = 1e-8
B0 = 3e-4
BIAS_TAU = 1800.0


def study_noise(s_m: float, s_p: float):
    """The :class:`TrialNoise` of one realisation with measurement scale ``s_m``, process scale ``s_p``."""
    return TrialNoise(sigma_pos=SIGMA_POS * s_m, sigma_psi=float(np.deg2rad(SIGMA_PSI_DEG)) * s_m,
                      q_h=Q_H * s_p ** 2, q_b=0.0, b0=B0 * s_p, bias_tau=BIAS_TAU)


#: The hard regime: each noise scale drawn log-uniformly over this range, separately.
HARD_SCALES = (0.3, 3.0)
#: The hard regime's sampling rates (Hz, drawn uniformly) and trial lengths (s, drawn uniformly).
HARD_RATE_HZ = (1.0, 10.0)
HARD_DURATION_S = (600.0, 1800.0)
#: Nominal levels of the hard regime (scaled per realisation): position and heading noise, white force
#: noise, bias random walk (eq. 37, bis force² per bis time) and initial bias std (bis force).
HARD_NOMINAL = {"sigma_pos": 0.5, "sigma_psi_deg": 0.2, "q_h": 1e-8, "q_b": 1e-10, "b0": 3e-4}


def hard_draw(rng) -> dict:
    """One hard-regime realisation's settings: the noise scales, rate and length (none told to the estimator).

    Measurement noise (position and heading together), white force noise, bias random walk and
    initial bias (random per trial, std ``b0``) each scaled by a factor drawn log-uniformly over
    :data:`HARD_SCALES`; the sampling rate uniformly over :data:`HARD_RATE_HZ` and the length of the
    trials over :data:`HARD_DURATION_S`.
    """
    lo, hi = np.log(HARD_SCALES[0]), np.log(HARD_SCALES[1])
    s = {k: float(np.exp(rng.uniform(lo, hi))) for k in ("s_m", "s_p", "s_b", "s_b0")}
    s["rate_hz"] = float(rng.uniform(*HARD_RATE_HZ))
    s["duration_s"] = float(np.round(rng.uniform(*HARD_DURATION_S)))
    return s


def hard_noise(d: dict) -> TrialNoise:
    """The :class:`TrialNoise` of a hard-regime draw :func:`hard_draw` (bias: the random walk of eq. 37)."""
    n = HARD_NOMINAL
    return TrialNoise(sigma_pos=n["sigma_pos"] * d["s_m"], sigma_psi=float(np.deg2rad(n["sigma_psi_deg"])) * d["s_m"],
                      q_h=n["q_h"] * d["s_p"] ** 2, q_b=n["q_b"] * d["s_b"] ** 2, b0=n["b0"] * d["s_b0"])


def run_one(i: int, seedseq, duration: float = 1200.0, trials: int = 2, covariance: str = "observed",
            regime: str = "scales") -> dict:
    """One realisation (campaign-engine task): simulate, identify, compare with the truth.

    ``regime="scales"``: :func:`study_noise` with scales from :data:`SCALES` at 1 Hz, ``duration``;
    ``"hard"``: :func:`hard_draw` (scales, rate and length drawn; ``duration`` unused).
    """
    rng = np.random.default_rng(seedseq)
    extra = {}
    if regime == "hard":
        draw = hard_draw(rng)
        s_m, s_p = draw["s_m"], draw["s_p"]
        noise = hard_noise(draw)
        dt, duration = 1.0 / draw["rate_hz"], draw["duration_s"]
        extra = draw
    else:
        s_m = float(rng.choice(SCALES))
        s_p = float(rng.choice(SCALES))
        noise, dt = study_noise(s_m, s_p), 1.0
    data_seed = int(rng.integers(0, 2 ** 31 - 1))
    v = dp_vessel(load_vessel("supply"))
    tr = simulate_dp_trials(v, data_seed, duration=duration, n_per_kind=trials, noise=noise, dt=dt)
    t0 = time.perf_counter()
    res = identify_dp(tr["surge"], tr["sway-yaw"], tr["azimuth"], v, DPOptions(covariance=covariance),
                      theta_true=v.theta)
    secs = time.perf_counter() - t0
    d = res.diagnostics
    noise = {st: {k: x["scale_vs_nominal"] for k, x in nz.items()} for st, nz in d.get("noise", {}).items()}
    return {"s_m": s_m, "s_p": s_p, "data_seed": data_seed, "seconds": secs, "regime": regime, **extra,
            "theta": [res.estimates[f"theta{j}"].value for j in range(1, 10)],
            "std": [res.estimates[f"theta{j}"].std for j in range(1, 10)],
            "status": [res.estimates[f"theta{j}"].status for j in range(1, 10)],
            "theta_true": v.theta.tolist(), "error_sigma": np.asarray(d["error_sigma"]).tolist(),
            "relative_error": np.asarray(d["relative_error"]).tolist(),
            "settled": {k: bool(s["settled"]) for k, s in d["stages"].items()},
            "noise_scale_estimates": noise, "warnings": list(d["warnings"])}


def summarise(outputs: list[dict | None]) -> dict:
    """Per-θ coverage of ±1/±2 std, RMS of error/std, relative error; pooled over θ1…θ9.

    Coverage and RMS are over the estimates that have a std (an unsettled scheme whose Hessian
    is not positive definite reports none: counted in ``no_std``); ``cover_2sd_all`` counts
    those as not covered. ``within_band``: realisations whose |relative error| is within
    :data:`ACCURACY_BAND` (``band_pct``).
    """
    ok = [o for o in outputs if o is not None]
    n = len(ok)
    out = {"runs": len(outputs), "ok": n, "failed": len(outputs) - n, "parameters": {}}
    if not n:
        return out
    es = np.array([o["error_sigma"] for o in ok], dtype=float)
    rel = np.array([o["relative_error"] for o in ok], dtype=float)
    unrel = np.array([[s != "estimated" for s in o["status"]] for o in ok])
    fin = np.isfinite(es)
    for j in range(9):
        e = es[fin[:, j], j]
        out["parameters"][f"theta{j + 1}"] = {
            "cover_1sd": float(np.mean(np.abs(e) <= 1.0)) if e.size else float("nan"),
            "cover_2sd": float(np.mean(np.abs(e) <= 2.0)) if e.size else float("nan"),
            "cover_2sd_all": float(np.sum(np.abs(e) <= 2.0) / n),
            "rms_error_over_std": float(np.sqrt(np.mean(e ** 2))) if e.size else float("nan"),
            "no_std": int(n - e.size),
            "mean_rel_error_pct": float(100 * np.mean(rel[:, j])),
            "rms_rel_error_pct": float(100 * np.sqrt(np.mean(rel[:, j] ** 2))),
            "max_abs_rel_error_pct": float(100 * np.max(np.abs(rel[:, j]))),
            "mean_abs_rel_error_pct": float(100 * np.mean(np.abs(rel[:, j]))),
            "band_pct": 100 * ACCURACY_BAND[j],
            "within_band": int(np.sum(np.abs(rel[:, j]) <= ACCURACY_BAND[j])),
            "std_unreliable": int(unrel[:, j].sum())}
    e = es[fin]
    out["pooled"] = {"cover_1sd": float(np.mean(np.abs(e) <= 1.0)), "cover_2sd": float(np.mean(np.abs(e) <= 2.0)),
                     "cover_2sd_all": float(np.sum(np.abs(e) <= 2.0) / es.size),
                     "rms_error_over_std": float(np.sqrt(np.mean(e ** 2))), "no_std": int(es.size - e.size)}
    out["unsettled_runs"] = int(sum(not all(o["settled"].values()) for o in ok))
    out["seconds_per_identify"] = float(np.mean([o["seconds"] for o in ok]))
    return out


def worst_regime(outputs: list[dict | None], k: int = 3) -> list[dict]:
    """The ``k`` realisations with the largest max |error|/std, with their drawn settings."""
    ok = [o for o in outputs if o is not None]
    keys = ("s_m", "s_p", "s_b", "s_b0", "rate_hz", "duration_s")
    rows = []
    for o in ok:
        es = np.abs(np.asarray(o["error_sigma"], dtype=float))
        j = int(np.nanargmax(es)) if np.any(np.isfinite(es)) else 0
        rows.append({"max_abs_error_over_std": float(es[j]), "theta": f"theta{j + 1}",
                     **{q: o[q] for q in keys if q in o}})
    return sorted(rows, key=lambda r: -r["max_abs_error_over_std"])[:k]


def by_scale(outputs: list[dict | None], key: str, edges=(0.3, 0.6, 1.2, 3.0)) -> list[dict]:
    """Pooled ±2-std coverage and RMS of error/std by the bin of one drawn setting (``key``)."""
    ok = [o for o in outputs if o is not None and key in o]
    out = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        es = np.array([o["error_sigma"] for o in ok if lo <= o[key] < hi or (hi == edges[-1] and o[key] == hi)],
                      dtype=float)
        e = es[np.isfinite(es)] if es.size else es
        out.append({"range": [lo, hi], "runs": int(len(es)),
                    "cover_2sd": float(np.mean(np.abs(e) <= 2.0)) if e.size else float("nan"),
                    "rms_error_over_std": float(np.sqrt(np.mean(e ** 2))) if e.size else float("nan")})
    return out


def warm_up(**_) -> None:
    """Compile (or load from numba's cache) the likelihood kernels in this process before the runs.

    One call of each kernel of :mod:`shipid.methods.dp.loglik` on a three-sample track, so the
    first realisation's ``seconds`` is not the compilation.
    """

    n = 3
    dt = np.ones(n - 1)
    momentum_loglik(np.zeros((n, 3)), dt, np.zeros((n, 3)), np.eye(3), np.eye(3), -np.eye(3), np.full(3, 1e-8),
                    np.full(3, 1e-10), np.full(3, 1e-4), np.zeros(9), np.eye(9))
    surge_loglik(np.zeros(n), dt, np.zeros(n), 1.0, -0.03, 1e-8, 1e-10, 1e-4, np.zeros(3), np.eye(3))


__all__ = ["ACCURACY_BAND", "SCALES", "HARD_SCALES", "HARD_RATE_HZ", "HARD_DURATION_S", "hard_draw", "hard_noise",
           "study_noise", "run_one", "summarise", "worst_regime", "warm_up"]
