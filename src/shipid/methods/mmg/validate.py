"""Open-loop validation of an identified model on a measured run.

The model is simulated from the run's measured initial state with the run's
measured inputs (rudder angle, propeller revolutions and, where recorded, the true
wind), held over each sample (zero-order hold), and compared with the measured
motion. Errors are reported as RMS and maximum over

* the first 30 s and the first 60 s after the start, and the whole run (one
  simulation from the first sample — errors grow without bound on long runs, so the
  whole-run numbers say how fast the model drifts, not how good it is locally);
* 60-s horizons restarted from the measured state every 60 s across the run
  (``horizons``; all horizons simulated at once as one batch). These are the numbers
  to compare models by: every part of the run counts, not one lucky window.

Quantities: heading ψ (deg, wrapped to ±180°), yaw rate r (deg/s), surge u and
sway v (m/s), position (m, distance between the measured and predicted midship
positions).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from shipid.analysis.openloop import Validation, horizon_starts, plot_series, summarise
from shipid.io.trial import Trial
from shipid.errors import InputError
from shipid.models import mmg
from shipid.result import Result

QUANTITIES = ("psi", "r", "u", "v", "pos")
UNITS = {"psi": "deg", "r": "deg/s", "u": "m/s", "v": "m/s", "pos": "m"}
#: Length of the restarted horizons, s.
DEFAULT_HORIZON = 60.0


# ----------------------------------------------------------------------------- models
def model_from_result(d: Mapping[str, Any]) -> mmg.MmgModel:
    """The MMG model of a MODEL.json dict (:meth:`shipid.result.Result.to_dict`)."""
    model = d.get("model") if "model" in d else None
    if not isinstance(model, Mapping) or model.get("family") != "mmg":
        raise InputError("MODEL.json does not hold an MMG model ('model.family' is not 'mmg'); "
                         "write it with 'shipid identify mmg --json'")
    return mmg.MmgModel.from_dict(model)


def load_model(spec: str | Path) -> mmg.MmgModel:
    """A model from a MODEL.json path, or ``published:esso_osaka_3m`` / ``published:kvlcc2_L7``."""
    return load_model_document(spec)[0]


def load_model_document(spec: str | Path) -> tuple[mmg.MmgModel, dict | None]:
    """The model of ``spec`` and the whole MODEL.json document (``None`` for a ``published:`` set).

    The document carries what ``validate`` needs besides the coefficients: the
    training runs' rudder sign convention and reading settings (``model.validate``,
    ``model.conventions``) and whether the identification converged
    (``diagnostics.converged``).
    """
    s = str(spec)
    if s.startswith("published:"):
        return mmg.load_published(s.split(":", 1)[1]), None
    p = Path(s)
    if not p.is_file():
        raise InputError("no such model file", file=s)
    try:
        d = json.loads(p.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as err:
        raise InputError(f"not a JSON model file ({err})", file=s) from None
    if not isinstance(d, dict):
        raise InputError("not a MODEL.json object", file=s)
    try:
        return model_from_result(d), d
    except InputError as err:
        raise InputError(str(err.args[0]) if err.args else str(err), file=s) from None
    except (KeyError, TypeError, ValueError) as err:
        raise InputError(f"malformed MMG model ({type(err).__name__}: {err})", file=s) from None


# ----------------------------------------------------------------------------- data
def measured_states(trial: Trial) -> np.ndarray:
    """``(n, 6)`` measured ``[x, y, ψ, u, v, r]``."""
    trial.require(list(mmg.STATE_NAMES), method="validate")
    return np.stack([trial[c] for c in mmg.STATE_NAMES], axis=-1)


def trial_inputs(trial: Trial) -> np.ndarray:
    """``(n, 4)`` inputs ``[δ, n, U_T, γ_T]``; no wind (zeros) when the run has none."""
    trial.require(["delta", "n"], method="validate")
    zero = np.zeros(trial.t.size)
    ws = trial["wind_speed"] if "wind_speed" in trial else zero
    wd = trial["wind_dir"] if "wind_dir" in trial else zero
    return np.stack([trial["delta"], trial["n"], ws, wd], axis=-1)


def _check_finite(trial: Trial, Z: np.ndarray, U: np.ndarray) -> None:
    bad = ~np.isfinite(Z).all(axis=1) | ~np.isfinite(U).all(axis=1)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise InputError("missing values in the states or inputs (read the run with interpolate_gaps "
                         "or trim_empty_rows)", file=trial.meta.get("source"), row=k + 1)


# ----------------------------------------------------------------------------- conventions
def first_step_yaw_sign(trial: Trial, *, max_window: float = 10.0) -> dict[str, Any]:
    """Sign of the yaw response to the first rudder step of a run (the run's rudder convention).

    The first step is the first sample where the rudder has moved from its initial
    value (median of the first second) by more than ``max(3 deg, half its largest
    excursion)``. The response is the change of the measured yaw rate from the second
    before the step to the last second of the step (at most ``max_window`` s, until the
    rudder returns). With the MMG convention (rudder positive turns the ship to
    starboard, yaw rate positive to starboard) the product of the step's sign and the
    response's sign is +1; a log whose rudder is positive to port gives -1. The rule holds for a ship going
    ahead with its propeller ahead: going astern, or with the propeller reversed, the rudder's inflow and so
    its side force change sign, and the step says nothing about the convention (``sign`` 0, ``ahead`` False).

    Returns
    -------
    dict
        ``sign`` (+1, -1, or 0 when the run has no clear step, no clear response, or the step is not made
        going ahead), ``t_step`` (s from the start), ``delta_step_deg``, ``dr_deg_s``, ``ahead`` (mean surge
        speed over the step > 0 and, where the run logs it, mean propeller rate >= 0).
    """
    t = np.asarray(trial.t, dtype=float)
    out: dict[str, Any] = {"sign": 0, "t_step": None, "delta_step_deg": None, "dr_deg_s": None}
    if "delta" not in trial or "r" not in trial or t.size < 10:
        return out
    d, r = np.asarray(trial["delta"], float), np.asarray(trial["r"], float)
    dt = float(np.median(np.diff(t)))
    n1 = max(int(round(1.0 / dt)), 1)
    d0 = float(np.nanmedian(d[:n1]))
    exc = np.abs(d - d0)
    if not np.isfinite(exc).any():
        return out
    thr = max(np.deg2rad(3.0), 0.5 * float(np.nanmax(exc)))
    above = np.flatnonzero(exc > thr)
    if above.size == 0:
        return out
    k = int(above[0])
    s = float(np.sign(d[k] - d0))
    stop = min(t.size, k + int(round(max_window / dt)))
    back = np.flatnonzero((np.sign(d[k:stop] - d0) != s) | (exc[k:stop] < 0.5 * thr))
    j = k + (int(back[0]) if back.size else stop - k)
    if (j - k) * dt < 2.0:
        return out
    before = float(np.nanmean(r[max(k - n1, 0):k + 1]))
    after = float(np.nanmean(r[max(j - n1, k):j]))
    dr = after - before
    scale = float(np.nanmax(np.abs(r))) if np.isfinite(r).any() else 0.0
    ahead = bool(np.nanmean(trial["u"][k:j]) > 0.0) if "u" in trial else True
    if "n" in trial:
        ahead = ahead and bool(np.nanmean(trial["n"][k:j]) >= 0.0)
    out.update(t_step=float(t[k] - t[0]), delta_step_deg=float(np.degrees(d[k] - d0)), dr_deg_s=float(np.degrees(dr)),
               ahead=ahead)
    if ahead and scale > 0 and abs(dr) > 0.1 * scale:
        out["sign"] = int(s * np.sign(dr))
    return out


# ----------------------------------------------------------------------------- metrics
def _errors(pred: np.ndarray, meas: np.ndarray) -> dict[str, np.ndarray]:
    dpsi = np.angle(np.exp(1j * (pred[..., 2] - meas[..., 2])))
    return {"psi": np.degrees(dpsi), "r": np.degrees(pred[..., 5] - meas[..., 5]),
            "u": pred[..., 3] - meas[..., 3], "v": pred[..., 4] - meas[..., 4],
            "pos": np.hypot(pred[..., 0] - meas[..., 0], pred[..., 1] - meas[..., 1])}


def _summary(err: Mapping[str, np.ndarray], mask: np.ndarray | None = None) -> dict[str, dict[str, float]]:
    return summarise(err, QUANTITIES, UNITS, mask)


def validate(model: mmg.MmgModel, trial: Trial, *, horizon: float = 60.0, stride: float | None = None,
             windows: tuple[float, ...] = (30.0, 60.0), whole: bool = True) -> Validation:
    """Simulate ``model`` open loop on ``trial`` and compare (module docstring).

    Parameters
    ----------
    horizon : float
        Length of the restarted horizons, s.
    stride : float, optional
        Spacing of their starts, s (default: ``horizon``, i.e. back to back).
    windows : tuple of float
        Lengths of the windows from the start of the run, s.
    whole : bool
        Also simulate the whole run from the first sample.
    """
    t = np.asarray(trial.t, dtype=float)
    Z = measured_states(trial)
    U = trial_inputs(trial)
    _check_finite(trial, Z, U)
    dt = float(np.median(np.diff(t)))
    nsteps = int(round(horizon / dt))
    nstride = int(round((stride or horizon) / dt))
    # whole run (windows are its first seconds)
    n_whole = t.size if whole else min(t.size, int(round(max(windows, default=0.0) / dt)) + 1)
    win = {}
    if n_whole > 1:
        pred = mmg.simulate_batch(model, t[:n_whole], Z[0][None], U[:n_whole])[0]
        err = _errors(pred, Z[:n_whole])
        tt = t[:n_whole] - t[0]
        for w in windows:
            win[f"first_{w:g}s"] = _summary(err, tt <= w + 1e-9)
        if whole:
            win["whole"] = _summary(err)
    else:
        pred = Z[:1].copy()
    # restarted horizons, all in one batch
    starts = horizon_starts(t.size, nsteps, nstride, min_steps=max(nsteps // 2, 2))
    hz: dict[str, Any] = {"length_s": horizon, "stride_s": (stride or horizon), "count": int(starts.size)}
    if starts.size:
        L = nsteps + 1
        idx = np.minimum(starts[:, None] + np.arange(L)[None, :], t.size - 1)
        valid = (starts[:, None] + np.arange(L)[None, :]) <= t.size - 1
        Ub = U[idx]
        tg = t[0] + dt * np.arange(L)           # uniform grid (the data are uniform)
        P = mmg.simulate_batch(model, tg, Z[starts], Ub)
        E = _errors(P, Z[idx])
        hz.update(_summary(E, valid))
    return Validation(windows=win, horizons=hz, t=t[:n_whole], measured=Z[:n_whole], predicted=pred,
                      model_name=model.name, source=str(trial.meta.get("source", "")),
                      quantities=QUANTITIES, units=UNITS, method="mmg-ebm", columns=mmg.STATE_NAMES)


def validate_result(result: Result, trial: Trial, *, horizon: float | None = None, **kw) -> Validation:
    """The common entry of every method's ``validate`` module: :func:`validate` on the MMG model of
    ``result`` (an ``identify("mmg", ...)`` result). ``trial``'s rudder must follow MMG's convention
    (positive turns the ship to starboard). ``horizon`` defaults to :data:`DEFAULT_HORIZON`."""
    return validate(model_from_result(result.to_dict()), trial,
                    horizon=DEFAULT_HORIZON if horizon is None else horizon, **kw)


def plot(v: Validation, path: str | Path, *, force: bool = False) -> Path:
    """Overlay measured and predicted trajectory and time series (ψ, r, u, v); written atomically."""
    return plot_series(v, path, [(2, np.degrees, "ψ [deg]"), (5, np.degrees, "r [deg/s]"),
                                 (3, lambda a: a, "u [m/s]"), (4, lambda a: a, "v [m/s]")],
                       trajectory=(0, 1), force=force)


__all__ = ["validate", "validate_result", "DEFAULT_HORIZON", "Validation", "load_model", "model_from_result", "measured_states", "trial_inputs",
           "first_step_yaw_sign", "load_model_document",
           "plot", "horizon_starts", "QUANTITIES", "UNITS"]
