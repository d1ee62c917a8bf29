"""Builders for the ``Result.series`` entries that ``shipid report`` draws.

Each function returns a plain JSON-able dict following the convention described
in :mod:`shipid.report` (arrays become lists, NaN stays NaN). They import no
plotting library, so method code can use them freely::

    from shipid.report.convention import overlay, history
    series = {"overlays": {"r": overlay(t, r_meas, r_model, "rad/s", label="yaw rate r")},
              "histories": {"X_u": history(t, xu, xu_std, "kg/s", true=-1.2e4)}}
"""

from __future__ import annotations

from typing import Any, Iterable, Mapping, Sequence

import numpy as np

#: Kinds of ``Result.series`` entries the report knows how to draw.
KINDS = ("overlays", "residuals", "histories", "signals", "matrices", "tables", "contours", "xy")


def _list(a) -> list:
    return np.asarray(a, dtype=float).tolist()


def _extra(entry: dict, **kw: Any) -> dict:
    for k, v in kw.items():
        if v is not None:
            entry[k] = v
    return entry


def overlay(t, measured, model, unit: str, *, label: str | None = None, kind: str = "fit",
            title: str | None = None, paper: str | None = None) -> dict:
    """Measured and model-predicted time history of one channel.

    ``kind`` is ``"fit"`` (data used for estimation) or ``"validation"`` (held-out data).
    """
    return _extra({"t": _list(t), "measured": _list(measured), "model": _list(model), "unit": unit,
                   "kind": kind}, label=label, title=title, paper=paper)


def residual(t, values, unit: str, *, std=None, label: str | None = None, title: str | None = None,
             paper: str | None = None) -> dict:
    """Residual (or innovation) history; ``std`` is its predicted standard deviation per sample."""
    return _extra({"t": _list(t), "values": _list(values), "unit": unit},
                  std=None if std is None else _list(std), label=label, title=title, paper=paper)


def history(t, value, std, unit: str, *, true: float | None = None, label: str | None = None,
            title: str | None = None, paper: str | None = None) -> dict:
    """Recursive estimate of one parameter versus time with its standard deviation (Fossen, Sagatun & Sørensen 1996, Fig. 8)."""
    return _extra({"t": _list(t), "value": _list(value), "unit": unit},
                  std=None if std is None else _list(std),
                  true=None if true is None else float(true), label=label, title=title, paper=paper)


def signal(t, lines: Mapping[str, Sequence[float]], unit: str, *, std: Mapping | None = None,
           label: str | None = None, title: str | None = None, paper: str | None = None) -> dict:
    """One axis of time histories (e.g. smoothed states, forces; Yoon & Rhee 2003, Figs 4, 9)."""
    return _extra({"t": _list(t), "lines": {str(k): _list(v) for k, v in lines.items()}, "unit": unit},
                  std=None if std is None else {str(k): _list(v) for k, v in std.items()},
                  label=label, title=title, paper=paper)


def matrix(values, rows: Iterable[str], cols: Iterable[str] | None = None, *, unit: str | None = None,
           vmin: float | None = None, vmax: float | None = None, annotate: bool | None = None,
           title: str | None = None, paper: str | None = None) -> dict:
    """A matrix drawn as a heat map (e.g. regressor correlation, Yoon & Rhee 2003, Tables 1-2)."""
    return _extra({"values": np.asarray(values, dtype=float).tolist(), "rows": [str(r) for r in rows]},
                  cols=None if cols is None else [str(c) for c in cols], unit=unit, vmin=vmin, vmax=vmax,
                  annotate=annotate, title=title, paper=paper)


def table(columns: Sequence[str], rows: Sequence[Sequence[Any]], *, units: Sequence[str] | None = None,
          caption: str | None = None, title: str | None = None, paper: str | None = None) -> dict:
    """An extra table (true vs estimated, kappa/R/Cp of Yoon & Rhee 2003, Table 4, Monte Carlo spread)."""
    def cell(v):
        if isinstance(v, (np.floating, np.integer)):
            return v.item()
        return v
    return _extra({"columns": [str(c) for c in columns], "rows": [[cell(v) for v in r] for r in rows]},
                  units=None if units is None else [str(u) for u in units], caption=caption,
                  title=title, paper=paper)


def contour(x, y, z, *, x_label: str, x_unit: str, y_label: str, y_unit: str, z_label: str | None = None,
            log: bool | None = None, points: Sequence[Mapping[str, Any]] | None = None,
            title: str | None = None, paper: str | None = None) -> dict:
    """A scalar field over a grid; ``z`` has ``len(y)`` rows and ``len(x)`` columns."""
    z = np.asarray(z, dtype=float)
    if z.shape != (len(y), len(x)):
        raise ValueError(f"contour z has shape {z.shape}, expected (len(y), len(x)) = ({len(y)}, {len(x)})")
    return _extra({"x": _list(x), "y": _list(y), "z": z.tolist(), "x_label": x_label, "x_unit": x_unit,
                   "y_label": y_label, "y_unit": y_unit},
                  z_label=z_label, log=log,
                  points=None if points is None else [{k: (float(v) if k in ("x", "y") else v)
                                                      for k, v in p.items()} for p in points],
                  title=title, paper=paper)


def xy(x, lines: Mapping[str, Sequence[float]], *, x_label: str, x_unit: str, y_label: str, y_unit: str,
       style: str = "line", title: str | None = None, paper: str | None = None) -> dict:
    """Any other x-y plot; ``style`` is ``"line"`` or ``"scatter"``."""
    return _extra({"x": _list(x), "lines": {str(k): _list(v) for k, v in lines.items()},
                   "x_label": x_label, "x_unit": x_unit, "y_label": y_label, "y_unit": y_unit,
                   "style": style}, title=title, paper=paper)


def trial_summary(trial, name: str | None = None, *, channels: Iterable[str] | None = None,
                  note: str | None = None) -> dict:
    """Describe the data a method used, for ``Result.provenance["inputs"]``.

    Parameters
    ----------
    trial : shipid.io.trial.Trial
    name : str, optional
        File name or label; defaults to ``trial.meta["source"]``.
    channels : iterable of str, optional
        The channels actually used (default: all channels of the trial).
    """
    t = np.asarray(trial.t, dtype=float)
    names = list(channels) if channels is not None else list(trial.channels)
    dts = np.diff(t)
    entry = {
        "name": str(name if name is not None else trial.meta.get("source", "in-memory trial")),
        "channels": {c: trial.units.get(c, "-") for c in names},
        "n_samples": int(t.size),
        "duration_s": float(t[-1] - t[0]) if t.size else 0.0,
        "dt_s": float(np.median(dts)) if dts.size else float("nan"),
        "t0_s": float(t[0]) if t.size else float("nan"),
    }
    for key in ("vessel", "manoeuvre", "seed"):
        if key in trial.meta:
            entry[key] = trial.meta[key]
    if note:
        entry["note"] = note
    return entry
