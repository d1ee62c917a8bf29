"""Identify an MMG model from real free-running runs: estimation-before-modelling adapted to real logs.

The two steps of Yoon & Rhee (2003, §§2–4) with what the Esso Osaka and
KVLCC2 logs measure (midship position, heading, u, v, r; no current in the pond or
tank, so no current states):

1. **Motion estimation.** A continuous–discrete EKF (:func:`shipid.estimate.cd_ekf.cd_ekf`,
   eq. 9) on a kinematic model with the accelerations as states driven by white jerk
   noise, ``s = [x0, y0, ψ, u, v, r, u̇, v̇, ṙ]``::

       ẋ0 = u cos ψ − v sin ψ,  ẏ0 = u sin ψ + v cos ψ,  ψ̇ = r,
       u̇, v̇, ṙ = states,  d/dt (u̇, v̇, ṙ) = w,  E[w wᵀ] = diag(q_u, q_v, q_r) δ(t − s)

   with measurements ``z = [x0, y0, ψ, u, v, r]``, followed by the RTS fixed-interval
   smoother (:func:`shipid.estimate.smoothers.rts_smoother`; eq. 10 gives the same
   estimates on this nearly linear model). The paper's force states (its eqs. 5–6) are
   replaced by acceleration states: the forces then follow from the equations of
   motion with the known masses, ``X = (m + m_x) u̇ − (m + m_y) v r − x_G m r²`` etc.
   (:func:`shipid.models.mmg.rigid_body_forces`), which is the same information
   without a force model in the filter.
2. **Modelling.** With the smoothed motion and the measured inputs, every mode is
   linear in its coefficients, ``F − F_fixed = H θ`` (:func:`shipid.models.mmg.basis`),
   and θ is estimated per mode by ridge regression with Hoerl–Kennard's biasing
   parameter on unit-length-scaled regressors (§4, eqs. 16–18,
   :func:`shipid.estimate.ridge.ridge`). Coefficients not free in the chosen structure
   stay at the prior model's values and their forces move into ``F_fixed``.

What stays fixed (taken from the prior model): the masses and added masses, the
shape constants of the sub-models (wake fraction law, rudder inflow/straightening
constants, open-water curve that drives the rudder slipstream, Fujiwara wind
coefficients). For the Esso Osaka these come from the published set, which its
authors identified from runs of the same data set — stated in every Result.

Structure selection: :func:`cross_validate` fits every candidate of :data:`CANDIDATES`
(sets of free coefficients, the hull structure — the low-speed hull vs the standard
MMG cubic hull expanded about forward speed —, the regression weighting, dimensional
vs non-dimensional forces (:func:`row_weights`), and for the standard MMG the
flow-straightening γ_R treatment) without each fold's runs and scores it on them,
errors pooled over all folds; :func:`select_structure` does it with 60-s horizons
restarted from the measured state (:func:`shipid.methods.mmg.validate.validate`, score =
RMS ψ/10° + RMS position/1 m), leave-one-run-out by default. Only training runs are
ever passed in. The candidate lists are full factorial designs over axes fixed a
priori; the reasons for each axis, the frozen hyper-parameters and the CV tables are
in ``docs/validation/mmg.md``.

Why a low-speed structure for the Esso Osaka: the random and berthing runs spend
most of their time below 0.2 m/s (median speed 0.11 m/s on the random runs, against
about 0.5 m/s service speed), with drift angles beyond 90° and reversed propeller. A
hull expanded in ``v' = v/U``, ``r' = rL/U`` about forward motion (Abkowitz, or the
standard MMG) scales every force with U² and has no term for the cross-flow drag of a
ship moving sideways; the low-speed hull (drag blending with |β|, cross-flow
integrals) holds at any drift angle. The leave-one-run-out CV on the training runs
agrees: the best low-speed candidate scores 1.84 against 2.38 for the best cubic-hull
one on the Miyauchi training runs, 1.95 against 2.10 on the Wakita training runs
(tables in ``docs/validation/mmg.md``).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

from shipid.io.trial import Trial
from shipid.errors import InputError, ShipidError
from shipid.estimate.cd_ekf import cd_ekf
from shipid.estimate.ridge import RidgeFit, ridge
from shipid.estimate.smoothers import rts_smoother
from shipid.methods.mmg.candidates import CANDIDATES, apply_candidate, candidate_config  # noqa: F401
from shipid.models import mmg
from shipid.result import Estimate, Result
from shipid.methods.mmg.validate import trial_inputs
from shipid.methods.mmg.kernels import kinematic_filter_smoother
from shipid.methods.mmg.validate import validate

# ----------------------------------------------------------------------------- step 1
MEAS = ("x", "y", "psi", "u", "v", "r")


@dataclass(frozen=True)
class SmoothConfig:
    """Noise model of step 1.

    Measurement standard deviations (position m, heading rad, u/v m/s, r rad/s) and
    the white-jerk spectral densities of the acceleration states. The defaults suit the
    GNSS-based 10 Hz Esso Osaka logs (mean NIS 0.4–1.6 of 6 on the Miyauchi training
    runs: conservative); on the 20 Hz KVLCC2 tank logs they are very conservative
    (NIS ≈ 0.02), which smooths more but changed the identified overshoots by less than 0.2°.
    ``auto_sigma`` estimates the measurement noise from the data
    (:func:`noise_from_data`) instead; it is off by default because channels that the
    logger already low-passed (the KVLCC2 yaw rate) then get a far too small σ.
    """

    sigma_pos: float = 0.02
    sigma_psi: float = np.deg2rad(0.3)
    sigma_uv: float = 0.01
    sigma_r: float = np.deg2rad(0.2)
    q_u: float = 1e-4
    q_v: float = 1e-4
    q_r: float = 1e-5
    auto_sigma: bool = False


def noise_from_data(z: np.ndarray) -> np.ndarray:
    """Measurement noise standard deviations per channel from the data themselves.

    For white noise of variance σ² on a signal smooth at the sampling rate, the second
    difference has variance 6σ²; the robust estimate ``σ = 1.4826 MAD(Δ²z) / √6`` ignores
    the few large second differences of real manoeuvres. A floor of 1e-6 (SI) keeps R
    positive definite on quantised or noiseless channels.
    """
    d2 = np.diff(z, n=2, axis=0)
    mad = np.nanmedian(np.abs(d2 - np.nanmedian(d2, axis=0)), axis=0)
    return np.maximum(1.4826 * mad / np.sqrt(6.0), 1e-6)


@dataclass(frozen=True)
class SmoothedRun:
    """Step-1 output for one run: smoothed motion, accelerations and the measured inputs."""

    t: np.ndarray
    s: np.ndarray                 # (n, 9) smoothed [x0, y0, ψ, u, v, r, u̇, v̇, ṙ]
    s_std: np.ndarray             # (n, 9)
    inputs: np.ndarray            # (n, 4) [δ, n, U_T, γ_T]
    source: str
    nis_mean: float
    loglik: float
    sigma: np.ndarray             # (6,) measurement noise standard deviations used


def kinematic_f(t, s, u, theta):
    """The 9-state kinematic model of step 1 as ``f(t, x, u, θ)`` (autonomous, no input, no parameter):
    ``s = [x0, y0, ψ, u, v, r, u̇, v̇, ṙ]``, white jerk noise enters the last three."""
    psi, u, v, r = s[2], s[3], s[4], s[5]
    c, sn = np.cos(psi), np.sin(psi)
    return np.array([u * c - v * sn, u * sn + v * c, r, s[6], s[7], s[8], 0.0, 0.0, 0.0])


def kinematic_F(t, s, u, theta):
    """∂f/∂s of :func:`kinematic_f`."""
    psi, u, v = s[2], s[3], s[4]
    c, sn = np.cos(psi), np.sin(psi)
    F = np.zeros((9, 9))
    F[0, 2], F[0, 3], F[0, 4] = -u * sn - v * c, c, -sn
    F[1, 2], F[1, 3], F[1, 4] = u * c - v * sn, sn, c
    F[2, 5] = 1.0
    F[3, 6] = F[4, 7] = F[5, 8] = 1.0
    return F


_H = np.zeros((6, 9))
_H[np.arange(6), np.arange(6)] = 1.0


def measurements(trial: Trial) -> np.ndarray:
    """Step 1's measurement matrix ``(n, 6)`` of :data:`MEAS`, the heading unwrapped (no wrap in the innovations)."""
    z = np.stack([np.asarray(trial[c], float) for c in MEAS], axis=-1)
    z[:, 2] = np.unwrap(z[:, 2])
    return z


