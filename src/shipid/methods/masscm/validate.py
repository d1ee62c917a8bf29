"""Open-loop validation of an identified roll model (Linder et al. 2015) on a held-out run.

The reduced roll model (23)–(26) of the run's loading condition, with the estimated physical
parameters (30) (``k, A_x, d, K_r, K_vdot, K_delta, z_f`` and the load ``m, zm_bar``) and the
known particulars of the result, is discretised by the bilinear transform (32)–(33)
(:func:`shipid.models.roll_reduced.discrete_coeffs`) and run as a simulation, not a one-step
predictor::

    ŷ_t = −ᾱ1 ŷ_{t−1} − ᾱ2 ŷ_{t−2} + β̄0 (a_t − a_{t−2}) + κ̄0 (r_t − r_{t−2}) + γ̄0 (δ_t − δ_{t−2})

driven by the measured tangential acceleration ``a_s``, yaw rate ``r`` and rudder angle ``δ``
(the inputs of (25)) and started from the measured roll rate at the two samples before each start
(a straight line fitted within ±``fit_half`` s, so that gyro noise does not start an oscillation). ``ŷ`` is
the roll rate ``p`` (ERRATA 000: (25) maps to p). Where the run records the roll angle ``phi``
the predicted angle is the measured one before the start plus the trapezoidal integral of ``ŷ``.

Compared: roll rate ``p`` (deg/s) and, where recorded, roll angle ``phi`` (deg), over the first
30 s and 60 s, the whole run and restarted horizons (default 10 s: the records of §5 are 60 s).
The loading condition is the ``condition=`` given, else the run's ``meta["condition"]``, else
``loaded`` (the condition whose load was estimated).
"""

from __future__ import annotations

import numpy as np

from shipid.analysis.openloop import Validation, check_finite, error_table, local_fit, plot_series
from shipid.io.trial import Trial
from shipid.errors import InputError
from shipid.models.roll_reduced import LOADED, THETA_NAMES, KnownParams, discrete_coeffs
from shipid.result import Result

#: Channels the run must have (the measured inputs and output of (25)).
REQUIRED = ("p", "a_s", "r", "delta")
UNITS = {"p": "deg/s", "phi": "deg"}
#: Length of the restarted horizons, s.
DEFAULT_HORIZON = 10.0


def model_from_result(result: Result) -> tuple[np.ndarray, KnownParams]:
    """``(theta, known)``: the estimated parameters (30) in :data:`THETA_NAMES` order and the known particulars."""
    try:
        theta = np.array([result.estimates[n].value for n in THETA_NAMES], dtype=float)
        known = KnownParams(**result.model["known"])
    except KeyError as err:
        raise InputError(f"not a mass-cm result: it has no {err.args[0]!r}") from None
    except TypeError as err:
        raise InputError(f"mass-cm result: malformed 'model.known' ({err})") from None
    return theta, known


def discrete_model(theta: np.ndarray, known: KnownParams, condition: str, T: float) -> np.ndarray:
    """``g = [ᾱ1, ᾱ2, β̄0, κ̄0, γ̄0]`` of (36) for one loading condition and sample period ``T``."""
    try:
        return np.asarray(discrete_coeffs(theta, known, [condition], T)[0], dtype=float)
    except ValueError as err:
        raise InputError(f"validate mass-cm: {err}") from None


