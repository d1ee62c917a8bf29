"""Open-loop validation of an identified DP low-frequency model (Fossen, Sagatun & Sørensen 1996) on a held-out run.

The LF model of eq. 8 with the kinematics of eqs. 13–14 (:func:`shipid.models.dp.lf_dynamics`),
with the identified θ1..θ9 of eqs. 46–47 converted to SI (eqs. 26–28) and the vessel's known
M'' (eq. 30) and thruster layout (eq. 29), is driven by the run's measured pitch ratios
``p1..p6`` and azimuth angle ``alpha6`` (zero-order hold, RK4 with sub-steps of at most 0.5 s).

Initial state at every start (the first sample and each restarted horizon): position and heading
and their rates from a straight line fitted to ``x, y, ψ`` within ±``fit_half`` s of the start;
the body velocity is ``ν = J(ψ)ᵀ η̇`` (eq. 14). The current ``ν_c`` and the slowly varying
environmental force (the bias ``b_h`` of eq. 37, which the estimator tracks per trial) are not
known for a held-out run and are taken as zero: an open-loop prediction drifts under them, and
the whole-run numbers say how much.

Compared: ``x``, ``y`` (m), heading ψ (deg, wrapped) and the position error (m, distance).
"""

from __future__ import annotations

import numpy as np

from shipid.analysis.openloop import Validation, check_finite, error_table, local_fit, plot_series, wrap_deg
from shipid.io.trial import Trial
from shipid.errors import InputError
from shipid.models import dp
from shipid.result import Result
from shipid.numerics.integrate import rk4_step
from shipid.vessels import load_vessel

#: Channels the run must have (positions, heading, pitch ratios, azimuth angle).
REQUIRED = ("x", "y", "psi", "p1", "p2", "p3", "p4", "p5", "p6", "alpha6")
COLUMNS = ("x", "y", "psi")
QUANTITIES = ("x", "y", "psi", "pos")
UNITS = {"x": "m", "y": "m", "psi": "deg", "pos": "m"}
#: Length of the restarted horizons, s.
DEFAULT_HORIZON = 60.0


def vessel_from_result(result: Result) -> dp.DPVessel:
    """The identified DP vessel: the result's vessel (M'', arms, p0, bis scales) with its θ1..θ9."""
    try:
        name = result.model["vessel"]
        theta = np.array([result.estimates[k].value for k in dp.THETA_NAMES], dtype=float)
    except KeyError as err:
        raise InputError(f"not a DP result: it has no {err.args[0]!r}") from None
    return dp.dp_vessel(load_vessel(name)).with_theta(theta)


def initial_states(trial: Trial, starts: np.ndarray, fit_half: float) -> np.ndarray:
    """LF states ``[x, y, ψ, u, v, r, 0, 0, 0]`` at ``starts`` (module docstring)."""
    t = np.asarray(trial.t, dtype=float)
    x, xd = local_fit(t, trial["x"], starts, fit_half)
    y, yd = local_fit(t, trial["y"], starts, fit_half)
    psi, r = local_fit(t, np.unwrap(np.asarray(trial["psi"], dtype=float)), starts, fit_half)
    c, s = np.cos(psi), np.sin(psi)
    z = np.zeros_like(x)
    return np.column_stack([x, y, psi, c * xd + s * yd, -s * xd + c * yd, r, z, z, z])


def _errors(pred: np.ndarray, meas: np.ndarray) -> dict[str, np.ndarray]:
    ex, ey = pred[..., 0] - meas[..., 0], pred[..., 1] - meas[..., 1]
    return {"x": ex, "y": ey, "psi": wrap_deg(pred[..., 2] - meas[..., 2]), "pos": np.hypot(ex, ey)}


def validate(vessel: dp.DPVessel, trial: Trial, *, horizon: float = DEFAULT_HORIZON, stride: float | None = None,
             windows: tuple[float, ...] = (30.0, 60.0), whole: bool = True, fit_half: float = 10.0,
             model_name: str | None = None) -> Validation:
    """Simulate the LF model of ``vessel`` open loop on ``trial`` and compare (module docstring)."""
    trial.require(list(REQUIRED), method="validate dp")
    src = trial.meta.get("source")
    check_finite(src, {c: trial[c] for c in REQUIRED})
    t = np.asarray(trial.t, dtype=float)
    U = np.column_stack([trial[c] for c in dp.LF_INPUTS]).astype(float)
    Z = np.column_stack([trial[c] for c in COLUMNS]).astype(float)
    par = dp.lf_params(vessel)
    dt = float(np.median(np.diff(t)))
    sub = max(1, int(np.ceil(dt / 0.5 - 1e-9)))
    h = dt / sub

    def simulate(starts: np.ndarray, L: int) -> np.ndarray:
        X0 = initial_states(trial, starts, fit_half)
        out = np.full((starts.size, L, 3), np.nan)
        with np.errstate(all="ignore"):
            for i, (k0, x) in enumerate(zip(starts, X0)):
                out[i, 0] = x[:3]
                for j in range(1, L):
                    u = U[min(k0 + j - 1, t.size - 1)]
                    for _ in range(sub):
                        x = rk4_step(dp.lf_dynamics, 0.0, x, u, par, h)
                    if not np.all(np.isfinite(x)):
                        break
                    out[i, j] = x[:3]
        return out

    win, hz, pred = error_table(t, Z, simulate, _errors, QUANTITIES, UNITS, horizon=horizon, stride=stride,
                                windows=windows, whole=whole)
    settings = {"initial_state": f"straight-line fit within +-{fit_half:g} s of each start",
                "current": "zero (not known for a held-out run)", "bias_force": "zero", "substeps": sub}
    n = pred.shape[0]
    return Validation(windows=win, horizons=hz, t=t[:n], measured=Z[:n], predicted=pred,
                      model_name=model_name or f"dp ({vessel.name})", source=str(src or ""),
                      quantities=QUANTITIES, units=UNITS, method="dp", columns=COLUMNS, settings=settings)


def validate_result(result: Result, trial: Trial, *, horizon: float | None = None, **kw) -> Validation:
    """The common entry of every method's ``validate`` module: :func:`validate` on the LF model of an
    ``identify("dp", ...)`` result."""
    return validate(vessel_from_result(result), trial, horizon=DEFAULT_HORIZON if horizon is None else horizon,
                    **kw)


def plot(v: Validation, path, *, force: bool = False):
    """Track, x, y and heading, measured vs predicted."""
    return plot_series(v, path, [(0, lambda a: a, "x [m]"), (1, lambda a: a, "y [m]"),
                                 (2, np.degrees, "ψ [deg]")], trajectory=(0, 1), force=force)


__all__ = ["validate", "validate_result", "vessel_from_result", "initial_states", "plot",
           "REQUIRED", "COLUMNS", "QUANTITIES", "UNITS", "DEFAULT_HORIZON"]