def smooth_run(trial: Trial, config: SmoothConfig = SmoothConfig(), *, compiled: bool = True) -> SmoothedRun:
    """Step 1 on one run: kinematic CD-EKF and RTS smoother (module docstring).

    ``compiled``: the fused compiled pass :func:`shipid.methods.mmg.kernels.kinematic_filter_smoother`
    (same algorithm, equal to rounding); False runs the reference
    :func:`~shipid.estimate.cd_ekf.cd_ekf` and :func:`~shipid.estimate.smoothers.rts_smoother`.
    """
    trial.require(list(MEAS) + ["delta", "n"], method="identify mmg")

    z = measurements(trial)
    t = np.asarray(trial.t, float) - float(trial.t[0])
    c = config
    sig = np.array([c.sigma_pos, c.sigma_pos, c.sigma_psi, c.sigma_uv, c.sigma_uv, c.sigma_r])
    if c.auto_sigma:
        sig = noise_from_data(z)
    R = np.diag(sig) ** 2
    Q = np.zeros((9, 9))
    Q[6, 6], Q[7, 7], Q[8, 8] = c.q_u, c.q_v, c.q_r
    x0 = np.concatenate([np.nan_to_num(z[0]), np.zeros(3)])
    P0 = np.diag(np.concatenate([sig, [0.05, 0.05, 0.01]])) ** 2
    out = None
    try:
        if compiled:
            out = kinematic_filter_smoother(t, z, Q, R, x0, P0)
        if out is None:
            fr = cd_ekf(kinematic_f, kinematic_F, lambda tt, s: _H @ s, lambda tt, s: _H, Q, R, t, z, x0, P0)
            sm = rts_smoother(fr)
            out = (sm.x, sm.std, fr.nis, float(fr.loglik))
    except Exception as err:   # a filter breakdown is reported in one line, never a traceback
        raise ShipidError(f"motion estimation failed on {trial.meta.get('source', 'run')}: {err}") from None
    xs, std, nis, loglik = out
    return SmoothedRun(t=np.asarray(trial.t, float), s=xs, s_std=std, inputs=trial_inputs(trial),
                       source=str(trial.meta.get("source", "")), nis_mean=float(np.nanmean(nis)),
                       loglik=float(loglik), sigma=sig)


