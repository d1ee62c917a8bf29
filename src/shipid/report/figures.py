"""Generic report figures (matplotlib, Agg canvas, no pyplot state).

Every function takes the convention dicts described in :mod:`shipid.report`
and returns a :class:`matplotlib.figure.Figure`; :func:`to_data_uri` turns a
figure into an inline ``data:image/png;base64`` URI. Axes are labelled with
quantity and unit (``t [s]``, ``r [rad/s]``). Long records are decimated for
drawing only.
"""

from __future__ import annotations

import base64
import functools
import io
import math
from typing import Iterable, Mapping, Sequence

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import LogNorm, TwoSlopeNorm
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, MaxNLocator

from shipid.report.stats import Z95
from shipid.report.units import pretty_unit

MAX_POINTS = 4000
WIDTH_IN = 9.6
DPI = 100

#: Colours: measured data in near-black, model in blue, bands light, reference dashed red.
C_MEAS = "#222222"
C_MODEL = "#1f6fb4"
C_BAND = "#9cc3e6"
C_TRUE = "#c0392b"
PALETTE = ["#1f6fb4", "#e07b00", "#2e8b57", "#c0392b", "#7b4fa0", "#8c6d31", "#d6609f", "#555555"]

_STYLE = {
    "font.size": 10.0,
    "axes.titlesize": 10.5,
    "axes.labelsize": 10.0,
    "axes.grid": True,
    "grid.color": "#dddddd",
    "grid.linewidth": 0.6,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "axes.edgecolor": "#888888",
    "legend.fontsize": 9.0,
    "legend.frameon": True,
    "legend.framealpha": 0.85,
    "legend.edgecolor": "#dddddd",
    "xtick.labelsize": 9.0,
    "ytick.labelsize": 9.0,
    "axes.formatter.useoffset": False,
    "axes.formatter.limits": (-4, 5),
    "lines.linewidth": 1.1,
    "figure.dpi": DPI,
}


def style():
    """Context manager applying the report's matplotlib style (use it while building a figure)."""
    import matplotlib

    return matplotlib.rc_context(_STYLE)


def _styled(fn):
    """Build the figure inside :func:`style` so text sizes and legends follow the report style."""
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with style():
            return fn(*args, **kwargs)
    return wrapper


