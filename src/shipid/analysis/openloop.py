"""Open-loop prediction error tables shared by every method's ``validate`` module.

An identified model is simulated from a held-out run's measured initial state with the run's
measured inputs and compared with the measured outputs. Errors are reported as RMS and maximum
over

* the first 30 s and the first 60 s after the start, and the whole run (one simulation from the
  first sample: on long runs the whole-run numbers say how fast the model drifts);
* horizons of ``horizon`` s restarted from the measured state every ``stride`` s across the run,
  pooled (every part of the run counts, not one lucky window).

What "state", "input" and "output" are is the method's business: its ``validate`` module passes
a ``simulate(starts, length)`` callable that returns the predicted output columns of each horizon
and an ``errors(pred, meas)`` callable that turns predicted and measured columns into one error
array per reported quantity. This module holds the bookkeeping only (windows, horizons,
:class:`Validation` with its summary table, the JSON, the plot and the CSV of the whole-run prediction).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from shipid import registry as method_registry
from shipid.errors import InputError
from shipid.io.trial import CHANNELS
from shipid.outputs import atomic_write, atomic_write_text


@dataclass(frozen=True)
class Validation:
    """Open-loop errors of a model on one run.

    Attributes
    ----------
    windows : dict
        ``{"first_30s" | "first_60s" | "whole": {quantity: {"rms", "max", "unit"}}}``.
    horizons : dict
        Same layout, pooled over the restarted horizons; plus ``"count"``, ``"length_s"``, ``"stride_s"``.
    t, measured, predicted : ndarray
        The whole-run simulation (for plots and ``--out``); columns named by ``columns``.
    model_name, source : str
        The model and the run it was validated on.
    quantities : tuple of str
        The reported error quantities, in table order; ``units`` gives each one's unit.
    method : str
        The method that identified the model (``Result.method``).
    columns : tuple of str
        Names of the columns of ``measured`` / ``predicted``.
    settings : dict
        How the prediction was made (initial state, current, condition ...), for the JSON.
    """

    windows: dict
    horizons: dict
    t: np.ndarray
    measured: np.ndarray
    predicted: np.ndarray
    model_name: str
    source: str
    quantities: tuple[str, ...] = ()
    units: Mapping[str, str] = field(default_factory=dict)
    method: str = ""
    columns: tuple[str, ...] = ()
    settings: dict = field(default_factory=dict)

    # -- the faces a user reads: table, frame, figure, short repr -----------------------------------

    def rows(self) -> list[tuple[str, str, float, float, str]]:
        """``(window, quantity, rms, max, unit)`` for every window and the pooled horizons."""
        out = []
        hz = f"{self.horizons.get('length_s', 0):g}-s horizons (n={self.horizons.get('count', 0)})"
        for name, s in list(self.windows.items()) + [(hz, self.horizons)]:
            for q in self.quantities:
                if isinstance(s.get(q), Mapping):
                    out.append((name, q, float(s[q]["rms"]), float(s[q]["max"]),
                                str(s[q].get("unit", self.units.get(q, "")))))
        return out

    def summary(self, width: int = 100) -> str:
        """RMS / max error per window (rows) and quantity (columns), at most ``width`` columns.

        Quantities that do not fit one block go to a second block below.
        """
        return _Text(summary_text(self, width))

    def to_frame(self):
        """pandas DataFrame, one row per (window, quantity): ``rms``, ``max``, ``unit``."""
        import pandas as pd

        return pd.DataFrame(self.rows(), columns=["window", "quantity", "rms", "max", "unit"]) \
            .set_index(["window", "quantity"])

    def plot(self, path: str | Path | None = None, *, force: bool = False):
        """Measured against predicted. With ``path``: the method's figure, written there (returns the
        path); without: a matplotlib Figure of every column against time (angles in deg)."""
        if path is not None:
            info = method_registry.for_result(self.method)
            fn = getattr(info.submodule("validate"), "plot", None) if (
                info is not None and info.has_module("validate")) else None
            if callable(fn):
                return fn(self, path, force=force)
            panels = [(j, *_display(c)) for j, c in enumerate(self.columns)]
            return plot_series(self, path, panels, force=force)
        return figure(self)

    def __repr__(self) -> str:
        head = f"<shipid Validation of {self.model_name} on {Path(self.source).name}>"
        whole = self.windows.get("whole") or {}
        bits = [f"{q} {float(whole[q]['rms']):.3g} {whole[q].get('unit', '')}".rstrip()
                for q in self.quantities if isinstance(whole.get(q), Mapping)]
        line = ("  whole-run RMS error: " + ", ".join(bits)) if bits else ""
        return "\n".join(x for x in (head, line, "  .summary() for the table, .to_frame() for pandas, .plot()")
                         if x)

    __str__ = __repr__

    def _repr_html_(self) -> str:
        import html as _html

        return f"<pre>{_html.escape(summary_text(self))}</pre>"

    def to_dict(self) -> dict[str, Any]:
        d = {"model": self.model_name, "trial": self.source, "duration_s": float(self.t[-1] - self.t[0]),
             "windows": self.windows, "horizons": self.horizons}
        if self.method:
            d["method"] = self.method
        if self.settings:
            d["settings"] = dict(self.settings)
        return d


def summarise(err: Mapping[str, np.ndarray], quantities: Sequence[str], units: Mapping[str, str],
              mask: np.ndarray | None = None) -> dict[str, dict[str, float]]:
    """RMS and max |error| per quantity over ``mask``; a non-finite error (diverged) is ``inf``."""
    out = {}
    for q in quantities:
        e = np.asarray(err[q])
        if mask is not None:
            e = e[mask]
        e = e.ravel()
        if e.size == 0:
            out[q] = {"rms": float("nan"), "max": float("nan"), "unit": units[q]}
        elif not np.all(np.isfinite(e)):
            out[q] = {"rms": float("inf"), "max": float("inf"), "unit": units[q]}
        else:
            out[q] = {"rms": float(np.sqrt(np.mean(e * e))), "max": float(np.max(np.abs(e))), "unit": units[q]}
    return out


def horizon_starts(n: int, steps: int, stride: int, min_steps: int) -> np.ndarray:
    """Start indices of restarted horizons: every ``stride`` samples while at least ``min_steps`` remain."""
    starts = np.arange(0, max(n - 1, 0), stride)
    return starts[(n - starts) >= min_steps]


def error_table(t: np.ndarray, measured: np.ndarray,
                simulate: Callable[[np.ndarray, int], np.ndarray],
                errors: Callable[[np.ndarray, np.ndarray], Mapping[str, np.ndarray]],
                quantities: Sequence[str], units: Mapping[str, str], *, horizon: float,
                stride: float | None = None, windows: tuple[float, ...] = (30.0, 60.0), whole: bool = True,
                first: int = 0) -> tuple[dict, dict, np.ndarray]:
    """Windows from the start, the whole run and the restarted horizons (module docstring).

    Parameters
    ----------
    t : ndarray (n,)
        Uniform sample times, s.
    measured : ndarray (n, k)
        Measured output columns.
    simulate : callable
        ``simulate(starts, L) -> (len(starts), L, k)``: the prediction of the output columns on the
        samples ``start, start + 1, ..., start + L - 1`` from the measured state at ``start``
        (samples past the end of the run may be anything; they are masked).
    errors : callable
        ``errors(pred, meas) -> {quantity: array}`` on arrays of the same leading shape.
    first : int
        First sample a prediction may start from (a model that needs past outputs).

    Returns
    -------
    windows, horizons, whole_prediction
    """
    t = np.asarray(t, dtype=float)
    n = t.size
    if n - first < 3:
        raise InputError(f"the run has {n} samples: too short to validate on")
    dt = float(np.median(np.diff(t)))
    nsteps = int(round(horizon / dt))
    nstride = max(int(round((stride or horizon) / dt)), 1)
    n_whole = n - first if whole else min(n - first, int(round(max(windows, default=0.0) / dt)) + 1)
    win: dict[str, Any] = {}
    pred = simulate(np.array([first]), n_whole)[0]
    meas = measured[first:first + n_whole]
    err = errors(pred, meas)
    tt = t[first:first + n_whole] - t[first]
    for w in windows:
        win[f"first_{w:g}s"] = summarise(err, quantities, units, tt <= w + 1e-9)
    if whole:
        win["whole"] = summarise(err, quantities, units)
    starts = first + horizon_starts(n - first, nsteps, nstride, min_steps=max(nsteps // 2, 2))
    hz: dict[str, Any] = {"length_s": horizon, "stride_s": (stride or horizon), "count": int(starts.size)}
    if starts.size:
        L = nsteps + 1
        k = starts[:, None] + np.arange(L)[None, :]
        valid = k <= n - 1
        P = simulate(starts, L)
        E = errors(P, measured[np.minimum(k, n - 1)])
        hz.update(summarise(E, quantities, units, valid))
    return win, hz, pred


def plot_series(v: Validation, path: str | Path, panels: Sequence[tuple[int, Callable, str]], *,
                trajectory: tuple[int, int] | None = None, force: bool = False) -> Path:
    """Measured (black) against predicted (red dashed) whole-run columns; written atomically.

    ``panels``: ``(column, transform, label)`` per time-series panel; ``trajectory``: the columns
    ``(north, east)`` of a plan-view panel, if any.
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    nrow = max(len(panels), 1)
    fig = plt.figure(figsize=(11 if trajectory else 8, max(2.0 * nrow, 4.0)))
    ncol = 2 if trajectory else 1
    if trajectory:
        ax = fig.add_subplot(1, 2, 1)
        i, j = trajectory
        ax.plot(v.measured[:, j], v.measured[:, i], "k-", label="measured")
        ax.plot(v.predicted[:, j], v.predicted[:, i], "r--", label="predicted")
        ax.set_xlabel(f"{v.columns[j]} [m]"); ax.set_ylabel(f"{v.columns[i]} [m]")
        ax.set_aspect("equal", "datalim"); ax.legend()
    a = None
    for k, (j, f, lab) in enumerate(panels):
        a = fig.add_subplot(nrow, ncol, ncol * k + ncol)
        a.plot(v.t, f(v.measured[:, j]), "k-", lw=0.8, label="measured")
        a.plot(v.t, f(v.predicted[:, j]), "r--", lw=0.8, label="predicted")
        a.set_ylabel(lab)
    if a is not None:
        a.set_xlabel("t [s]")
    fig.suptitle(f"{v.model_name}: {Path(v.source).name}")
    fig.tight_layout()
    fmt = Path(path).suffix.lstrip(".") or "png"
    try:
        return atomic_write(path, lambda tmp: fig.savefig(tmp, format=fmt, dpi=110), force=force)
    finally:
        plt.close(fig)