# ----------------------------------------------------------------------------- step 2
@dataclass(frozen=True)
class FitConfig:
    """Step-2 settings.

    ``decimate``: use every n-th sample (the smoothed forces are strongly
    correlated at 10–20 Hz); ``trim_s``: drop this many seconds at both ends of each
    run (smoother edge effects); ``ridge_k``: None for Hoerl–Kennard, 0 for OLS.

    ``equation``: ``"auto"`` (default) is :data:`EQUATION_BY_STRUCTURE` of the prior's structure;
    ``"differential"`` regresses the forces of the smoothed accelerations on
    the regressors at the same instant (Yoon & Rhee 2003, eq. 16); ``"integral"`` regresses the
    impulse over a window of ``window_s`` seconds — the change of smoothed momentum plus
    the time integral of the velocity-dependent rigid-body terms — on the time integrals
    of the regressors (:func:`regression_data`). The integral form needs no accelerations:
    the smoothed velocities follow the measured ones without the lag that the white-jerk
    smoother's accelerations have after a rudder step, which biased the differential form
    (:mod:`shipid.methods.mmg.coverage`). Windows start every ``decimate`` samples and last
    ``window_s`` seconds, by default :data:`WINDOW_FROUDE` units of ``√(L/g)`` (Froude-scaled time,
    so that a window spans the same part of a manoeuvre at model and full scale).
    """

    decimate: int = 5
    trim_s: float = 2.0
    ridge_k: float | None = None
    min_speed: float = 0.0
    weighting: str = "none"
    U_ref: float = 0.1
    equation: str = "auto"
    window_s: float | None = None


