"""Simulation–extrapolation (SIMEX) correction of the step-2 regression for step-1 state errors.

Step 2 (:func:`shipid.methods.mmg.estimator.fit`) puts the SMOOTHED states of step 1 into
regressors that are nonlinear in them (``v|v|``, ``r'``, the rudder inflow, …). The smoothed
states carry estimation errors — at a simulated 20-deg zig-zag of the Esso Osaka 3 m about
0.002 m/s on a sway velocity whose standard deviation is 0.012 m/s — and a regression on
error-laden regressors is biased towards zero (errors in variables). In the simulated
coverage study (:mod:`shipid.methods.mmg.coverage`) that bias of the integral-form regression
was 5–10 % on N_v, N_r, Y_v, Y_r: several times their standard errors.

SIMEX (Cook & Stefanski 1994, *J. Amer. Statist. Assoc.* 89:1314–1328; Carroll, Ruppert,
Stefanski & Crainiceanu 2006, *Measurement Error in Nonlinear Models*, ch. 5) measures that
bias by making it worse: extra white noise of variance ``λ σ̂²`` is added to each measured
channel (``σ̂`` per channel and run, :func:`shipid.methods.mmg.estimator.noise_from_data`, the
robust second-difference estimate), steps 1 and 2 are repeated, the mean estimate over
``draws`` noise draws is taken at each ``λ`` of :attr:`SimexConfig.lambdas`, and the estimates
as a function of ``λ`` are extrapolated to ``λ = −1`` (no measurement noise). The extrapolant is
linear by default, over ``λ`` = 0.125, 0.25, 0.375, 0.5 (:attr:`SimexConfig.lambdas`): the bias is not
linear in λ at larger added noises, so a grid close to 0 extrapolates better; its larger Monte Carlo
variance is in the covariance. How the grid and the extrapolant were chosen: ``docs/validation/mmg.md``.

On real data: on the Esso Osaka logs σ̂ is at the level the logger's own smoothing leaves, the
pilot (:attr:`SimexConfig.pilot`) moves no estimate by 0.1 SE, and no correction is made; a forced
correction moved no coefficient by 0.1 % at about 30 s per fit of 24 runs.

What it does not correct: a bias of step 1 that does not grow with the noise (the white-jerk
smoother's lag after an instantaneous rudder step); the integral form of step 2
(``FitConfig.equation``) is what keeps that small.

The covariance MODEL.json carries is the regression's plus the Monte Carlo variance of the
correction (:attr:`SimexInfo.mc_cov`), and, where the regression's is the HAC sandwich (fewer
than 5 runs, :func:`shipid.methods.mmg.covariance.honest_covariance`), the noise's part
:attr:`SimexInfo.noise_cov` measured by the draws themselves. The reason: the smoothed states'
errors are smooth and correlated over a whole run, so they move the estimate without showing as
score variance within the HAC's lag window; the draws move the estimate by exactly that
mechanism (measured coverage with and without it: ``docs/validation/mmg.md``). The run bootstrap (5 runs
or more) resamples whole runs and so already holds it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Mapping, Sequence

import numpy as np

from shipid.io.trial import Trial
from shipid.methods.mmg import estimator as R
from shipid.models import mmg


@dataclass(frozen=True)
class SimexConfig:
    """``lambdas``: added noise variances in units of σ̂²; ``draws`` noise draws per λ; ``seed`` of the draws;
    ``extrapolant``: ``"linear"`` or ``"quadratic"`` in λ (the two compared: ``docs/validation/mmg.md``).

    ``pilot``: first refit twice at ``λ = pilot_lambda`` (added noise of twice the measured variance); if no
    estimate moves by more than ``pilot_threshold`` of its (iid ridge, i.e. small) standard error, the measurement noise is too small to bias the
    regression and the correction is not made (the naive fit is returned, ``SimexInfo.applied`` False).
    On the Esso Osaka logs the pilot moved no estimate by 0.1 SE (module docstring)."""

    lambdas: tuple[float, ...] = (0.125, 0.25, 0.375, 0.5)
    draws: int = 8
    seed: int = 0
    extrapolant: str = "linear"
    pilot: bool = True
    pilot_threshold: float = 0.25
    pilot_lambda: float = 2.0


def _noisy(trial: Trial, sd: np.ndarray, scale: float, rng: np.random.Generator) -> Trial:
    """``trial`` with white noise of std ``scale · sd`` added to the step-1 measurements (:data:`MEAS`)."""
    new = {c: np.asarray(trial[c], float) + scale * s * rng.standard_normal(len(trial))
           for c, s in zip(R.MEAS, sd)}
    return trial.with_channels(**new)


def measurement_sd(trial: Trial) -> np.ndarray:
    """σ̂ of each step-1 measurement channel of ``trial`` (heading unwrapped first)."""
    return R.noise_from_data(R.measurements(trial))


@dataclass(frozen=True)
class SimexInfo:
    """What the correction did: ``lambdas`` (0 first), the mean estimate at each (``path``, names × λ),
    ``mc_cov`` the Monte Carlo part of the corrected estimate's covariance (the finite number of noise
    draws: ``Σ_j w_j² S²(λ_j) / draws`` with ``w`` the extrapolation weights and ``S²`` the draws'
    covariance at ``λ_j``), the correction applied per coefficient, the σ̂ per run; ``applied`` False when
    the pilot found the noise immaterial (``pilot_moved_se``: the largest move of an estimate at
    ``pilot_lambda``, in iid standard errors); ``noise_cov`` the covariance one draw's added noise of
    variance ``λ σ̂²`` gives the estimate, per unit λ, pooled over the grid (``mean_j S²(λ_j) / λ_j``):
    the part of the estimate's covariance the measured noise causes through the step-1 states,
    which the HAC sandwich of the regression residuals misses (:func:`shipid.methods.mmg.pipeline.identify`
    adds it where the regression covariance is the HAC; module docstring); ``noise_sd`` the square
    roots of its diagonal."""

    names: tuple[str, ...]
    lambdas: tuple[float, ...]
    path: np.ndarray
    mc_cov: np.ndarray
    correction: dict[str, float]
    sd: dict[str, list[float]]
    applied: bool = True
    pilot_moved_se: float = float("nan")
    noise_sd: np.ndarray | None = None
    noise_cov: np.ndarray | None = None

    def to_dict(self) -> dict:
        return {"method": "SIMEX (Cook & Stefanski 1994)", "applied": self.applied,
                "pilot_largest_move_in_se": self.pilot_moved_se, "lambdas": list(self.lambdas),
                "path": {n: self.path[i].tolist() for i, n in enumerate(self.names)},
                "correction": dict(self.correction), "measurement_sd": dict(self.sd),
                "mc_se": dict(zip(self.names, np.sqrt(np.maximum(np.diag(self.mc_cov), 0.0)).tolist())),
                "noise_sd": None if self.noise_sd is None else dict(zip(self.names, self.noise_sd.tolist()))}


def simex_fit(f0: R.MmgFit, trials: Sequence[Trial], prior: mmg.MmgModel, free: Mapping[str, Sequence[str]],
              fit_config: R.FitConfig, smooth_config: R.SmoothConfig = R.SmoothConfig(),
              config: SimexConfig = SimexConfig()) -> tuple[R.MmgFit, SimexInfo]:
    """The SIMEX-corrected fit of ``f0`` (the naive fit of ``trials`` with ``prior``, ``free``, ``fit_config``).

    Returns a fit with the same free / dropped coefficients and the extrapolated values in
    ``fits[mode].theta`` (every other ridge statistic is the naive fit's), and the
    :class:`SimexInfo`. Seeded: the same inputs give the same numbers.
    """
    if config.extrapolant not in ("linear", "quadratic"):
        raise ValueError(f"unknown SIMEX extrapolant '{config.extrapolant}' (linear, quadratic)")
    names = [c for m in mmg.MODES for c in f0.free.get(m, ())]
    used = {m: tuple(f0.free.get(m, ())) for m in mmg.MODES}
    sds = [measurement_sd(tr) for tr in trials]
    sd_of = {str(tr.meta.get("source", i)): sd.tolist() for i, (tr, sd) in enumerate(zip(trials, sds))}
    rng = np.random.default_rng(np.random.SeedSequence([int(config.seed), 0x51_3E]))
    p = len(names)
    th0 = np.array([f0.model.coef[n] for n in names])

    def refit(lam: float) -> np.ndarray:
        """The estimates after steps 1 and 2 on the runs with added noise of variance ``lam σ̂²`` (one draw)."""
        runs = [R.smooth_run(_noisy(tr, sd, np.sqrt(lam), rng), smooth_config) for tr, sd in zip(trials, sds)]
        fb = R.fit(runs, prior, used, fit_config)
        return np.array([fb.model.coef[n] for n in names])

    moved = float("nan")
    if config.pilot:
        # the fit's (iid) standard errors in the order of ``names`` (each mode's fit holds its free coefficients)
        se = np.concatenate([f0.fits[m].se for m in mmg.MODES if f0.free.get(m)]) if p else np.zeros(0)
        moved = 0.0
        for _ in range(2):
            d = np.abs(refit(float(config.pilot_lambda)) - th0) / np.where(se > 0, se, np.inf)
            moved = max(moved, float(np.nanmax(d)) if d.size else 0.0)
        if moved < config.pilot_threshold:
            info = SimexInfo(names=tuple(names), lambdas=(0.0,), path=th0[:, None], mc_cov=np.zeros((p, p)),
                             correction={n: 0.0 for n in names}, sd=sd_of, applied=False, pilot_moved_se=moved)
            return f0, info
    path = np.empty((p, 1 + len(config.lambdas)))
    path[:, 0] = th0
    spread = []                                   # covariance of one draw's estimate at each λ
    for j, lam in enumerate(config.lambdas):
        draws = np.array([refit(lam) for _ in range(config.draws)]).reshape(config.draws, p)
        path[:, 1 + j] = draws.mean(axis=0)
        spread.append(np.cov(draws, rowvar=False, ddof=1).reshape(p, p) if config.draws > 1 else np.zeros((p, p)))
    lam = np.concatenate([[0.0], np.asarray(config.lambdas, float)])
    deg = 1 if config.extrapolant == "linear" else 2
    # the extrapolated value is a fixed linear combination  Σ_j w_j θ(λ_j)  of the path (least-squares fit)
    V = np.vander(lam, deg + 1)
    w = np.vander(np.array([-1.0]), deg + 1) @ np.linalg.pinv(V)
    w = w.ravel()
    at_minus_one = path @ w
    # Monte Carlo part of its variance: the mean of ``draws`` noise draws at each λ > 0
    mc = sum(w[1 + j] ** 2 * spread[j] for j in range(len(config.lambdas))) / max(config.draws, 1)
    mc = 0.5 * (mc + mc.T)
    corrected = dict(zip(names, at_minus_one))
    fits = {m: replace(fi, theta=np.array([corrected[c] for c in f0.free[m]])) for m, fi in f0.fits.items()}
    model = f0.model.with_coef(corrected, name=f0.model.name)
    # the noise's part of the covariance: an added variance λ σ̂² spreads one draw's estimate by λ V
    noise_cov = sum(S / lj for S, lj in zip(spread, config.lambdas)) / len(config.lambdas)
    noise_cov = 0.5 * (noise_cov + noise_cov.T)
    noise_sd = np.sqrt(np.maximum(np.diag(noise_cov), 0.0))
    info = SimexInfo(names=tuple(names), lambdas=tuple(lam.tolist()), path=path, mc_cov=mc, applied=True,
                     noise_sd=noise_sd, noise_cov=noise_cov, pilot_moved_se=moved,
                     correction={n: float(corrected[n] - path[i, 0]) for i, n in enumerate(names)}, sd=sd_of)
    return replace(f0, model=model, fits=fits), info


__all__ = ["SimexConfig", "SimexInfo", "simex_fit", "measurement_sd"]
