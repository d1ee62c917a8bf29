"""Parameter estimates versus time for the DP identification (Fossen et al. 1996, Fig. 8)."""

from __future__ import annotations

import os

from shipid.outputs import atomic_write
from shipid.result import Result


def plot_parameter_histories(result: Result, path: str | os.PathLike, *, force: bool = False):
    """Draw θ1''…θ9'' versus time with ±2σ bands (and the true value when known); write a PNG.

    Uses ``result.series["histories"]`` (made by :func:`shipid.methods.dp.series.with_series`).
    Each scheme (SI1–SI3) has its own time axis: the time of its longest trial.
    """
    import matplotlib
    matplotlib.use("Agg")
    import numpy as np
    from matplotlib.figure import Figure

    hist = result.series.get("histories", {})
    names = sorted(hist, key=lambda n: int(n.replace("theta", "")))
    fig = Figure(figsize=(12, 9), layout="constrained")
    axes = fig.subplots(3, 3).ravel()
    for ax, nm in zip(axes, names):
        h = hist[nm]
        t = np.asarray(h["t"])
        v = np.asarray(h["value"])
        ax.plot(t, v, color="C0", lw=1.2, label="estimate")
        if "std" in h:
            sd = np.asarray(h["std"])
            ax.fill_between(t, v - 2 * sd, v + 2 * sd, color="C0", alpha=0.2, label="±2σ")
        if "true" in h:
            ax.axhline(h["true"], color="k", ls="--", lw=1, label="true")
        ax.set_title(h.get("label", nm), fontsize=9)
        ax.set_xlabel("time [s]")
        ax.set_ylabel(f"θ{nm[5:]}'' [-] (bis)")
        ax.grid(alpha=0.3)
        # keep the converged part readable: limits from the second half ± a margin
        half = v[len(v) // 2:]
        lo, hi = float(np.min(half)), float(np.max(half))
        if "true" in h:
            lo, hi = min(lo, h["true"]), max(hi, h["true"])
        pad = max(hi - lo, 0.05 * max(abs(lo), abs(hi), 1e-12)) * 1.5
        ax.set_ylim(lo - pad, hi + pad)
    for ax in axes[len(names):]:
        ax.set_visible(False)
    if names:
        axes[0].legend(fontsize=8, loc="best")
    fig.suptitle("DP identification: parameter estimates vs time (cf. Fossen, Sagatun & Sørensen 1996, Fig. 8)")
    return atomic_write(path, lambda p: fig.savefig(p, dpi=110, format="png"), force=force)


__all__ = ["plot_parameter_histories"]