#: Default window of the integral equation in units of √(L/g): 10 s for the Esso Osaka 3 m, 15.3 s for
#: the 7-m KVLCC2, 86 s for a 300-m ship. Long windows weight the low-frequency content, where an unmodelled
#: steady yaw moment dominates; short ones keep the errors-in-variables bias of the differential form. The
#: evidence behind the value is in docs/validation/mmg.md ("Step-2 form and window").
WINDOW_FROUDE = 18.0


#: Step-2 form per prior structure under ``FitConfig(equation="auto")``: the integral form for the Esso
#: low-speed hull, the differential form for the KVLCC2 (Yasukawa 2015) structure, whose results are checked
#: against the integral form (:func:`shipid.methods.mmg.pipeline.form_check`, a disagreement said). The
#: evidence for each choice is in docs/validation/mmg.md ("Step-2 form and window").
#: Structures not listed: integral.
EQUATION_BY_STRUCTURE = {"esso-lowspeed": "integral", "yasukawa2015": "differential"}


def equation_for(config: "FitConfig", prior: mmg.MmgModel) -> str:
    """The step-2 form ``config`` asks for on ``prior`` (``"auto"``: :data:`EQUATION_BY_STRUCTURE`)."""
    if config.equation == "auto":
        return EQUATION_BY_STRUCTURE.get(prior.structure, "integral")
    return config.equation


def integral_window(config: "FitConfig", L: float) -> float:
    """The integral-equation window in seconds: ``config.window_s`` or :data:`WINDOW_FROUDE` · √(L/g)."""
    return float(config.window_s) if config.window_s is not None else WINDOW_FROUDE * float(np.sqrt(L / 9.80665))


def row_weights(u: np.ndarray, v: np.ndarray, r: np.ndarray, L: float, config: "FitConfig") -> np.ndarray:
    """Regression row weights.

    ``"none"``: ordinary (dimensional) least squares, dominated by the fastest samples
    since forces grow with U². ``"nondimensional"``: each row divided by
    ``U² + (L r/2)² + U_ref²`` — the regression of non-dimensional forces, so that the
    low-speed (berthing) samples count as much as the fast ones; ``U_ref`` keeps the
    weight finite at rest.
    """
    if config.weighting == "none":
        return np.ones_like(u)
    if config.weighting == "nondimensional":
        return 1.0 / (u * u + v * v + (0.5 * L * r) ** 2 + config.U_ref ** 2)
    raise InputError(f"unknown weighting '{config.weighting}' (none, nondimensional)")


@dataclass(frozen=True)
class ModeData:
    H: np.ndarray
    y: np.ndarray
    names: tuple[str, ...]