def validate(theta: np.ndarray, known: KnownParams, trial: Trial, *, condition: str | None = None,
             horizon: float = DEFAULT_HORIZON, stride: float | None = None,
             windows: tuple[float, ...] = (30.0, 60.0), whole: bool = True, fit_half: float = 0.1,
             model_name: str = "roll model") -> Validation:
    """Simulate the roll model (33) of ``theta`` open loop on ``trial`` and compare (module docstring)."""
    trial.require(list(REQUIRED), method="validate mass-cm")
    src = trial.meta.get("source")
    check_finite(src, {c: trial[c] for c in REQUIRED})
    cond = condition or str(trial.meta.get("condition") or LOADED)
    t = np.asarray(trial.t, dtype=float)
    dt = float(np.median(np.diff(t)))
    g = discrete_model(theta, known, cond, dt)
    p = np.asarray(trial["p"], dtype=float)
    a, r, d = (np.asarray(trial[c], dtype=float) for c in ("a_s", "r", "delta"))
    has_phi = "phi" in trial and np.all(np.isfinite(trial["phi"]))
    phi = np.asarray(trial["phi"], dtype=float) if has_phi else None
    cols = ("p", "phi") if has_phi else ("p",)
    Z = np.column_stack([p, phi] if has_phi else [p])
    drive = np.zeros_like(p)
    drive[2:] = g[2] * (a[2:] - a[:-2]) + g[3] * (r[2:] - r[:-2]) + g[4] * (d[2:] - d[:-2])
    n = t.size

    def simulate(starts: np.ndarray, L: int) -> np.ndarray:
        val, slope = local_fit(t, p, starts - 1, fit_half)        # measured y_{s-1}, y_{s-2}, smoothed
        y1, y2 = val, val - slope * dt
        y1_0 = y1.copy()
        Y = np.empty((starts.size, L))
        with np.errstate(all="ignore"):
            for j in range(L):
                y = -g[0] * y1 - g[1] * y2 + drive[np.minimum(starts + j, n - 1)]
                Y[:, j] = y
                y1, y2 = y, y1
        if not has_phi:
            return Y[..., None]
        prev = np.concatenate([y1_0[:, None], Y], axis=1)
        Phi = phi[starts - 1][:, None] + np.cumsum(0.5 * dt * (prev[:, 1:] + prev[:, :-1]), axis=1)
        return np.stack([Y, Phi], axis=-1)

    def errors(pred: np.ndarray, meas: np.ndarray) -> dict[str, np.ndarray]:
        e = {"p": np.degrees(pred[..., 0] - meas[..., 0])}
        if has_phi:
            e["phi"] = np.degrees(pred[..., 1] - meas[..., 1])
        return e

    units = {q: UNITS[q] for q in cols}
    win, hz, pred = error_table(t, Z, simulate, errors, cols, units, horizon=horizon, stride=stride,
                                windows=windows, whole=whole, first=2)
    settings = {"condition": cond, "discrete_coefficients_eq36": dict(zip(
        ("alpha1_bar", "alpha2_bar", "beta0_bar", "kappa0_bar", "gamma0_bar"), map(float, g))),
        "sample_period_s": dt, "initial_state": f"roll rate at the two samples before each start, straight-line fit within +-{fit_half:g} s"}
    m = pred.shape[0]
    return Validation(windows=win, horizons=hz, t=t[2:2 + m], measured=Z[2:2 + m], predicted=pred,
                      model_name=model_name, source=str(src or ""), quantities=cols, units=units,
                      method="mass-cm", columns=cols, settings=settings)


def validate_result(result: Result, trial: Trial, *, horizon: float | None = None, **kw) -> Validation:
    """The common entry of every method's ``validate`` module: :func:`validate` on the roll model of an
    ``identify("mass-cm", ...)`` result (``condition=`` as in :func:`validate`)."""
    theta, known = model_from_result(result)
    name = kw.pop("model_name", f"roll model (m = {theta[7]:.4g} kg, zm_bar = {theta[8]:.4g} m)")
    return validate(theta, known, trial, horizon=DEFAULT_HORIZON if horizon is None else horizon,
                    model_name=name, **kw)


def plot(v: Validation, path, *, force: bool = False):
    """Roll rate (and roll angle), measured vs predicted."""
    panels = [(0, np.degrees, "p [deg/s]")]
    if "phi" in v.columns:
        panels.append((1, np.degrees, "φ [deg]"))
    return plot_series(v, path, panels, force=force)


__all__ = ["validate", "validate_result", "model_from_result", "discrete_model", "plot", "REQUIRED", "UNITS",
           "DEFAULT_HORIZON"]