class _Text(str):
    """A text table that shows as itself at the prompt (not as a quoted string)."""

    def __repr__(self) -> str:
        return str(self)


_ANGLES = {"psi", "r", "phi", "p", "delta", "beta", "theta", "q", "heading", "chi", "yaw"}


def _display(column: str) -> tuple[Callable, str]:
    """(transform, axis label) of a predicted column: angles and rates in deg, the rest as stored."""
    base = column.split("_")[0]
    if base in _ANGLES:
        return np.degrees, f"{column} [deg{'/s' if base in ('r', 'p', 'q') else ''}]"
    unit = "m/s" if base in ("u", "v", "w", "U", "sog") else ("m" if base in ("x", "y", "z", "n", "e") else "")
    return (lambda a: a), (f"{column} [{unit}]" if unit else column)


def figure(v: Validation):
    """Every predicted column against the measured one over time, as a matplotlib Figure (Agg)."""
    from matplotlib.figure import Figure

    cols = list(v.columns)
    fig = Figure(figsize=(8, max(1.8 * len(cols), 3.0)))
    axes = fig.subplots(max(len(cols), 1), 1, sharex=True, squeeze=False)[:, 0]
    step = max(len(v.t) // 4000, 1)
    for ax, (j, c) in zip(axes, enumerate(cols)):
        f, lab = _display(c)
        ax.plot(v.t[::step], f(v.measured[::step, j]), "k-", lw=0.8, label="measured")
        ax.plot(v.t[::step], f(v.predicted[::step, j]), "r--", lw=0.8, label="predicted")
        ax.set_ylabel(lab)
    axes[0].legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(f"{v.model_name} on {Path(v.source).name}", fontsize=10)
    fig.tight_layout()
    return fig


def _g(x: float) -> str:
    """Three significant digits in at most 8 characters (``9.95e-8``)."""
    return f"{x:.3g}".replace("e+0", "e").replace("e-0", "e-").replace("e+", "e")


def summary_text(v: Validation, width: int = 100) -> str:
    """:meth:`Validation.summary` (rows: windows and pooled horizons; columns: quantities)."""
    rows = v.rows()
    windows = list(dict.fromkeys(r[0] for r in rows))
    cell = {(w, q): (rms, mx) for w, q, rms, mx, _ in rows}
    units = {q: u for _, q, _, _, u in rows}
    qs = [q for q in v.quantities if q in units]
    name_w = min(max([len(w) for w in windows] + [6]), 30)
    col_w = 19
    per = max((width - name_w) // (col_w + 1), 1)
    what = v.model_name if (not v.method or v.method in v.model_name) else f"{v.model_name} ({v.method})"
    lines = [f"shipid validate: {what} on {Path(v.source).name}"[:width],
             "open-loop error RMS / max; horizons restart from the measured state"[:width]]
    for k in range(0, len(qs), per):
        block = qs[k:k + per]
        lines.append("-" * min(width, name_w + (col_w + 1) * len(block)))
        lines.append(f"{'window':<{name_w}}" + "".join(f" {(q + ' [' + units[q] + ']')[:col_w]:>{col_w}}"
                                                        for q in block))
        for w in windows:
            vals = [cell.get((w, q)) for q in block]
            lines.append(f"{w[:name_w]:<{name_w}}" + "".join(
                f" {'-':>{col_w}}" if x is None else f" {_g(x[0]) + ' / ' + _g(x[1]):>{col_w}}" for x in vals))
    return "\n".join(lines)


def write_csv(v: Validation, path: str | Path, *, force: bool = False) -> Path:
    """The whole-run prediction beside the measured columns, CSV, atomically.

    Header ``t [s], <c> [unit], <c>_pred [unit], ...``: each column in the SI unit of its
    channel (:data:`shipid.io.trial.CHANNELS`; ``-`` for a name it does not list), so that
    :func:`shipid.io.files.read_trial` reads the file back.
    """
    cols = ["t [s]"] + [f"{c} [{CHANNELS.get(name, '-')}]" for name in v.columns for c in (name, f"{name}_pred")]
    data = np.column_stack([v.t] + [a for j in range(len(v.columns))
                                    for a in (v.measured[:, j], v.predicted[:, j])])
    lines = [",".join(cols)] + [",".join("" if not np.isfinite(x) else repr(float(x)) for x in row)
                                for row in data]
    return atomic_write_text(path, "\n".join(lines) + "\n", force=force)


def local_fit(t: np.ndarray, y: np.ndarray, centres: np.ndarray, half: float) -> tuple[np.ndarray, np.ndarray]:
    """Value and slope at ``t[centres]`` of a straight line fitted to ``y`` within ±``half`` s.

    The measured state of a model whose states are not all measured (velocities from positions):
    a local least-squares line through the noisy samples around each start.
    """
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    val = np.empty(len(centres))
    slope = np.empty(len(centres))
    for i, c in enumerate(np.asarray(centres, dtype=int)):
        w = np.abs(t - t[c]) <= half + 1e-9
        tw = t[w] - t[c]
        yw = y[w]
        A = np.column_stack([np.ones_like(tw), tw])
        coef = np.linalg.lstsq(A, yw, rcond=None)[0]
        val[i], slope[i] = coef
    return val, slope


def wrap_deg(a: np.ndarray) -> np.ndarray:
    """An angle difference (rad) in degrees, wrapped to ±180°."""
    return np.degrees(np.angle(np.exp(1j * np.asarray(a))))


def check_finite(trial_source: str | None, arrays: Mapping[str, np.ndarray]) -> None:
    """One line naming the channel and row of the first missing value."""
    for name, a in arrays.items():
        bad = ~np.isfinite(np.asarray(a, dtype=float))
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            raise InputError("missing value (read the run with interpolate_gaps or trim_empty_rows)",
                             file=trial_source, channel=name, row=k + 1)


__all__ = ["Validation", "summarise", "summary_text", "figure", "horizon_starts", "error_table", "plot_series",
           "write_csv", "local_fit", "wrap_deg", "check_finite"]