def regression_data(runs: Sequence[SmoothedRun], prior: mmg.MmgModel, free: Mapping[str, Sequence[str]],
                    config: FitConfig = FitConfig()) -> dict[str, ModeData]:
    """Stack the step-2 regression of all runs: ``y = F − F_fixed − H_fixed θ_fixed`` on ``H_free``."""
    parts: dict[str, list] = {m: ([], []) for m in mmg.MODES}
    allnames = mmg.COEFS[prior.structure]
    for mode in mmg.MODES:
        bad = [c for c in free[mode] if c not in allnames[mode]]
        if bad:
            raise InputError(f"{mode}: not a coefficient of the {prior.structure} structure: {', '.join(bad)}")
    if config.equation not in ("auto", "differential", "integral"):
        raise InputError(f"unknown equation '{config.equation}' (auto, differential, integral)")
    integral = equation_for(config, prior) == "integral"
    split = {}                                  # per mode: indices of the free and of the fixed coefficients
    for mode in mmg.MODES:
        names = allnames[mode]
        idx_free = [names.index(c) for c in free[mode]]
        split[mode] = (idx_free, [i for i in range(len(names)) if i not in idx_free])
    for run in runs:
        dt = float(np.median(np.diff(run.t)))
        k0 = int(round(config.trim_s / dt))
        if integral:
            for mode, (H, y) in _integral_rows(run, prior, split, config, k0, dt).items():
                parts[mode][0].append(H)
                parts[mode][1].append(y)
            continue
        sel = np.arange(k0, run.t.size - k0, max(1, config.decimate))
        s = run.s[sel]
        U = run.inputs[sel]
        psi, u, v, r = s[:, 2], s[:, 3], s[:, 4], s[:, 5]
        if config.min_speed > 0:
            keep = np.hypot(u, v) >= config.min_speed
            s, U, psi, u, v, r = s[keep], U[keep], psi[keep], u[keep], v[keep], r[keep]
        UA, gA = mmg.apparent_wind(U[:, 2], U[:, 3], psi, u, v)
        b = mmg.basis(prior, u, v, r, U[:, 0], U[:, 1], UA, gA)
        F = mmg.rigid_body_forces(prior, u, v, r, s[:, 6], s[:, 7], s[:, 8])
        w = row_weights(u, v, r, prior.particulars["L"], config)
        for mode, Fm in zip(mmg.MODES, F):
            H, F0 = b[mode]
            idx_free, idx_fix = split[mode]
            th = prior.theta(mode)
            y = Fm - F0 - H[:, idx_fix] @ th[idx_fix]
            parts[mode][0].append(H[:, idx_free] * w[:, None])
            parts[mode][1].append(y * w)
    out = {}
    for mode in mmg.MODES:
        H = np.concatenate(parts[mode][0])
        y = np.concatenate(parts[mode][1])
        ok = np.all(np.isfinite(H), axis=1) & np.isfinite(y)
        out[mode] = ModeData(H=H[ok], y=y[ok], names=tuple(free[mode]))
    return out


