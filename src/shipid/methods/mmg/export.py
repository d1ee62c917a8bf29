"""The open-loop prediction of a whole run, written as a trial file beside the measurements.

:func:`prediction_trial` turns a :class:`shipid.methods.mmg.validate.Validation` (one
simulation from the run's measured initial state, driven by its measured rudder,
propeller revolutions and true wind held over each sample) into a
:class:`shipid.io.trial.Trial` on the run's own time base:

* every measured channel of the run, under the column name and in the unit of the
  file it was read from (``x_position_mid [m]``, ``psi_hat [rad]`` for the Esso Osaka
  CSVs; ``psi [deg]``, ``delta [deg]`` for the HSVA ``.dat`` files), the rudder in the
  file's own sign convention;
* the predicted states ``x, y, ψ, u, v, r`` as ``<column>_pred`` in the same unit
  (``psi_hat_pred [rad]``). The predicted heading is put on the branch of the
  measured one (``ψ_meas + wrap(ψ_pred − ψ_meas)``), so a file whose heading is
  unwrapped stays unwrapped and a wrapped one stays in the same interval;
* ``pos_err [m]``: the distance between measured and predicted midship positions.

Channels derived by the reader (the HSVA ``u, v`` from the earth-fixed velocities)
keep their standard names and SI units. A diverged prediction is written as empty
cells (``nan``) from the sample it diverged; :func:`write_prediction` reports it.
The file reads back with :func:`shipid.io.files.read_trial` (the Esso profile is
recognised from its column names, the ``_pred`` channels come back under their own names).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from shipid.io.trial import Trial
from shipid.errors import InputError
from shipid.models import mmg
from shipid.io.files import write_trial

#: Suffix of the predicted channels.
PRED_SUFFIX = "_pred"


def prediction_trial(validation, trial: Trial, *, rudder_sign: int = 1) -> Trial:
    """The measured run and its whole-run open-loop prediction as one Trial (module docstring).

    Parameters
    ----------
    validation : shipid.methods.mmg.validate.Validation
        From ``validate(model, trial, whole=True)`` on the same ``trial``.
    trial : Trial
        The run as simulated (rudder in the MMG convention: positive turns to starboard).
    rudder_sign : {1, -1}
        The factor that took the file's rudder to the MMG convention; the rudder is
        written back in the file's convention (``δ_file = rudder_sign · δ``).

    Returns
    -------
    Trial
        Channels named as in the file (see ``meta["columns"]``), units in ``meta["units_out"]``.
    """
    if rudder_sign not in (1, -1):
        raise InputError(f"rudder sign must be 1 or -1, got {rudder_sign}")
    n = trial.t.size
    P = np.asarray(validation.predicted, float)
    if P.shape != (n, len(mmg.STATE_NAMES)):
        raise InputError(f"the prediction covers {P.shape[0]} of the run's {n} samples "
                         "(validate with whole=True)", file=trial.meta.get("source"))
    cols = dict(trial.meta.get("columns") or {})
    units_in = dict(trial.meta.get("units_in") or {})

    def name_of(std: str) -> str:
        return str(cols.get(std, std))

    def unit_of(std: str) -> str:
        return str(units_in.get(std, trial.units.get(std, "-")))

    chans: dict[str, np.ndarray] = {}
    si: dict[str, str] = {}
    out_units: dict[str, str] = {"t": str(units_in.get("t", "s"))}
    for std, values in trial.channels.items():
        nm = name_of(std)
        chans[nm] = rudder_sign * values if std == "delta" else values
        si[nm] = trial.units[std]
        out_units[nm] = unit_of(std)
    for j, std in enumerate(mmg.STATE_NAMES):
        p = P[:, j]
        if std == "psi":
            meas = trial["psi"]
            p = meas + np.angle(np.exp(1j * (p - meas)))
        nm = name_of(std) + PRED_SUFFIX
        if nm in chans:
            raise InputError(f"the run already has a channel '{nm}'", file=trial.meta.get("source"), channel=nm)
        chans[nm] = p
        si[nm] = mmg_unit(std)
        out_units[nm] = unit_of(std) if std in trial.channels else si[nm]
    chans["pos_err"] = np.hypot(P[:, 0] - trial["x"], P[:, 1] - trial["y"])
    si["pos_err"] = out_units["pos_err"] = "m"
    meta = {"source": f"open-loop prediction of {validation.model_name} on {trial.meta.get('source', 'run')}",
            "model": validation.model_name, "trial": trial.meta.get("source"),
            "rudder_sign": int(rudder_sign), "units_out": out_units,
            "diverged_from_s": diverged_from(trial.t, P)}
    return Trial(trial.t, chans, si, meta)


def mmg_unit(std: str) -> str:
    """SI unit of an MMG state channel."""
    return {"x": "m", "y": "m", "psi": "rad", "u": "m/s", "v": "m/s", "r": "rad/s"}[std]


def diverged_from(t: np.ndarray, P: np.ndarray) -> float | None:
    """Time of the first non-finite predicted state, or None."""
    bad = ~np.isfinite(P).all(axis=1)
    return float(t[int(np.flatnonzero(bad)[0])]) if bad.any() else None


def write_prediction(validation, trial: Trial, path: str | Path, *, rudder_sign: int = 1,
                     force: bool = False) -> tuple[Path, Trial]:
    """Write :func:`prediction_trial` as CSV or Parquet (by extension), atomically; no clobbering without ``force``."""

    pt = prediction_trial(validation, trial, rudder_sign=rudder_sign)
    units = {k: v for k, v in pt.meta["units_out"].items() if k == "t" or pt.units.get(k) != v}
    return write_trial(pt, path, units=units, force=force), pt


__all__ = ["prediction_trial", "write_prediction", "PRED_SUFFIX", "diverged_from"]
