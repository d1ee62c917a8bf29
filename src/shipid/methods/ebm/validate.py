"""Open-loop validation of an identified Abkowitz model (Yoon & Rhee 2003) on a held-out run.

The model of eqs. 1–3 and 12–15 (:mod:`shipid.models.abkowitz`) with the identified coefficient
vectors θ_X, θ_Y, θ_N of eq. 13, the approach condition (U0, n0, c0) and the current (U_c, ψ_c)
of the result, and the hull particulars of the result's vessel, is simulated open loop with the
run's measured rudder angle δ and propeller rate n (zero-order hold, RK4 with sub-steps of at
most 0.2 s).

Initial state at every start (the first sample, and each restarted horizon): not all of the
state is measured, so it is taken from the measurements of eq. 8 around the start (a straight
line fitted within ±``fit_half`` s to each channel, evaluated at the start):

* ψ from the gyro, ``r`` from the slope of ψ;
* the body-axis velocity over ground of the antenna from ``x_dot, y_dot``, less the current and
  the lever-arm terms: ``u_r = (ẋ_D cos ψ + ẏ_D sin ψ − c_x cos ψ − c_y sin ψ) + y_D r``,
  ``v_r = (−ẋ_D sin ψ + ẏ_D cos ψ + c_x sin ψ − c_y cos ψ) − x_D r``;
* the midship position from the antenna fix less the lever arm.

The prediction is compared in the measured quantities of eq. 8 (what the run records, at the
sensors' positions): heading ψ (deg, wrapped), antenna position (m, distance), antenna velocity
over ground (m/s, magnitude of the difference of ``(ẋ, ẏ)``) and the speed log ``u_r − y_S r``
(m/s). The lever arms ``x_D, y_D, y_S`` are the run's metadata, else those of the model's training
runs, else zero (body origin, with a warning).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from shipid.analysis.openloop import Validation, check_finite, error_table, local_fit, plot_series, wrap_deg
from shipid.io.trial import Trial
from shipid.errors import InputError
from shipid.models import abkowitz as ab
from shipid.result import Result
from shipid.numerics.integrate import rk4_step

#: Channels the run must have: the measurements of eq. 8 and the inputs δ, n.
REQUIRED = ("x", "y", "x_dot", "y_dot", "psi", "U", "delta", "n")
#: Measured columns compared with the prediction (eq. 8).
COLUMNS = ("x", "y", "x_dot", "y_dot", "psi", "U")
QUANTITIES = ("psi", "pos", "vel", "U")
UNITS = {"psi": "deg", "pos": "m", "vel": "m/s", "U": "m/s"}
#: Length of the restarted horizons, s.
DEFAULT_HORIZON = 60.0


def params_from_result(result: Result) -> ab.AbkowitzParams:
    """The identified ship: the vessel's particulars (mass, inertia, added mass, propeller), the
    result's θ_X, θ_Y, θ_N, approach condition and mean current."""
    m = result.model
    try:
        vessel = m["vessel"]
        est = result.estimates
        thX = [est[k].value for k in ab.THETA_X_NAMES]
        thY = [est[k].value for k in ab.THETA_Y_NAMES]
        thN = [est[k].value for k in ab.THETA_N_NAMES]
        U0, n0, c0 = float(m["U0"]), float(m["n0"]), float(m["c0"])
        cs, cd = est["current_speed"].value, est["current_direction"].value
    except KeyError as err:
        raise InputError(f"not an EBM result: it has no {err.args[0]!r}") from None
    p = ab.particulars_from_vessel(vessel)
    p = replace(p, U0=U0, n0=n0, c0=c0, yaw_rudder_variant=bool(m.get("yaw_rudder_variant", False)))
    return p.with_theta(thX, thY, thN).with_current(cs, cd)


def levers(trial: Trial, result: Result | None = None) -> tuple[tuple[float, float, float], str]:
    """Sensor lever arms ``(x_D, y_D, y_S)`` (m) and where they came from.

    The run's metadata, else those of the result's training runs (the same installation, when
    they all agree), else the body origin.
    """
    keys = ("x_D", "y_D", "y_S")
    if all(k in trial.meta for k in keys):
        return tuple(float(trial.meta[k]) for k in keys), "run metadata"
    if result is not None:
        seen = {tuple(float(s.get(k, 0.0)) for k in keys)
                for s in (d.get("sensors") or {} for d in (result.diagnostics or {}).get("trials", []))}
        if len(seen) == 1:
            return seen.pop(), "the model's training runs"
    return (0.0, 0.0, 0.0), "not stated: body origin assumed"


def measured_columns(trial: Trial) -> np.ndarray:
    """``(n, 6)`` measured ``[x, y, x_dot, y_dot, ψ, U]`` of eq. 8."""
    return np.column_stack([np.asarray(trial[c], dtype=float) for c in COLUMNS])


def sensor_outputs(X: np.ndarray, p: ab.AbkowitzParams, lever) -> np.ndarray:
    """Eq. 8 (absolute positions) from states ``[u_r, v_r, r, x, y, ψ]`` (..., 6): ``[x_D, y_D, ẋ_D, ẏ_D, ψ, U]``."""
    xD, yD, yS = lever
    ur, vr, r, x, y, psi = (X[..., i] for i in range(6))
    c, s = np.cos(psi), np.sin(psi)
    cx, cy = p.current_xy
    a, b = ur - yD * r, vr + xD * r
    return np.stack([x + xD * c - yD * s, y + xD * s + yD * c, a * c - b * s + cx, a * s + b * c + cy,
                     psi, ur - yS * r], axis=-1)