def _integral_rows(run: SmoothedRun, prior: mmg.MmgModel, split: Mapping[str, tuple[list, list]],
                   config: FitConfig, k0: int, dt: float) -> dict:
    """One run's rows of the integral equation (``FitConfig.equation == "integral"``); ``split``: per mode
    the indices of the free and of the fixed coefficients (:func:`regression_data`).

    The rigid-body forces are linear in the accelerations,
    ``F = M (u̇, v̇, ṙ) + c(u, v, r)`` (:func:`shipid.models.mmg.rigid_body_forces`), so over a
    window ``[t_a, t_b]``::

        M (ν(t_b) − ν(t_a)) + ∫ c dt − ∫ F_fixed dt − (∫ H_fixed dt) θ_fixed = (∫ H_free dt) θ_free

    with the integrals by the trapezoidal rule on every sample interval of the smoothed run, the inputs
    held over each interval as the simulators hold them (:func:`shipid.models.mmg.simulate_batch`):
    the regressors at both ends of an interval are evaluated with its first sample's inputs. Each row's
    weight is the mean of :func:`row_weights` over its window; with ``min_speed`` a window is
    kept only if every sample in it is at least that fast. A window holding a non-finite
    sample is dropped (the caller drops non-finite rows).
    """
    n = run.t.size
    idx = np.arange(k0, n - k0)
    W = max(1, int(round(integral_window(config, prior.particulars["L"]) / dt)))
    if idx.size <= W:
        return {m: (np.zeros((0, len(split[m][0]))), np.zeros(0)) for m in mmg.MODES}
    s, U, t = run.s[idx], run.inputs[idx], run.t[idx]
    psi, u, v, r = s[:, 2], s[:, 3], s[:, 4], s[:, 5]
    # the regressors at both ends of each sample interval with that interval's (held) inputs
    ends = (slice(0, -1), slice(1, None))
    b = [mmg.basis(prior, u[j], v[j], r[j], U[:-1, 0], U[:-1, 1],
                   *mmg.apparent_wind(U[:-1, 2], U[:-1, 3], psi[j], u[j], v[j])) for j in ends]
    z = np.zeros_like(u)
    C = mmg.rigid_body_forces(prior, u, v, r, z, z, z)                 # velocity-dependent part c(u, v, r)
    a0 = np.arange(0, idx.size - W, max(1, config.decimate))
    a1 = a0 + W
    dnu = s[a1, 3:6] - s[a0, 3:6]
    zw = np.zeros(a0.size)
    M = mmg.rigid_body_forces(prior, zw, zw, zw, dnu[:, 0], dnu[:, 1], dnu[:, 2])   # M Δν
    h = np.diff(t)

    def window_integral(Y0, Y1):
        """∫ over each window, by the trapezoidal rule on the interval-end values ``Y0`` (left) and ``Y1``
        (right), each (n − 1,) or (n − 1, p); NaN where a value in the window is not finite."""
        shape = Y0.shape[1:]
        I = 0.5 * h.reshape((-1,) + (1,) * len(shape)) * (Y0 + Y1)
        I2 = I.reshape(I.shape[0], -1)
        bad = ~np.isfinite(I2)
        cum = np.concatenate([np.zeros((1, I2.shape[1])), np.cumsum(np.where(bad, 0.0, I2), axis=0)])
        nbad = np.concatenate([np.zeros((1, I2.shape[1])), np.cumsum(bad, axis=0)])
        out = cum[a1] - cum[a0]
        out[(nbad[a1] - nbad[a0]) > 0] = np.nan
        return out.reshape((a0.size,) + shape)

    w = row_weights(u, v, r, prior.particulars["L"], config)
    cw = np.concatenate([[0.0], np.cumsum(w)])
    wr = (cw[a1 + 1] - cw[a0]) / (W + 1)
    if config.min_speed > 0:
        slow = np.concatenate([[0], np.cumsum(np.hypot(u, v) < config.min_speed)])
        wr = np.where(slow[a1 + 1] - slow[a0] > 0, np.nan, wr)
    out = {}
    for mode, Mm, Cm in zip(mmg.MODES, M, C):
        idx_free, idx_fix = split[mode]
        th = prior.theta(mode)
        rest = [Cm[j] - F0 - H[:, idx_fix] @ th[idx_fix] for j, (H, F0) in zip(ends, (b[0][mode], b[1][mode]))]
        y = Mm + window_integral(*rest)
        Hf = window_integral(b[0][mode][0][:, idx_free], b[1][mode][0][:, idx_free])
        out[mode] = (Hf * wr[:, None], y * wr)
    return out


def _ridge_safe(H: np.ndarray, y: np.ndarray, k: float | None, mode: str) -> RidgeFit:
    """Ridge with Hoerl–Kennard's k for one mode; any warning of the fit (a runaway k
    iteration falls back to the one-step k with ``converged`` False, see
    :func:`shipid.estimate.ridge.hoerl_kennard_k`) is re-issued naming the mode."""
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fit = ridge(H, y, k)
    for w in caught:
        warnings.warn(f"mode {mode}: {w.message}", w.category, stacklevel=3)
    return fit