def new_figure(width: float = WIDTH_IN, height: float = 3.2) -> Figure:
    """A figure attached to an Agg canvas, styled like the rest of the report."""
    import matplotlib

    with matplotlib.rc_context(_STYLE):
        fig = Figure(figsize=(width, height), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    fig._shipid_style = dict(_STYLE)  # applied again when drawn
    return fig


def to_png(fig: Figure, dpi: int = DPI) -> bytes:
    """Render ``fig`` to PNG bytes; a label with broken mathtext is shown literally instead."""
    import matplotlib

    buf = io.BytesIO()
    with matplotlib.rc_context(getattr(fig, "_shipid_style", _STYLE)):
        try:
            fig.savefig(buf, format="png", dpi=dpi)
        except ValueError:  # e.g. an unbalanced "$" in a label: show it as plain text
            for text in fig.findobj(lambda a: hasattr(a, "get_text") and hasattr(a, "set_text")):
                s = text.get_text()
                if "$" in s:
                    text.set_text(s.replace("$", r"\$"))
            buf = io.BytesIO()
            fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()


def to_data_uri(fig: Figure, dpi: int = DPI) -> str:
    """``data:image/png;base64,...`` of ``fig``."""
    return "data:image/png;base64," + base64.b64encode(to_png(fig, dpi)).decode("ascii")


# -- helpers ---------------------------------------------------------------------------------------

def axis_label(name: str, unit: str | None, width: int = 26) -> str:
    """``name [unit]`` (``[-]`` for dimensionless), wrapped onto two lines when long."""
    if unit and unit not in ("-", "1", ""):
        text = f"{name} [{unit}]"
    else:
        text = f"{name} [-]" if unit in ("-", "1") else name
    if len(text) > width and "$" not in text:
        import textwrap

        text = "\n".join(textwrap.wrap(text, width)[:3])
    return text


_SUP = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def eng_scale(*arrays, unit: str | None = None) -> tuple[float, str]:
    """Engineering scale for an axis: (factor to divide by, unit text such as ``10⁶ kg``).

    Values of magnitude ≥ 10⁴ or < 10⁻³ are shown as multiples of 10^(3k) so that tick
    labels stay short and no offset text collides with the axis title.
    """
    mags = [np.nanmax(np.abs(a)) for a in arrays if np.size(a) and np.isfinite(a).any()]
    big = max(mags) if mags else 0.0
    u = unit if unit not in (None, "", "-", "1") else ""
    if not big or not np.isfinite(big) or 1e-3 <= big < 1e4:
        return 1.0, (unit or "")
    e = int(3 * math.floor(math.log10(big) / 3))
    if e == 0:
        return 1.0, (unit or "")
    pre = f"10{str(e).translate(_SUP)}"
    return 10.0 ** e, f"{pre} {u}".strip()


def _arr(a) -> np.ndarray:
    return np.asarray(a if a is not None else [], dtype=float).ravel()


def _short_formatter() -> FuncFormatter:
    """Tick labels with 3 significant digits and true minus signs (no 3.51235×10¹)."""
    def f(x, _pos=None):
        if x == 0:
            return "0"
        s = f"{x:.3g}"
        if "e" in s:
            m, e = s.split("e")
            s = f"{m}×10{str(int(e)).translate(_SUP)}"
        return s.replace("-", "−")
    return FuncFormatter(f)


def decimate(n: int, max_points: int = MAX_POINTS) -> slice:
    """Stride slice keeping at most about ``max_points`` samples (drawing only)."""
    step = max(1, int(math.ceil(n / max_points)))
    return slice(None, None, step)


def in_degrees(entry: Mapping) -> Mapping:
    """A time-history entry with unit ``rad`` or ``rad/s`` converted to ``deg`` / ``deg/s`` (the unit of
    every table of angles); other entries unchanged. Converts ``measured``, ``model``, ``values``,
    ``std`` and each of ``lines``."""
    unit = str(entry.get("unit", "") or "")
    if unit not in ("rad", "rad/s", "rad/s^2", "rad/s²"):
        return entry
    out = dict(entry)
    out["unit"] = unit.replace("rad", "deg")
    for k in ("measured", "model", "values", "std"):
        if out.get(k) is not None and not isinstance(out[k], Mapping):
            out[k] = np.degrees(np.asarray(out[k], dtype=float)).tolist()
    for k in ("lines", "std"):
        if isinstance(entry.get(k), Mapping):
            out[k] = {n: np.degrees(np.asarray(v, dtype=float)).tolist() for n, v in entry[k].items()}
    return out


#: Zero crossings above which a whole-record overlay is a solid block: the top panel then zooms in.
MAX_CROSSINGS = 60


def zoom_window(t: np.ndarray, y: np.ndarray, crossings: int = MAX_CROSSINGS // 2) -> tuple[int, int] | None:
    """Index range ``(i0, i1)`` of about ``crossings`` zero crossings of ``y − mean`` in the middle of the
    record, when the whole record has more than :data:`MAX_CROSSINGS`; else ``None`` (draw it all)."""
    y = np.asarray(y, dtype=float)
    ok = np.isfinite(y)
    if y.size < 100 or not ok.any():
        return None
    d = np.where(ok, y - np.nanmean(y), 0.0)
    idx = np.flatnonzero(np.signbit(d[1:]) != np.signbit(d[:-1]))
    if idx.size <= MAX_CROSSINGS:
        return None
    mid = idx.size // 2
    a, b = idx[max(mid - crossings // 2, 0)], idx[min(mid + crossings // 2, idx.size - 1)]
    return int(a), int(b) + 1


def _dt(t: np.ndarray) -> float | None:
    """Median sample interval when the record is (nearly) uniform, else None (lags stay in samples)."""
    if t.size < 3:
        return None
    d = np.diff(t)
    med = float(np.median(d))
    if not np.isfinite(med) or med <= 0 or np.max(np.abs(d - med)) > 0.01 * med:
        return None
    return med


def _short(label: str) -> str:
    """Axis label without a trailing parenthetical (the caption carries it), file paths as file names."""
    import re

    label = re.sub(r"(?:[\w.\-+@~]*/)+([\w.\-+@]+)", r"\1", str(label))
    return re.sub(r"\s*\(.*\)\s*$", "", label) or label


def _ylabel(label: str, unit: str | None) -> str:
    """``quantity [unit]`` when short; only ``[unit]`` for a long quantity (the axes title names it)."""
    q = _short(label)
    u = _pretty(unit)
    return axis_label(q, u) if len(q) <= 24 else (f"[{u}]" if u and u not in ("-", "1") else "[-]")


def _grid(n: int, ncols: int) -> tuple[int, int]:
    ncols = max(1, min(ncols, n))
    return int(math.ceil(n / ncols)), ncols


# -- time histories --------------------------------------------------------------------------------

@_styled
def overlay_figure(name: str, entry: Mapping, resid: np.ndarray, acf_vals: np.ndarray,
                   bound: float) -> Figure:
    """Measured vs model (top), residual (bottom left) and its ACF with ±1.96/√N bounds (bottom right)."""
    t = _arr(entry["t"])
    meas, mod = _arr(entry["measured"]), _arr(entry["model"])
    unit = entry.get("unit", "")
    label = entry.get("label", name)
    fig = new_figure(height=4.8)
    gs = fig.add_gridspec(2, 3, height_ratios=[1.35, 1.0])
    ax = fig.add_subplot(gs[0, :])
    sl = decimate(t.size)
    k, su = eng_scale(meas, mod, unit=unit)
    zoom = zoom_window(t, meas)
    if zoom is not None:   # a long record of many cycles: the top panel shows a window, legibly
        zs = slice(*zoom)
        ax.plot(t[zs], meas[zs] / k, color=C_MEAS, lw=0.9, label="measured")
        ax.plot(t[zs], mod[zs] / k, color=C_MODEL, lw=1.3, label="model")
        title = f"{_short(label)}: t = {t[zoom[0]]:.0f}–{t[zoom[1] - 1]:.0f} s of {t[-1] - t[0]:.0f} s"
    else:
        ax.plot(t[sl], meas[sl] / k, color=C_MEAS, lw=0.9, label="measured")
        ax.plot(t[sl], mod[sl] / k, color=C_MODEL, lw=1.3, label="model")
        title = f"{_short(label)}: measured and model"
    ax.set_xlabel("t [s]")
    ax.set_ylabel(_ylabel(label, su))
    ax.legend(loc="upper right", ncols=2)
    ax.set_title(title if len(title) <= 70 else title[:69] + "…", loc="left")
    ax_r = fig.add_subplot(gs[1, :2])
    kr, sur = eng_scale(resid, unit=unit)
    ax_r.plot(t[sl], resid[sl] / kr, color=C_MODEL, lw=0.8)
    ax_r.axhline(0.0, color="#888888", lw=0.7)
    ax_r.set_xlabel("t [s]")
    ax_r.set_ylabel(axis_label("residual", sur))
    ax_r.set_title("residual = measured − model" + (", whole record" if zoom is not None else ""), loc="left")
    _acf_axes(fig.add_subplot(gs[1, 2]), acf_vals, bound, _dt(t))
    return fig


@_styled
def residual_figure(name: str, entry: Mapping, acf_vals: np.ndarray, bound: float) -> Figure:
    """Residual (or innovation) vs time with its predicted ±2σ band, and its ACF."""
    t, v = _arr(entry["t"]), _arr(entry["values"])
    unit = entry.get("unit", "")
    label = entry.get("label", name)
    fig = new_figure(height=2.8)
    gs = fig.add_gridspec(1, 3)
    ax = fig.add_subplot(gs[0, :2])
    sl = decimate(t.size)
    std = entry.get("std")
    s = _arr(std) if std is not None else None
    k, su = eng_scale(v, *([2 * s] if s is not None and s.shape == v.shape else []), unit=unit)
    if s is not None and s.shape == v.shape:
        ax.fill_between(t[sl], -2 * s[sl] / k, 2 * s[sl] / k, color=C_BAND, alpha=0.5, lw=0,
                        label="±2σ predicted")
        ax.legend(loc="upper right")
    ax.plot(t[sl], v[sl] / k, color=C_MODEL, lw=0.8)
    if s is not None and s.shape == v.shape:
        # the first innovations carry the prior's large σ: scale to the residual and the typical band
        fin_v, fin_s = np.abs(v[np.isfinite(v)]), 2 * s[np.isfinite(s)]
        if fin_v.size and fin_s.size:
            lim = 1.15 * max(float(fin_v.max()), float(np.percentile(fin_s, 90)))
            if lim > 0:
                ax.set_ylim(-lim / k, lim / k)
    ax.axhline(0.0, color="#888888", lw=0.7)
    ax.set_xlabel("t [s]")
    ax.set_ylabel(_ylabel(label, su))
    title = _short(label)
    ax.set_title(title if len(title) <= 60 else title[:59] + "…", loc="left")
    _acf_axes(fig.add_subplot(gs[0, 2]), acf_vals, bound, _dt(t))
    return fig


def _acf_axes(ax, r: np.ndarray, bound: float, dt: float | None = None) -> None:
    lags = np.arange(r.size) * (dt if dt else 1.0)
    if r.size <= 80:
        ax.vlines(lags, 0.0, r, color=C_MODEL, lw=1.2)
        ax.plot(lags, r, "o", ms=2.2, color=C_MODEL)
    else:  # many lags: a line reads better than a forest of stems
        ax.plot(lags, r, color=C_MODEL, lw=1.2)
    if np.isfinite(bound):
        ax.axhspan(-bound, bound, color=C_BAND, alpha=0.35, lw=0, label="±1.96/√N")
        ax.legend(loc="upper right")
    ax.axhline(0.0, color="#888888", lw=0.7)
    ax.set_xlabel("lag [s]" if dt else "lag [samples]")
    ax.set_ylabel("autocorrelation [-]")
    ax.set_ylim(min(-0.3, float(np.nanmin(r)) - 0.05), 1.05)
    ax.set_title("residual autocorrelation", loc="left")


def _settled_ylim(t, v, s, true) -> tuple[float, float] | None:
    """y-range that keeps the settled part readable when the start-up transient is much wider.

    Returns limits from the last 90 % of the record (value ± σ, and the true value), padded by
    25 %, when the full range is more than three times wider; otherwise ``None`` (autoscale).
    """
    if t.size < 10:
        return None
    band_lo = v - s if s is not None and s.shape == v.shape else v
    band_hi = v + s if s is not None and s.shape == v.shape else v
    full = np.nanmax(band_hi) - np.nanmin(band_lo)
    late = t >= t[0] + 0.1 * (t[-1] - t[0])
    vals = np.concatenate([band_lo[late], band_hi[late], [true] if np.isfinite(true) else []])
    vals = vals[np.isfinite(vals)]
    if not vals.size:
        return None
    lo, hi = float(vals.min()), float(vals.max())
    span = hi - lo
    if not np.isfinite(full) or span <= 0 or full <= 3 * span:
        return None
    return lo - 0.25 * span, hi + 0.25 * span


@_styled
def histories_figure(entries: Sequence[tuple[str, Mapping]], ncols: int = 3) -> Figure:
    """Parameter histories with ±σ bands (Fossen, Sagatun & Sørensen 1996, Fig. 8 style); dashed red line at the true value."""
    nrows, ncols = _grid(len(entries), ncols)
    fig = new_figure(height=max(2.0, 1.9 * nrows + 0.3))
    axes = fig.subplots(nrows, ncols, squeeze=False, sharex=False)
    for k, (name, e) in enumerate(entries):
        ax = axes[k // ncols][k % ncols]
        t, v = _arr(e["t"]), _arr(e["value"])
        sl = decimate(t.size)
        true = float(e["true"]) if e.get("true") is not None else float("nan")
        sc, su = eng_scale(v, np.array([true]), unit=e.get("unit"))
        if e.get("std") is not None:
            s = _arr(e["std"])
            if s.shape == v.shape:
                ax.fill_between(t[sl], (v - s)[sl] / sc, (v + s)[sl] / sc, color=C_BAND, alpha=0.6, lw=0,
                                label="±σ")
        ax.plot(t[sl], v[sl] / sc, color=C_MODEL, lw=1.1, label="estimate")
        if np.isfinite(true):
            ax.axhline(true / sc, color=C_TRUE, ls="--", lw=1.0, label="true")
        lim = _settled_ylim(t, v, _arr(e["std"]) if e.get("std") is not None else None, true)
        if lim is not None:
            ax.set_ylim(lim[0] / sc, lim[1] / sc)
        label = str(e.get("label", name))
        if len(label) > 14 or ncols > 1:
            import textwrap

            width = max(18, int(96 / ncols) - 6)  # characters that fit over one panel at 9 pt
            ax.set_title("\n".join(textwrap.wrap(label, width)[:3]), loc="left", fontsize=9.0)
            ax.set_ylabel(f"[{_pretty(su)}]" if su else "")
        else:
            ax.set_ylabel(axis_label(label, su))
        ax.set_xlabel("t [s]")
        if k == 0:
            handles, labels = ax.get_legend_handles_labels()
    if entries:
        fig.legend(handles, labels, loc="outside upper right", ncols=len(labels))
    for k in range(len(entries), nrows * ncols):
        axes[k // ncols][k % ncols].set_visible(False)
    return fig


@_styled
def signals_figure(entries: Sequence[tuple[str, Mapping]]) -> Figure:
    """Stacked time histories sharing the time axis (Yoon & Rhee 2003, Figs 4, 9: smoothed motion, forces)."""
    n = len(entries)
    fig = new_figure(height=max(2.2, 1.9 * n + 0.5))
    axes = fig.subplots(n, 1, squeeze=False, sharex=True)[:, 0]
    for ax, (name, e) in zip(axes, entries):
        t = _arr(e["t"])
        sl = decimate(t.size)
        lines = e.get("lines")
        if lines is None and "values" in e:
            lines = {e.get("label", name): e["values"]}
        stds = e.get("std") or {}
        k, su = eng_scale(*[_arr(v) for v in (lines or {}).values()], unit=e.get("unit"))
        for j, (lab, vals) in enumerate((lines or {}).items()):
            v = _arr(vals)
            col = PALETTE[j % len(PALETTE)]
            if lab in stds:
                s = _arr(stds[lab])
                if s.shape == v.shape:
                    ax.fill_between(t[sl], (v - 2 * s)[sl] / k, (v + 2 * s)[sl] / k, color=col, alpha=0.18,
                                    lw=0)
            ax.plot(t[sl], v[sl] / k, color=col, lw=1.0 if j else 1.2, label=lab)
        label = str(e.get("label", name))
        if n > 1 or len(label) > 14:  # stacked panels: the quantity as panel title, the unit on the axis
            ax.set_title(label, loc="left", fontsize=9.5)
            ax.set_ylabel(f"[{_pretty(su)}]" if su and su not in ("-", "1") else "[-]")
        else:
            ax.set_ylabel(axis_label(label, _pretty(su)))
        if lines and len(lines) > 1:
            ax.legend(loc="upper right", ncols=min(4, len(lines)))
    axes[-1].set_xlabel("t [s]")
    return fig


def _pretty(u: str | None) -> str:

    return pretty_unit(u)


def label_problems(fig: Figure) -> list[str]:
    """Labels that overlap each other or stick out of the figure, after drawing it (empty: clean).

    Checks every axis label, axes title and legend: pairwise intersections of their rendered
    boxes (shrunk by one pixel) and containment in the figure. Used by the tests.
    """
    import matplotlib

    with matplotlib.rc_context(getattr(fig, "_shipid_style", _STYLE)):
        fig.canvas.draw()
        rend = fig.canvas.get_renderer()
        boxes = []
        for i, ax in enumerate(fig.axes):
            if not ax.get_visible():
                continue
            arts = [("x label", ax.xaxis.label), ("y label", ax.yaxis.label), ("title", ax.title),
                    ("left title", ax._left_title), ("right title", ax._right_title)]
            if ax.get_legend() is not None:
                arts.append(("legend", ax.get_legend()))
            for what, a in arts:
                if what != "legend" and not a.get_text():
                    continue
                bb = a.get_window_extent(rend)
                if bb.width > 0 and bb.height > 0:
                    boxes.append((f"axes {i} {what} {getattr(a, 'get_text', lambda: '')()!r}", bb))
        W, H = fig.bbox.width, fig.bbox.height
        out = []
        for name, bb in boxes:
            if bb.x0 < -1 or bb.y0 < -1 or bb.x1 > W + 1 or bb.y1 > H + 1:
                out.append(f"{name} is clipped by the figure edge")
        for j, (n1, b1) in enumerate(boxes):
            for n2, b2 in boxes[j + 1:]:
                if "legend" in n1 and "legend" in n2:
                    continue
                if (min(b1.x1, b2.x1) - max(b1.x0, b2.x0) > 1) and (min(b1.y1, b2.y1) - max(b1.y0, b2.y0) > 1):
                    if "legend" in n1 or "legend" in n2:
                        continue  # a legend inside the plot area may cover a title only by design: skip
                    out.append(f"{n1} overlaps {n2}")
    return out


# -- fields ----------------------------------------------------------------------------------------

@_styled
def matrix_figure(entry: Mapping, *, title: str | None = None) -> Figure:
    """Heat map of a matrix with a colour bar; cells annotated when the matrix is small."""
    m = np.asarray(entry["values"], dtype=float)
    if m.ndim != 2:
        raise ValueError(f"matrix must be 2-D, got shape {m.shape}")
    rows = list(entry.get("rows") or [str(i) for i in range(m.shape[0])])
    cols = list(entry.get("cols") or rows if m.shape[0] == m.shape[1] else range(m.shape[1]))
    cols = [str(c) for c in cols]
    finite = m[np.isfinite(m)]
    vmin, vmax = entry.get("vmin"), entry.get("vmax")
    if vmin is None or vmax is None:
        if finite.size and finite.min() < 0 < finite.max():
            a = float(np.max(np.abs(finite)))
            vmin, vmax = (-a, a) if vmin is None and vmax is None else (vmin, vmax)
        elif finite.size:
            vmin = float(finite.min()) if vmin is None else vmin
            vmax = float(finite.max()) if vmax is None else vmax
    diverging = vmin is not None and vmax is not None and vmin < 0 < vmax
    side = min(7.5, 2.2 + 0.42 * max(m.shape))
    fig = new_figure(width=side + 1.4, height=side)
    ax = fig.add_subplot()
    norm = TwoSlopeNorm(0.0, vmin, vmax) if diverging else None
    im = ax.imshow(m, cmap="RdBu_r" if diverging else "viridis", norm=norm,
                   vmin=None if diverging else vmin, vmax=None if diverging else vmax,
                   interpolation="nearest", aspect="equal")
    ax.set_xticks(range(m.shape[1]), cols, rotation=60 if max(len(c) for c in cols) > 3 else 0,
                  ha="right" if max(len(c) for c in cols) > 3 else "center")
    ax.set_yticks(range(m.shape[0]), rows)
    ax.grid(False)
    for s in ax.spines.values():
        s.set_visible(False)
    annotate = entry.get("annotate")
    if annotate is None:
        annotate = max(m.shape) <= 14
    if annotate:
        scale = max(abs(vmin or 0), abs(vmax or 0)) or 1.0
        for i in range(m.shape[0]):
            for j in range(m.shape[1]):
                val = m[i, j]
                if np.isfinite(val):
                    ax.text(j, i, f"{val:.2f}" if abs(val) < 100 else f"{val:.3g}", ha="center",
                            va="center", fontsize=7, color="white" if abs(val) > 0.6 * scale else "#222222")
    cb = fig.colorbar(im, ax=ax, shrink=0.8)
    if entry.get("unit"):
        cb.set_label(entry["unit"])
    if title:
        ax.set_title(title, loc="left")
    return fig


def correlation_from_covariance(cov, names: Sequence[str]) -> dict:
    """Correlation-matrix entry (convention ``matrices``) from a covariance matrix."""
    c = np.asarray(cov, dtype=float)
    d = np.sqrt(np.clip(np.diag(c), 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        r = c / np.outer(d, d)
    r[~np.isfinite(r)] = np.nan
    return {"values": r.tolist(), "rows": list(names), "cols": list(names), "vmin": -1.0, "vmax": 1.0,
            "unit": "correlation [-]"}


@_styled
def contour_figure(entry: Mapping) -> Figure:
    """Filled contour of a scalar field (mass-cm Fig. 4 cost over (m, z̄_m); EBM Fig. 7 D-optimal map)."""
    x, y = _arr(entry["x"]), _arr(entry["y"])
    z = np.asarray(entry["z"], dtype=float)
    if z.shape != (y.size, x.size):
        raise ValueError(f"contour z has shape {z.shape}, expected ({y.size}, {x.size})")
    fig = new_figure(width=6.8, height=4.6)
    ax = fig.add_subplot()
    finite = z[np.isfinite(z)]
    use_log = bool(entry.get("log")) and finite.size and finite.min() > 0
    if use_log:
        levels = np.geomspace(finite.min(), finite.max(), 20) if finite.max() > finite.min() else 10
        cs = ax.contourf(x, y, z, levels=levels, norm=LogNorm(), cmap="viridis")
    else:
        cs = ax.contourf(x, y, z, levels=20, cmap="viridis")
    ax.contour(x, y, z, levels=cs.levels[::2], colors="white", linewidths=0.4, alpha=0.6)
    cb = fig.colorbar(cs, ax=ax, format=_short_formatter())
    cb.set_label(entry.get("z_label", "value"))
    ax.xaxis.set_major_locator(MaxNLocator(7))
    ax.yaxis.set_major_locator(MaxNLocator(8))
    for j, p in enumerate(entry.get("points") or []):
        mk = ["x", "o", "^", "s", "D"][j % 5]
        ax.plot([p["x"]], [p["y"]], mk, color=["#ffffff", C_TRUE, "#ffb000", "#00d0ff", "#ff66cc"][j % 5],
                ms=8, mew=2, mfc="none" if mk != "x" else None, label=p.get("label"))
    if entry.get("points"):
        ax.legend(loc="upper right", frameon=True, facecolor="white", framealpha=0.8)
    ax.set_xlabel(axis_label(entry.get("x_label", "x"), entry.get("x_unit")))
    ax.set_ylabel(axis_label(entry.get("y_label", "y"), entry.get("y_unit")))
    ax.grid(False)
    return fig


@_styled
def xy_figure(entry: Mapping) -> Figure:
    """Generic x–y lines or scatter."""
    x = _arr(entry["x"])
    fig = new_figure(width=6.8 if entry.get("style") == "scatter" else WIDTH_IN, height=3.6)
    ax = fig.add_subplot()
    lines = entry.get("lines") or {}
    for j, (lab, vals) in enumerate(lines.items()):
        v = _arr(vals)
        col = PALETTE[j % len(PALETTE)]
        if entry.get("style") == "scatter":
            ax.plot(x, v, "o", ms=3.5, alpha=0.7, color=col, label=lab)
        else:
            sl = decimate(x.size)
            ax.plot(x[sl], v[sl], color=col, label=lab)
    if len(lines) > 1:
        ax.legend(loc="best")
    ax.set_xlabel(axis_label(entry.get("x_label", "x"), entry.get("x_unit")))
    ax.set_ylabel(axis_label(entry.get("y_label", "y"), entry.get("y_unit")))
    return fig