def initial_states(trial: Trial, starts: np.ndarray, p: ab.AbkowitzParams, fit_half: float,
                   lever: tuple[float, float, float]) -> np.ndarray:
    """States ``[u_r, v_r, r, x, y, ψ]`` at ``starts`` from the measurements around them (module docstring)."""
    t = np.asarray(trial.t, dtype=float)
    xD, yD, _ = lever
    psi, r = local_fit(t, np.unwrap(np.asarray(trial["psi"], dtype=float)), starts, fit_half)
    xa, _ = local_fit(t, trial["x"], starts, fit_half)
    ya, _ = local_fit(t, trial["y"], starts, fit_half)
    xd, _ = local_fit(t, trial["x_dot"], starts, fit_half)
    yd, _ = local_fit(t, trial["y_dot"], starts, fit_half)
    cx, cy = p.current_xy
    c, s = np.cos(psi), np.sin(psi)
    ub = (xd - cx) * c + (yd - cy) * s
    vb = -(xd - cx) * s + (yd - cy) * c
    return np.column_stack([ub + yD * r, vb - xD * r, r, xa - (xD * c - yD * s), ya - (xD * s + yD * c), psi])


def _errors(pred: np.ndarray, meas: np.ndarray) -> dict[str, np.ndarray]:
    return {"psi": wrap_deg(pred[..., 4] - meas[..., 4]),
            "pos": np.hypot(pred[..., 0] - meas[..., 0], pred[..., 1] - meas[..., 1]),
            "vel": np.hypot(pred[..., 2] - meas[..., 2], pred[..., 3] - meas[..., 3]),
            "U": pred[..., 5] - meas[..., 5]}


def validate(p: ab.AbkowitzParams, trial: Trial, *, horizon: float = DEFAULT_HORIZON, stride: float | None = None,
             windows: tuple[float, ...] = (30.0, 60.0), whole: bool = True, fit_half: float = 5.0,
             model_name: str = "abkowitz", lever: tuple[float, float, float] | None = None,
             lever_source: str = "") -> Validation:
    """Simulate the Abkowitz ship ``p`` open loop on ``trial`` and compare (module docstring).

    ``lever``: the sensor lever arms ``(x_D, y_D, y_S)``, m (default :func:`levers` of the run).
    """
    trial.require(list(REQUIRED), method="validate ebm")
    src = trial.meta.get("source")
    check_finite(src, {c: trial[c] for c in REQUIRED})
    t = np.asarray(trial.t, dtype=float)
    U = np.column_stack([trial["delta"], trial["n"]]).astype(float)
    Z = measured_columns(trial)
    if lever is None:
        lever, lever_source = levers(trial)
    dt = float(np.median(np.diff(t)))
    sub = max(1, int(np.ceil(dt / 0.2 - 1e-9)))
    h = dt / sub
    f = ab.make_dynamics(p)

    def simulate(starts: np.ndarray, L: int) -> np.ndarray:
        X0 = initial_states(trial, starts, p, fit_half, lever)
        out = np.full((starts.size, L, 6), np.nan)
        with np.errstate(all="ignore"):
            for i, (k0, x) in enumerate(zip(starts, X0)):
                out[i, 0] = x
                for j in range(1, L):
                    u = U[min(k0 + j - 1, t.size - 1)]
                    for _ in range(sub):
                        x = rk4_step(f, 0.0, x, u, p, h)
                    if not np.all(np.isfinite(x)):
                        break
                    out[i, j] = x
        return sensor_outputs(out, p, lever)

    win, hz, pred = error_table(t, Z, simulate, _errors, QUANTITIES, UNITS, horizon=horizon, stride=stride,
                                windows=windows, whole=whole)
    settings = {"levers_m": dict(zip(("x_D", "y_D", "y_S"), lever)), "levers_from": lever_source,
                "current": {"speed_m_s": p.current_speed, "direction_rad": p.current_dir},
                "initial_state": f"straight-line fit within +-{fit_half:g} s of each start",
                "substeps": sub}
    if lever_source.startswith("not stated"):
        settings["warnings"] = [f"{src or 'the run'} states no sensor positions: DGPS antenna and speed log "
                                "taken at the body origin"]
    return Validation(windows=win, horizons=hz, t=t[:pred.shape[0]], measured=Z[:pred.shape[0]], predicted=pred,
                      model_name=model_name, source=str(src or ""), quantities=QUANTITIES, units=UNITS,
                      method="ebm", columns=COLUMNS, settings=settings)


def validate_result(result: Result, trial: Trial, *, horizon: float | None = None, **kw) -> Validation:
    """The common entry of every method's ``validate`` module: :func:`validate` on the ship of an
    ``identify("ebm", ...)`` result (every coefficient of eq. 13 as estimated, also those the
    training data did not determine)."""
    name = f"ebm ({result.model.get('vessel', '?')})"
    lever, source = levers(trial, result)
    kw.setdefault("lever", lever)
    kw.setdefault("lever_source", source)
    return validate(params_from_result(result), trial, horizon=DEFAULT_HORIZON if horizon is None else horizon,
                    model_name=kw.pop("model_name", name), **kw)


def plot(v: Validation, path, *, force: bool = False):
    """Antenna track, heading, antenna speed over ground and speed log, measured vs predicted."""
    return plot_series(v, path, [(4, np.degrees, "ψ [deg]"), (2, lambda a: a, "ẋ_D [m/s]"),
                                 (3, lambda a: a, "ẏ_D [m/s]"), (5, lambda a: a, "U (log) [m/s]")],
                       trajectory=(0, 1), force=force)


__all__ = ["validate", "validate_result", "params_from_result", "initial_states", "sensor_outputs",
           "measured_columns", "levers", "plot", "REQUIRED", "COLUMNS", "QUANTITIES", "UNITS", "DEFAULT_HORIZON"]