@dataclass(frozen=True)
class MmgFit:
    """Step-2 output: the identified model and the ridge fit of each mode."""

    model: mmg.MmgModel
    fits: dict[str, RidgeFit]
    free: dict[str, tuple[str, ...]]
    dropped: dict[str, tuple[str, ...]]


def fit(runs: Sequence[SmoothedRun], prior: mmg.MmgModel, free: Mapping[str, Sequence[str]],
        config: FitConfig = FitConfig(), name: str = "mmg-identified",
        data: Mapping[str, ModeData] | None = None) -> MmgFit:
    """Ridge regression of every mode (module docstring, step 2).

    A free coefficient whose regressor is identically zero in the data (a regime
    never visited, e.g. astern propeller side force in runs without reversing) cannot
    be estimated: it is kept at the prior value and listed in ``dropped``. ``data``: the
    :func:`regression_data` of ``runs`` when the caller has it already (cross-validation
    stacks per-run blocks once instead of once per fold).
    """
    free = {m: tuple(free[m]) for m in mmg.MODES}
    data = regression_data(runs, prior, free, config) if data is None else data
    new, fits, dropped, used = {}, {}, {}, {}
    for mode in mmg.MODES:
        d = data[mode]
        colnorm = np.sqrt(np.sum(d.H ** 2, axis=0))
        ok = colnorm > 1e-12 * max(colnorm.max(), 1e-300)
        # regimes visited in fewer than 20 samples are not estimable either
        ok &= np.count_nonzero(np.abs(d.H) > 1e-12 * max(colnorm.max(), 1e-300), axis=0) >= 20
        names = tuple(n for n, k in zip(d.names, ok) if k)
        dropped[mode] = tuple(n for n, k in zip(d.names, ok) if not k)
        if not names:
            continue
        H = d.H[:, ok]
        # the dropped coefficients' forces (at prior values) belong to the fixed part
        y = d.y - d.H[:, ~ok] @ np.array([prior.coef[n] for n in dropped[mode]]) if dropped[mode] else d.y
        f = _ridge_safe(H, y, config.ridge_k, mode)
        fits[mode] = f
        used[mode] = names
        new.update(dict(zip(names, f.theta)))
    model = prior.with_coef(new, name=name)
    return MmgFit(model=model, fits=fits, free=used, dropped=dropped)


# ----------------------------------------------------------------------------- selection
def subsample(trial: Trial, k: int) -> Trial:
    """Every ``k``-th sample of a trial (the simulator holds the inputs over the longer step)."""
    if k <= 1:
        return trial
    return Trial(trial.t[::k], {c: trial[c][::k] for c in trial.channels}, trial.units, trial.meta)


def heldout_score(model: mmg.MmgModel, trials: Sequence[Trial], horizon: float = 60.0,
                  decimate: int = 1) -> dict[str, float]:
    """Pooled RMS heading (deg) and position (m) errors over restarted horizons on ``trials``.

    ``decimate``: simulate on every n-th sample (cheaper; used inside cross-validation).
    Returns ``psi``, ``pos``, ``score`` (:func:`horizon_score`) and ``count`` (horizons).
    """
    se = horizon_sse(model, trials, horizon, decimate)
    n = se["psi"][1]
    if n == 0:
        return {"psi": float("nan"), "pos": float("nan"), "score": float("nan"), "count": 0}
    out = {q: float(np.sqrt(se[q][0] / n)) for q in ("psi", "pos")}
    out["score"] = horizon_score(out)
    out["count"] = int(n)
    return out


def horizon_score(rms: Mapping[str, float]) -> float:
    """CV score of the horizon criteria: RMS ψ / 10° + RMS position / 1 m (10° of heading ~ 1 m of position)."""
    return float(rms["psi"] / 10.0 + rms["pos"] / 1.0)


