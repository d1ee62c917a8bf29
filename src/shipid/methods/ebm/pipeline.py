"""The two steps of Estimation-Before-Modelling for given particulars (Yoon & Rhee 2003).

Step 1 (§3), :func:`estimate_states`: for one trial, the continuous–discrete EKF
(:mod:`shipid.estimate.cd_ekf`, or its compiled twin :mod:`shipid.methods.ebm.compiled`) and the
modified Bryson–Frazier or RTS smoother estimate the 17 states of :mod:`shipid.models.ebm_state`
from the measurements of eq. 8, in ``config.passes`` passes (§5.1.1).

Step 2 (§4), :func:`fit_coefficients`: ridge regression (:mod:`shipid.estimate.ridge`) of the
smoothed X, Y, N on the regressors of eqs. 14–15 built from the smoothed ``u_r, v_r, r`` and
the known δ and n, all trials together.

:mod:`shipid.methods.ebm.estimator` runs both, adds the verdicts and the bias correction and
builds the Result.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Sequence

import numpy as np

from shipid.analysis.observability import ebm_observability
from shipid.io.trial import Trial
from shipid.errors import InputError, ShipidError
from shipid.estimate.cd_ekf import FilterResult, cd_ekf
from shipid.numerics.linalg import NotPositiveDefiniteError
from shipid.estimate.ridge import RidgeFit, ridge
from shipid.estimate.smoothers import SmootherResult, mbf_smoother, rts_smoother
from shipid.methods.ebm.compiled import ebm_cd_ekf, mbf_smoother_fast, rts_smoother_fast
from shipid.models import abkowitz as ab
from shipid.models.ebm_state import STATE_NAMES, EbmModel, initial_state, measurement_noise

REQUIRED = ("x", "y", "x_dot", "y_dot", "psi", "U", "delta", "n")


@dataclass(frozen=True)
class EbmConfig:
    """Tuning of the EBM pipeline.

    Attributes
    ----------
    q_force : (float, float, float)
        Spectral densities of the third derivatives of X (N²/s⁵), Y (N²/s⁵) and
        N (N²m²/s⁵). Chosen on simulated trials (seeds 0–2, zig-zag and PRBS):
        the mean normalised innovation squared is then 5.5–5.7 (expected 6) and
        the smoothed forces follow the rudder without lag.
    q_current : float
        Spectral density of the current's random walk ((m/s)²/s).
    passes : int
        Number of estimation passes (2 in §5.1.1).
    smoother : str
        ``"mbf"`` (the paper's) or ``"rts"``.
    ridge_k : float or None
        Ridge biasing parameter; None = Hoerl–Kennard iteration, 0 = OLS.
    yaw_rudder_variant : bool
        Use the yaw rudder regressors of eq. 22.
    substeps : int
        RK4 steps per sample in the filter's prediction.
    rudder_q_gain : float
        Our addition (not in the paper): while the (known) rudder moves, the force
        processes' spectral densities are multiplied by ``1 + rudder_q_gain``
        (over the samples where |δ̇| > 0, widened by ``rudder_q_halo`` samples each
        side). The forces jump when the rudder is put over; a constant-q
        Gauss–Markov model smooths those jumps away and biases the regression.
        0 reproduces the paper's constant-Q model.
    rudder_q_halo : int
    compiled : bool
        Run step 1 on the numba-compiled filter and smoothers of
        :mod:`shipid.methods.ebm.compiled` (same algorithm and numbers to ~1e-11 as the
        reference :func:`~shipid.estimate.cd_ekf.cd_ekf` path, tested; ~8× faster than
        filterpy, ``benchmarks/bench_ebm_filter.py``). False runs the reference path.
    approach_s : float
        Seconds at the start of each trial over which the approach speed and propeller
        rate are averaged (:func:`approach_condition`).
    approach_speed, approach_rate : float or None
        The approach speed through the water (m/s) and propeller rate (1/s) when the user
        measured them otherwise; None takes them from the trials.
    se : str
        ``"hac"`` (default): Newey–West standard errors of the ridge estimate with the
        ridge bias added in quadrature (:func:`shipid.estimate.ridge.ridge`); ``"iid"``: the
        textbook ridge covariance, which assumes independent residuals.
    weights : str
        ``"smoother"`` (default): step 2 weights each sample by ``1/σ`` of the smoothed force
        (the smoother's marginal standard deviation); ``"none"``: the paper's unweighted fit.
    sensors : (x_D, y_D, y_S) or None
        DGPS antenna and speed-log positions in body axes (m) for trials that do not state them
        (:func:`sensor_positions`); None: the body origin.
    bias_threshold : float
        The correction is applied to the coefficients whose bias exceeds this many std.
    hac_bandwidth : int or None
        Newey–West lag window (samples); None: Andrews' (1991) rule.
    bias_correction : bool
        Subtract the pipeline's own bias at the identified ship (:mod:`shipid.methods.ebm.bias`).
    """

    q_force: tuple[float, float, float] = (1e8, 1e9, 1e13)
    q_current: float = 1e-12
    passes: int = 2
    smoother: str = "mbf"
    ridge_k: float | None = None
    yaw_rudder_variant: bool = False
    substeps: int = 1
    rudder_q_gain: float = 100.0
    rudder_q_halo: int = 3
    compiled: bool = True
    approach_s: float = 10.0
    approach_speed: float | None = None
    approach_rate: float | None = None
    se: str = "hac"
    weights: str = "yaw"
    bias_correction: bool = True
    hac_bandwidth: int | None = None
    bias_threshold: float = 0.5
    sensors: tuple[float, float, float] | None = None


def process_noise(model: EbmModel, delta: np.ndarray, config: EbmConfig) -> np.ndarray:
    """Q per sample interval: constant, or raised while the rudder moves (``rudder_q_gain``)."""
    Q = model.Q()
    if config.rudder_q_gain <= 0 or delta.size < 2:
        return Q
    moving = np.abs(np.diff(delta)) > 1e-9
    h = int(config.rudder_q_halo)
    if h > 0:
        kern = np.ones(2 * h + 1)
        moving = np.convolve(moving.astype(float), kern, mode="same") > 0
    scale = 1.0 + config.rudder_q_gain * moving.astype(float)
    Qs = np.repeat(Q[None, :, :], delta.size - 1, axis=0)
    idx = [8, 11, 14]
    for i in idx:
        Qs[:, i, i] *= scale
    return Qs


@dataclass(frozen=True)
class StateEstimate:
    """Step-1 output for one trial."""

    trial: Trial
    filt: FilterResult
    smooth: SmootherResult
    current: np.ndarray          # (c_x, c_y) from the smoothed initial state
    current_std: np.ndarray
    passes: int
    model: EbmModel | None = None
    first_pass_current: np.ndarray | None = None

    def series(self, name: str) -> np.ndarray:
        return self.smooth.x[:, STATE_NAMES.index(name)]


def sensor_positions(trial: Trial, vessel=None, config=None) -> dict[str, float]:
    """Body-axis positions of the DGPS antenna (``x_D, y_D``) and speed log (``y_S``) of eq. 8, in m.

    From the trial's metadata (simulated §5.1 records carry them), else from
    ``config.sensors`` (what the user states), else the body origin: the shipid channel
    convention for ``x, y, x_dot, y_dot, U`` (``shipid simulate`` records the origin). The
    vessel file's [trials] positions belong to the §5.1 simulation set-up, not to a user's
    trial, and are not used: a wrong lever arm moves the reference point of every velocity
    and biases all coefficients without any sign in the innovations.
    """
    given = {} if config is None or config.sensors is None else dict(zip(("x_D", "y_D", "y_S"), config.sensors))
    return {k: float(trial.meta.get(k, given.get(k, 0.0))) for k in ("x_D", "y_D", "y_S")}


def sensor_source(trial: Trial, config=None) -> str:
    """Where :func:`sensor_positions` took the lever arms from (for the Result)."""
    if all(k in trial.meta for k in ("x_D", "y_D", "y_S")):
        return "trial metadata"
    if config is not None and config.sensors is not None:
        return "given by the user"
    return "not stated: body origin assumed"


def measurements(trial: Trial) -> np.ndarray:
    """The measurement matrix ``z`` (N, 6) of eq. 8 from a trial."""
    trial.require(list(REQUIRED), method="ebm")
    return np.column_stack([trial["x"], trial["y"], trial["x_dot"], trial["y_dot"],
                            trial["psi"], trial["U"]])


def prior_cov(current_known: bool) -> np.ndarray:
    """Diagonal prior covariance of the 17 states at the first sample (current known or not)."""
    sd = np.array([0.05, 0.5, 1e-3, 30.0, 30.0, 1e-3,
                   1e6, 1e4, 1e2, 2e6, 2e4, 2e2, 5e8, 5e6, 5e4,
                   0.05 if current_known else 2.0, 0.05 if current_known else 2.0])
    return np.diag(sd ** 2)


def estimate_states(trial: Trial, p: ab.AbkowitzParams, *, vessel: str = "esso-osaka",
                    config: EbmConfig = EbmConfig()) -> StateEstimate:
    """Step 1 for one trial: EKF + fixed-interval smoother, ``config.passes`` passes (§5.1.1)."""
    z = measurements(trial)
    t = trial.t - trial.t[0]
    sens = sensor_positions(trial, vessel, config)
    conds = ab.trial_conditions(vessel)
    sig = {k: float(trial.meta.get(k, conds[k])) for k in ("sigma_xy", "sigma_xy_dot", "sigma_psi", "sigma_u_log")}
    R = measurement_noise(sig["sigma_xy"], sig["sigma_xy_dot"], sig["sigma_psi"], sig["sigma_u_log"])
    model = EbmModel.from_abkowitz(p, sens["x_D"], sens["y_D"], sens["y_S"],
                                   q_force=config.q_force, q_current=config.q_current)
    Q = process_noise(model, np.asarray(trial["delta"], dtype=float), config)
    smooth_fn = mbf_smoother if config.smoother == "mbf" else rts_smoother
    if config.compiled:
        smooth_fn = mbf_smoother_fast if config.smoother == "mbf" else rts_smoother_fast
    current = np.zeros(2)
    first = None
    x0 = initial_state(z[0], model)
    P0 = prior_cov(False)
    fr = sm = None
    for k in range(max(1, config.passes)):
        if k > 0:
            # §5.1.1: initial velocities corrected by the current of the previous pass
            psi0 = z[0, 4]
            c, s = np.cos(psi0), np.sin(psi0)
            ug = z[0, 2] * c + z[0, 3] * s
            vg = -z[0, 2] * s + z[0, 3] * c
            uc = current[0] * c + current[1] * s
            vc = -current[0] * s + current[1] * c
            x0 = initial_state(z[0], model, u_r0=ug - uc, v_r0=vg - vc, current=tuple(current))
            x0[2] = sm.x[0, 2]
            P0 = prior_cov(True)
        try:
            if config.compiled:
                fr = ebm_cd_ekf(model, Q, R, t, z, x0, P0, substeps=config.substeps)
            else:
                fr = cd_ekf(model.f, model.F, model.h, model.H, Q, R, t, z, x0, P0,
                            substeps=config.substeps)
        except NotPositiveDefiniteError as err:
            raise ShipidError(f"EBM step 1 failed on {trial.meta.get('source', 'trial')}: {err}") from None
        sm = smooth_fn(fr)
        current = sm.x[0, 15:17].copy()
        if first is None:
            first = current.copy()
    cstd = sm.std[0, 15:17]
    return StateEstimate(trial=trial, filt=fr, smooth=sm, current=current, current_std=cstd,
                         passes=max(1, config.passes), model=model, first_pass_current=first)


def observability_report(state: StateEstimate, points: int = 20) -> dict:
    """Eq. 11 rank along the smoothed trajectory, relative and absolute position (§3.2)."""
    conds = ab.trial_conditions()
    std = np.array([conds["sigma_xy"], conds["sigma_xy"], conds["sigma_xy_dot"], conds["sigma_xy_dot"],
                    conds["sigma_psi"], conds["sigma_u_log"]])
    every = max(1, state.smooth.t.size // points)
    o = ebm_observability(state.model, state.smooth.t, state.smooth.x, std, every=every)
    return {k: {"n": v.n, "min_rank": int(v.rank.min()), "max_rank": int(v.rank.max()),
                "full_rank_fraction": v.full_rank_fraction,
                "smallest_relative_singular_value": float(v.min_rel_sv.min()), "points": int(v.rank.size)}
            for k, v in o.items()}


@dataclass(frozen=True)
class RegressionData:
    """Stacked step-2 data of all trials."""

    HX: np.ndarray
    HY: np.ndarray
    HN: np.ndarray
    X: np.ndarray
    Y: np.ndarray
    N: np.ndarray
    v: np.ndarray
    r: np.ndarray
    seg: np.ndarray | None = None
    sX: np.ndarray | None = None
    sY: np.ndarray | None = None
    sN: np.ndarray | None = None


def regression_data(states: Sequence[StateEstimate], p: ab.AbkowitzParams, *, skip: int = 0
                    ) -> RegressionData:
    """Build the regressors of eq. 14 from smoothed states and the known inputs."""
    parts = {k: [] for k in ("HX", "HY", "HN", "X", "Y", "N", "v", "r", "seg", "sX", "sY", "sN")}
    for i, st in enumerate(states):
        x = st.smooth.x[skip:]
        sd = st.smooth.std[skip:]
        tr = st.trial
        HX, HY, HN = ab.regressors(x[:, 0], x[:, 1], x[:, 2], tr["delta"][skip:], tr["n"][skip:], p)
        for k, val in (("HX", HX), ("HY", HY), ("HN", HN), ("X", x[:, 6]), ("Y", x[:, 9]),
                       ("N", x[:, 12]), ("v", x[:, 1]), ("r", x[:, 2]), ("seg", np.full(x.shape[0], i)),
                       ("sX", sd[:, 6]), ("sY", sd[:, 9]), ("sN", sd[:, 12])):
            parts[k].append(val)
    return RegressionData(**{k: np.concatenate(v) for k, v in parts.items()})


def combined_coefficients(theta_Y, theta_N, alpha: float) -> tuple[float, float]:
    """Eq. 21: ``Y'_v + Y'_r/α`` and ``N'_v α + N'_r`` (with ``v ≅ L α r``, eq. 20)."""
    return (float(theta_Y[1] + theta_Y[2] / alpha), float(theta_N[1] * alpha + theta_N[2]))


def slope_alpha(v: np.ndarray, r: np.ndarray, L: float) -> float:
    """Eq. 20: least-squares slope α of ``v ≅ L α r`` (through the origin)."""
    Lr = L * np.asarray(r)
    return float(np.dot(np.asarray(v), Lr) / np.dot(Lr, Lr))


@dataclass(frozen=True)
class EbmFit:
    """Step-2 output."""

    surge: RidgeFit
    sway: RidgeFit
    yaw: RidgeFit
    alpha: float
    data: RegressionData
    bias: tuple | None = None
    note: str = ""


def fit_coefficients(states: Sequence[StateEstimate], p: ab.AbkowitzParams,
                     config: EbmConfig = EbmConfig()) -> EbmFit:
    """Step 2: ridge regression per mode on all trials together (§5.1.2)."""
    pp = replace(p, yaw_rudder_variant=config.yaw_rudder_variant)
    d = regression_data(states, pp)
    import warnings

    kw = dict(cov=config.se, segments=d.seg, bandwidth=config.hac_bandwidth)

    def wls(H, y, s, mode):
        # rows weighted by 1/σ of the smoothed force (step 1's own uncertainty): the samples where the
        # smoother cannot follow the force (rudder moving, Q raised) count less (module docstring)
        if not (config.weights == "smoother" or config.weights == mode):
            return ridge(H, y, config.ridge_k, **kw)
        w = 1.0 / np.maximum(s, 1e-300)
        w = w / np.mean(w)
        return ridge(H * w[:, None], y * w, config.ridge_k, **kw)

    with warnings.catch_warnings():  # non-convergence is reported by build_result's warnings
        warnings.simplefilter("ignore", RuntimeWarning)
        fx = wls(d.HX, d.X, d.sX, "surge")
        fy = wls(d.HY, d.Y, d.sY, "sway")
        fn = wls(d.HN, d.N, d.sN, "yaw")
    return EbmFit(surge=fx, sway=fy, yaw=fn, alpha=slope_alpha(d.v, d.r, p.L), data=d)


def approach_condition(states: Sequence[StateEstimate], config: EbmConfig = EbmConfig()
                       ) -> tuple[float, float, list[dict]]:
    """Approach speed ``U0`` (m/s through the water) and propeller rate ``n0`` (1/s) from the trials.

    ``c0`` of the rudder regressor (eq. 15; :mod:`shipid.models.abkowitz`) is the rudder
    inflow speed of the straight approach run. It is measured, not derived from packaged
    coefficients: per trial, the smoothed ``u_r`` (step 1, which uses no hydrodynamic
    coefficient) and the measured propeller-rate channel ``n`` averaged over the first
    ``config.approach_s`` seconds, then averaged over the trials.
    ``config.approach_speed`` / ``config.approach_rate`` (a user's measured values) replace them.
    Returns ``(U0, n0, per_trial)``.
    """
    per = []
    for st in states:
        t = st.smooth.t - st.smooth.t[0]
        w = t <= max(float(config.approach_s), 0.0)
        w[0] = True
        per.append({"U0": float(np.mean(st.smooth.x[w, 0])), "n0": float(np.mean(np.asarray(st.trial["n"])[w]))})
    U0 = float(np.mean([d["U0"] for d in per])) if config.approach_speed is None else float(config.approach_speed)
    n0 = float(np.mean([d["n0"] for d in per])) if config.approach_rate is None else float(config.approach_rate)
    if not (np.isfinite(U0) and U0 > 0 and np.isfinite(n0) and n0 > 0):
        raise InputError(f"EBM needs a straight approach run ahead at positive speed and propeller rate "
                         f"(found u_r {U0:.3g} m/s, n {n0:.3g} 1/s at the start of the trial)", channel="n")
    return U0, n0, per


__all__ = ["REQUIRED", "EbmConfig", "StateEstimate", "RegressionData", "EbmFit", "process_noise",
           "sensor_positions", "sensor_source", "measurements", "prior_cov", "estimate_states",
           "observability_report", "regression_data", "combined_coefficients", "slope_alpha",
           "fit_coefficients", "approach_condition"]
