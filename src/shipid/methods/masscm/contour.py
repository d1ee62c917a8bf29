"""Fig. 4 of Linder et al. (2015): the IV cost (40) over (m, zm_bar) with the other parameters fixed.

The cost is the criterion of the last iteration of Algorithm 1 (its instruments, prefilters and
weights), evaluated on a grid of load mass and centre; every other parameter stays at the estimate.
The paper's observation — a unique minimum in a long, flat valley — follows from the identifiable
combination: the valley runs along constant load moment ``m z_m`` (dotted line in the figure).
"""

from __future__ import annotations

import numpy as np

from shipid.methods.masscm.criterion import residual_function
from shipid.methods.masscm.estimator import MassCMOptions, iterate, prepare
from shipid.models.roll_reduced import KnownParams, to_moment
from shipid.models.roll_sim import simulate_datasets
from shipid.outputs import atomic_write
from shipid.vessels import load_vessel


def cost_grid(data_seed: int = 0, zf_mode: str = "known", n: int = 61, span_m: float = 0.05,
              span_z: float = 0.02, vessel: str = "fishing-vessel") -> dict:
    """Cost (40) on an ``n × n`` grid around the estimate (relative span ``span_m`` in m, ``span_z`` m in zm_bar)."""
    d = simulate_datasets(vessel, seed=data_seed)
    known = KnownParams.from_vessel(vessel)
    prep = prepare(list(d.items()))
    z_f = float(load_vessel(vessel).value("general", "z_f")) if zf_mode == "known" else None
    core = iterate(prep, known, np.zeros(9), z_f=z_f, init="linear", options=MassCMOptions(noise_model="ar"))
    th = core["theta"]
    free = np.ones(9, dtype=bool)
    fun, _ = residual_function(core["state"], known, free, to_moment(th), None)
    ms = th[7] * (1 + np.linspace(-span_m, span_m, n))
    zs = th[8] + np.linspace(-span_z, span_z, n)
    C = np.empty((n, n))
    for a, zm in enumerate(zs):
        for b, m in enumerate(ms):
            t = th.copy()
            t[7], t[8] = m, zm
            C[a, b] = float(np.sum(fun(to_moment(t)) ** 2))
    return {"m": ms, "zm_bar": zs, "cost": C, "theta": th, "converged": core["converged"]}


def contour_figure(out, *, data_seed: int = 0, zf_mode: str = "known", force: bool = False,
                   grid: dict | None = None):
    """Draw Fig. 4 to ``out`` (format from the extension); returns the path.

    ``grid`` is a :func:`cost_grid` result to draw (computed here when not given).
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    g = cost_grid(data_seed=data_seed, zf_mode=zf_mode) if grid is None else grid
    th = g["theta"]
    fig, ax = plt.subplots(figsize=(6, 4.5))
    M, Z = np.meshgrid(g["m"], g["zm_bar"])
    cs = ax.contour(M, Z, np.log10(g["cost"]), levels=20)
    fig.colorbar(cs, ax=ax, label="log10 cost (40)")
    q = th[7] * (th[8] + th[6])
    ax.plot(g["m"], q / g["m"] - th[6], ":k", label="constant load moment m z_m")
    i = np.unravel_index(np.argmin(g["cost"]), g["cost"].shape)
    ax.plot(g["m"][i[1]], g["zm_bar"][i[0]], "rx", ms=10, mew=2, label="minimum")
    ax.set_xlabel("m [kg]")
    ax.set_ylabel("zm_bar [m]")
    ax.set_ylim(g["zm_bar"][0], g["zm_bar"][-1])
    ax.set_title("Linder et al. 2015 Fig. 4: IV cost over (m, zm_bar)")
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    path = atomic_write(out, lambda p: fig.savefig(p, format=str(out).rsplit(".", 1)[-1] if "." in str(out) else "png"),
                        force=force)
    plt.close(fig)
    return path


__all__ = ["cost_grid", "contour_figure"]