def horizon_sse(model: mmg.MmgModel, trials: Sequence[Trial], horizon: float = 60.0,
                decimate: int = 1) -> dict[str, tuple[float, int]]:
    """``{"psi" | "pos": (sum of horizon-weighted squared RMS, horizon count)}`` for pooling."""

    se = {"psi": 0.0, "pos": 0.0}
    n = 0
    for tr in trials:
        tr = subsample(tr, decimate)
        h = validate(model, tr, horizon=horizon, windows=(), whole=False).horizons
        if h["count"] == 0:
            continue
        for q in se:
            se[q] += h["count"] * h[q]["rms"] ** 2
        n += h["count"]
    return {q: (v, n) for q, v in se.items()}


def fold_groups(n: int, folds: int | None) -> list[list[int]]:
    """Run indices of each CV fold: leave-one-run-out (``folds`` None) or ``folds`` interleaved groups
    (run ``i`` in fold ``i mod k``; the split lists are ordered by manoeuvre type, so every fold mixes types)."""
    k = n if folds is None else max(2, min(folds, n))
    return [list(range(i, n, k)) for i in range(k)]


def cross_validate(runs: Sequence[SmoothedRun], prior: mmg.MmgModel, candidates: Mapping[str, Mapping],
                   fold_errors, combine, *, config: FitConfig = FitConfig(), folds: int | None = None,
                   progress=None) -> dict[str, dict]:
    """Cross-validation of every candidate over the training runs, errors pooled over all folds.

    Parameters
    ----------
    runs : sequence of SmoothedRun
        The TRAINING runs (nothing else is ever passed here).
    fold_errors : callable
        ``fold_errors(model, test_idx, train_idx) -> {quantity: (sum of squares, count)}``:
        the errors of the model fitted without the runs ``test_idx`` on those runs.
    combine : callable
        ``combine({quantity: pooled RMS}) -> score`` (lower is better).

    Returns
    -------
    dict
        Per candidate: ``score``, the pooled RMS of every quantity, ``count`` and
        ``folds``. A candidate whose fit or prediction fails (or diverges) in any fold
        scores infinity: a structure that cannot be fitted on part of the data is not chosen.
    """
    groups = fold_groups(len(runs), folds)
    table: dict[str, dict] = {}
    for cname, cand in candidates.items():
        cprior, free = apply_candidate(prior, cand)
        cfg = candidate_config(config, cand)
        acc: dict[str, list[float]] = {}
        failed = False
        for g in groups:
            tr_idx = [i for i in range(len(runs)) if i not in g]
            if not tr_idx:
                continue
            try:
                m = fit([runs[i] for i in tr_idx], cprior, free, cfg).model
                errs = fold_errors(m, g, tr_idx)
            except (ShipidError, np.linalg.LinAlgError, ValueError):
                failed = True
                errs = {}
            for q, (sse, cnt) in errs.items():
                a = acc.setdefault(q, [0.0, 0])
                a[0] += sse
                a[1] += cnt
            if progress is not None:
                progress()
        rms = {q: (float(np.sqrt(a[0] / a[1])) if a[1] else float("nan")) for q, a in acc.items()}
        score = combine(rms) if rms and not failed else float("inf")
        if not np.isfinite(score):
            score = float("inf")
        row = {"score": float(score), "folds": len(groups)}
        row.update({f"{q}_rms": v for q, v in rms.items()})
        row["count"] = int(max((a[1] for a in acc.values()), default=0))
        table[cname] = row
    return table


__all__ = ["SmoothConfig", "SmoothedRun", "measurements", "smooth_run", "FitConfig", "EQUATION_BY_STRUCTURE", "equation_for",
           "WINDOW_FROUDE", "integral_window", "CANDIDATES", "regression_data", "fit",
           "kinematic_f", "kinematic_F", "apply_candidate", "candidate_config", "row_weights", "subsample",
           "noise_from_data", "MmgFit", "heldout_score", "horizon_sse", "horizon_score", "fold_groups", "cross_validate"]
