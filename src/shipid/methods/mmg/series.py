"""Report series of ``mmg-ebm`` results of ``shipid identify mmg`` (real free-running runs).

Such a result records its training runs by file name and checksum only
(``provenance["training_runs"]``) and carries no series. :func:`with_series` computes the report's
material on request (``Result.with_series()``, ``shipid report``; ``identify`` never does it) from the
trials given, or else from the recorded files when they can still be read: the "Data used" summary of each run
(samples, duration, sampling, channels with units) and, per run, an open-loop simulation of
the identified model from the run's measured initial state driven by its measured rudder,
propeller revolutions and wind (:func:`shipid.methods.mmg.validate.validate`), drawn as
measured-versus-model overlays of ψ, r, u and v. These runs were used for estimation, so
the overlays show the fit, not a prediction; the verdict says so.
"""

from __future__ import annotations

import dataclasses
import os
from typing import Mapping, Sequence

import numpy as np

from shipid.io.files import read_trial
from shipid.io.trial import Trial
from shipid.errors import InputError
from shipid.outputs import short_path
from shipid.report.convention import overlay, signal, trial_summary
from shipid.methods.mmg import validate as V
from shipid.models import mmg

#: (channel, label, unit) of the overlays, in the MMG state order [x, y, ψ, u, v, r].
OVERLAY_CHANNELS = (("psi", "heading ψ", "rad"), ("r", "yaw rate r", "rad/s"), ("u", "surge speed u", "m/s"),
                    ("v", "sway speed v", "m/s"))


def _runs(prov: Mapping) -> list:
    runs = prov.get("training_runs")
    return list(runs) if isinstance(runs, (list, tuple)) else []


def _read(path: str, prov: Mapping):

    tr = read_trial(path, fmt=prov.get("format"), channel_map=prov.get("channels"), trim_empty_rows=True,
                    interpolate_gaps=1.0, method="shipid report")
    if int(prov.get("rudder_sign", 1) or 1) == -1 and "delta" in tr:
        tr = tr.with_channels(delta=-tr["delta"])
    return tr


def with_series(result, *, trials: Sequence | None = None):
    """A copy of ``result`` with ``provenance["inputs"]``, fit overlays and input signals.

    ``trials``: the training runs (trials or paths, in the order of ``provenance["training_runs"]``, as
    ``shipid.identify("mmg", ...)`` took them); None reads the recorded files again (with the recorded
    format, channel map and rudder sign). Returns ``result`` itself when it already records inputs and
    overlays, when it is not an ``mmg-ebm`` result, or when it records no training runs; a run that cannot
    be read gets a note in its input summary.
    """
    prov = dict(result.provenance or {})
    runs = _runs(prov)
    if result.method != "mmg-ebm" or not runs:
        return result
    given = None if trials is None else (list(trials) if not isinstance(trials, (Trial, str, os.PathLike))
                                         else [trials])
    if given is not None and len(given) != len(runs):
        raise InputError(f"mmg: {len(given)} trials given for the {len(runs)} training runs the result records")
    series = {k: (dict(v) if isinstance(v, Mapping) else v) for k, v in (result.series or {}).items()}
    have_inputs = isinstance(prov.get("inputs"), (list, tuple)) and prov["inputs"]
    have_overlays = bool(series.get("overlays"))
    if have_inputs and have_overlays:
        return result

    inputs, overlays, signals, notes = [], {}, {}, []
    model = None
    for k, run in enumerate(runs):
        path = str(run.get("file") if isinstance(run, Mapping) else run)
        name = short_path(path) if os.path.isabs(path) else path
        src = path if given is None else given[k]
        if not isinstance(src, Trial) and not os.path.isfile(str(src)):
            inputs.append({"name": name, "note": "file not found where the report was built: no summary"})
            continue
        try:
            tr = src if isinstance(src, Trial) else _read(str(src), prov)
        except Exception as err:  # noqa: BLE001 - the report must still be written
            inputs.append({"name": name, "note": f"could not be read again: {' '.join(str(err).split())[:160]}"})
            continue
        entry = trial_summary(tr, name=name, note="training run")
        if isinstance(run, Mapping) and run.get("sha256_16"):
            entry["note"] += f"; sha256 {run['sha256_16']}…"
        inputs.append(entry)
        if have_overlays:
            continue
        try:

            if model is None:
                model = V.model_from_result(result.to_dict())
            v = V.validate(model, tr, horizon=60.0)
            cols = {c: i for i, c in enumerate(mmg.STATE_NAMES)}
            t = v.t - v.t[0]
            for ch, label, unit in OVERLAY_CHANNELS:
                overlays[f"run{k + 1}_{ch}"] = overlay(
                    t, v.measured[:, cols[ch]], v.predicted[:, cols[ch]], unit,
                    label=f"{label} ({name})", kind="fit",
                    title=f"Open-loop simulation of the identified model over training run {name} (from its "
                          f"measured initial state, driven by its measured rudder, propeller and wind): {label}, "
                          "measured and model; residual and its autocorrelation with 95 % white-noise bounds.")
            tt = np.asarray(tr.t, float) - float(tr.t[0])
            signals[f"run{k + 1}_delta"] = signal(tt, {"rudder δ": tr["delta"]}, "rad", label="rudder angle δ",
                                                  title=f"Measured inputs of training run {name}.")
            if "n" in tr:
                signals[f"run{k + 1}_n"] = signal(tt, {"propeller n": tr["n"]}, "1/s", label="propeller n",
                                                  title=f"Measured inputs of training run {name}.")
        except Exception as err:  # noqa: BLE001
            notes.append(f"report: open-loop simulation of {name} not drawn "
                         f"({type(err).__name__}: {' '.join(str(err).split())[:160]})")
    if not have_inputs:
        prov["inputs"] = inputs
    if overlays:
        series.setdefault("overlays", {}).update(overlays)
    if signals:
        series.setdefault("signals", {}).update(signals)
    diag = dict(result.diagnostics or {})
    if notes:
        diag["warnings"] = list(diag.get("warnings") or []) + notes
    return dataclasses.replace(result, provenance=prov, series=series, diagnostics=diag)


__all__ = ["OVERLAY_CHANNELS", "with_series"]
