"""D-optimal PRBS rudder input for EBM identification (Yoon & Rhee 2003, §5.1.4, Figs. 7–8).

The regression of step 2 is best conditioned when the unit-length-scaled regressor
matrix W (eq. 16) has the largest ``|WᵀW|`` (D-optimality; ``WᵀW`` is the
correlation matrix, so ``0 < |WᵀW| ≤ 1`` with 1 for orthogonal regressors). W is the
ship's response to the rudder, so ``|WᵀW|`` is a function of the PRBS amplitude
and clock period (Fig. 7) and of the current speed (Fig. 8). We evaluate it on the
noise-free simulated response of the true model, for the surge and sway
regressors (the yaw regressors are ``L`` times the sway ones, so their scaled W is
identical), and report ``log10 |WᵀW|``, averaged over a few PRBS register seeds
(one realisation of a PRBS is a noisy sample of the criterion).

Current (Fig. 8): in eqs. 1–3 a uniform constant current only carries the ship
along; the motion *relative to the water* — and so W — does not depend on it when
the approach speed through the water is fixed. The criterion varies with the
current only if the approach is defined over the ground, as in a tank with a
current generator where the carriage speed is set: :func:`current_sweep` fixes
the approach speed over ground at U0 (heading 0), so the speed through the water
is ``U0 − U_c cos ψ_c`` (the propeller rate follows it).

The optimum is the best point of a stated grid (:data:`DEFAULT_AMPLITUDES` ×
:data:`DEFAULT_PERIODS`, the defaults of :func:`prbs_grid` and of ``shipid design
prbs``), and :func:`paper_comparison` says, from the computed map, whether the
paper's optimum is the same point or within 2 standard errors of the
PRBS-realisation spread. A continuous optimisation is not used: the criterion of
one realisation jumps from period to period (see below), so its maximiser over a
continuum would be chosen by the noise.

Agreement with Fig. 7 (35°, 105 s), measured on 1200-s runs, dt = 1 s, the
packaged ESSO OSAKA, current 2 kn (``shipid design prbs --amplitudes 35 --periods
15:200:5 --seeds 8`` and an amplitude scan 5–35° at eight periods, 2 seeds):

* amplitude: the criterion grows with the amplitude from 20° up at every period but
  15 s, so the optimum is the largest amplitude allowed, 35°, as in the paper;
* period: it does **not** agree. On the 35° row, periods 15–200 s in steps of 5 s,
  8 PRBS seeds, the best period is 40 s (log10 |WᵀW| = −9.81 ± 0.17, mean ± SE over
  the seeds); at 105 s it is −10.38 ± 0.27, lower by 0.57 ± 0.26 (paired over the
  seeds, 2.2 SE). Resampling the 8 seeds (2000 bootstrap draws) puts the argmax at
  40 s in 70 % of the draws, at 45–50 s in 18 %, near 90 s in 5 % and never at 105 s.
  The row is flat within about 2 SE from 40 to 95 s; the paper's 105 s lies just
  beyond that plateau on this simulated criterion.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shipid.estimate.ridge import unit_length_scale
from shipid.methods.ebm.trials import simulate_trial
from shipid.models import abkowitz as ab
from shipid.report.convention import contour, table, xy
from shipid.result import Estimate, Result


def log_det_criterion(H: np.ndarray) -> float:
    """``log10 |WᵀW|`` of the unit-length-scaled regressors ``H`` (D-optimality)."""
    sc = unit_length_scale(H, np.ones(H.shape[0]))
    sign, logdet = np.linalg.slogdet(sc.correlation)
    return float(logdet / np.log(10.0)) if sign > 0 else float("-inf")


def prbs_criterion(amplitude_deg: float, period: float, *, duration: float = 1200.0, seed: int = 0,
                   current_speed: float | None = None, current_dir: float | None = None,
                   dt: float = 1.0, vessel: str = "esso-osaka", ground_speed: bool = False
                   ) -> dict[str, float]:
    """``log10 |WᵀW|`` of the surge and sway regressors for one PRBS run (noise-free truth).

    ``ground_speed=True`` fixes the approach speed over ground (see the module docstring).
    """

    tc = ab.trial_conditions(vessel)
    cs = tc["current_speed"] if current_speed is None else float(current_speed)
    cd = tc["current_dir"] if current_dir is None else float(current_dir)
    name = f"prbs-{amplitude_deg:g}-{period:g}"
    p = ab.params_from_vessel(vessel)
    speed = p.U0 - cs * np.cos(cd) if ground_speed else None
    if speed is not None and speed <= 0.5:
        raise ValueError(f"current {cs:.3g} m/s leaves no headway through the water")
    # oversample=1: the half-sample force lead of a coarse zero-order hold (ebm_trials)
    # matters for step 2 on estimated forces, not for the regressor geometry here
    tr = simulate_trial(name, duration, seed=seed, dt=dt, current=(cs, cd), noise=False, vessel=vessel,
                        speed=speed, oversample=1)
    HX, HY, _ = ab.regressors(tr["true_u_r"], tr["true_v_r"], tr["true_r"], tr["delta"], tr["n"], p)
    return {"surge": log_det_criterion(HX), "sway": log_det_criterion(HY)}


@dataclass(frozen=True)
class DesignGrid:
    """``log10 |WᵀW|`` over amplitude × period (Fig. 7)."""

    amplitudes: np.ndarray      # deg
    periods: np.ndarray         # s
    surge: np.ndarray           # (n_amp, n_per)
    sway: np.ndarray
    seeds: tuple[int, ...]
    duration: float
    current_speed: float
    dt: float = 1.0                 # s, simulation / sampling step
    vessel: str = "esso-osaka"
    sway_seeds: np.ndarray | None = None    # (n_amp, n_per, n_seeds): the value of each PRBS realisation
    surge_seeds: np.ndarray | None = None

    def optimum(self, mode: str = "sway") -> tuple[float, float, float]:
        """(amplitude deg, period s, log10 |WᵀW|) of the best grid point for ``mode``
        (``"sway"`` — also the yaw criterion — or ``"sum"`` of surge and sway)."""
        G = self.sway if mode == "sway" else (self.surge + self.sway if mode == "sum" else self.surge)
        i, j = np.unravel_index(int(np.nanargmax(G)), G.shape)
        return float(self.amplitudes[i]), float(self.periods[j]), float(G[i, j])

    def to_dict(self) -> dict:
        a, T, v = self.optimum("sway")
        return {"amplitudes_deg": self.amplitudes.tolist(), "periods_s": self.periods.tolist(),
                "log10_det_surge": self.surge.tolist(), "log10_det_sway": self.sway.tolist(),
                "seeds": list(self.seeds), "duration_s": self.duration, "current_speed_m_s": self.current_speed,
                "optimum_sway": {"amplitude_deg": a, "period_s": T, "log10_det": v}}


#: Default grid of :func:`prbs_grid` and ``shipid design prbs``: amplitudes 5–35° in steps of 10°
#: (the criterion grows with the amplitude, module docstring), periods 15–200 s in steps of 5 s.
DEFAULT_AMPLITUDES = (5.0, 15.0, 25.0, 35.0)
DEFAULT_PERIODS = tuple(float(p) for p in range(15, 205, 5))


def prbs_grid(amplitudes=DEFAULT_AMPLITUDES, periods=DEFAULT_PERIODS,
              *, duration: float = 1200.0, seeds=(0, 1, 2), current_speed: float | None = None,
              dt: float = 1.0, vessel: str = "esso-osaka", progress=None) -> DesignGrid:
    """Evaluate the D-criterion on an amplitude × period grid (Fig. 7).

    Every grid point is the mean over the PRBS register ``seeds`` of
    :func:`prbs_criterion`; the per-seed values are kept (``sway_seeds``,
    ``surge_seeds``) for the standard errors of :func:`paper_comparison`.
    """
    A = np.asarray(amplitudes, dtype=float)
    T = np.asarray(periods, dtype=float)
    seeds = tuple(int(s) for s in seeds)
    Ss = np.empty((A.size, T.size, len(seeds))); Ws = np.empty((A.size, T.size, len(seeds)))
    tc = ab.trial_conditions(vessel)
    cs = tc["current_speed"] if current_speed is None else float(current_speed)
    for i, a in enumerate(A):
        for j, per in enumerate(T):
            for k, s in enumerate(seeds):
                v = prbs_criterion(a, per, duration=duration, seed=s, current_speed=cs, dt=dt, vessel=vessel)
                Ss[i, j, k], Ws[i, j, k] = v["surge"], v["sway"]
            if progress is not None:
                progress()
    return DesignGrid(A, T, Ss.mean(axis=2), Ws.mean(axis=2), seeds, float(duration), cs, float(dt), vessel,
                      sway_seeds=Ws, surge_seeds=Ss)


#: The optimum of Fig. 7 of Yoon & Rhee (2003, §5.1.4): amplitude 35°, clock period 105 s.
PAPER_FIG7 = (35.0, 105.0)


def paper_comparison(grid: DesignGrid, paper: tuple[float, float] = PAPER_FIG7) -> dict:
    """Does the grid's sway optimum agree with the paper's Fig. 7 optimum? Computed, not asserted.

    The criterion of one PRBS realisation is a noisy sample, so the comparison is
    made against the realisation spread: with several seeds the difference between
    the optimum and the paper's point (both on the grid) is paired over the seeds and
    its standard error is ``std(differences) / sqrt(n_seeds)``.

    Returns
    -------
    dict
        ``paper`` (amplitude, period), ``optimum`` (amplitude, period), ``same_point``,
        ``on_grid`` (the paper's point is a grid point), ``log10_det_optimum``,
        ``log10_det_paper`` (or None), ``difference`` and ``difference_se`` (None
        without per-seed values or with one seed), ``verdict`` (``"same point"``,
        ``"within 2 SE"``, ``"differs"``, ``"differs (one seed, no SE)"`` or
        ``"not on the grid"``) and ``text``, one sentence for a caption.
    """
    a, per, val = grid.optimum("sway")
    pa, pp = float(paper[0]), float(paper[1])
    ia = np.flatnonzero(np.isclose(grid.amplitudes, pa))
    ip = np.flatnonzero(np.isclose(grid.periods, pp))
    out = {"paper": [pa, pp], "optimum": [a, per], "same_point": bool(np.isclose(a, pa) and np.isclose(per, pp)),
           "on_grid": bool(ia.size and ip.size), "log10_det_optimum": val, "log10_det_paper": None,
           "difference": None, "difference_se": None}
    if not out["on_grid"]:
        out["verdict"] = "not on the grid"
        out["text"] = (f"the paper's Fig. 7 optimum {pa:g}° / {pp:g} s is not a point of this grid, so this map "
                       f"neither confirms nor contradicts it (optimum here {a:g}° / {per:g} s)")
        return out
    i, j = int(ia[0]), int(ip[0])
    vp = float(grid.sway[i, j])
    out["log10_det_paper"] = vp
    out["difference"] = float(val - vp)
    if out["same_point"]:
        out["verdict"] = "same point"
        out["text"] = f"the optimum {a:g}° / {per:g} s is the paper's Fig. 7 optimum"
        return out
    ib = int(np.flatnonzero(np.isclose(grid.amplitudes, a))[0])
    jb = int(np.flatnonzero(np.isclose(grid.periods, per))[0])
    se = None
    if grid.sway_seeds is not None and grid.sway_seeds.shape[2] > 1:
        d = grid.sway_seeds[ib, jb] - grid.sway_seeds[i, j]
        se = float(np.std(d, ddof=1) / np.sqrt(d.size))
    out["difference_se"] = se
    head = (f"the optimum {a:g}° / {per:g} s is not the paper's Fig. 7 optimum {pa:g}° / {pp:g} s, where "
            f"log10 |WᵀW| is {out['difference']:.2f} lower")
    if se is None:
        out["verdict"] = "differs (one seed, no SE)"
        out["text"] = head + " (one PRBS seed: no standard error of the difference)"
    elif out["difference"] <= 2.0 * se:
        out["verdict"] = "within 2 SE"
        out["text"] = (head + f", within 2 standard errors ({se:.2f}, {grid.sway_seeds.shape[2]} PRBS seeds): "
                       "the map does not distinguish the two")
    else:
        out["verdict"] = "differs"
        out["text"] = (head + f", more than 2 standard errors ({se:.2f}, {grid.sway_seeds.shape[2]} PRBS seeds): "
                       "on this map the paper's point is not optimal")
    return out


def current_sweep(amplitude_deg: float, period: float, speeds=(-4.0, -2.0, 0.0, 2.0, 4.0), *,
                  duration: float = 1200.0, seeds=(0, 1, 2), dt: float = 1.0,
                  vessel: str = "esso-osaka") -> dict[str, list[float]]:
    """The D-criterion versus current speed (knots, towards 45°) at a fixed PRBS (Fig. 8).

    Approach speed over ground fixed at U0 (module docstring); negative speeds are
    a current setting towards 225°.
    """
    out = {"speeds_knot": [float(s) for s in speeds], "surge": [], "sway": []}
    for s in speeds:
        vals = [prbs_criterion(amplitude_deg, period, duration=duration, seed=k, dt=dt, vessel=vessel,
                               current_speed=float(s) * ab.KNOT, ground_speed=True) for k in seeds]
        out["surge"].append(float(np.mean([v["surge"] for v in vals])))
        out["sway"].append(float(np.mean([v["sway"] for v in vals])))
    return out


def _neighbours(values: np.ndarray, v: float) -> str:
    """Grid resolution around ``v``: the neighbouring grid values (or 'grid edge')."""
    vals = np.sort(np.asarray(values, dtype=float))
    i = int(np.argmin(np.abs(vals - v)))
    lo = f"{vals[i - 1]:g}" if i > 0 else "grid edge"
    hi = f"{vals[i + 1]:g}" if i + 1 < vals.size else "grid edge"
    return f"{lo} … {hi}"


def _axis_text(values: np.ndarray) -> str:
    """A grid axis as ``start–stop step d`` when evenly spaced, else the list of values."""
    v = np.asarray(values, dtype=float)
    if v.size > 2 and np.allclose(np.diff(v), v[1] - v[0]):
        return f"{v[0]:g}–{v[-1]:g} in steps of {v[1] - v[0]:g}"
    return ", ".join(f"{x:g}" for x in v)


def _grid_table(grid: DesignGrid, values: np.ndarray, what: str, paper: str | None) -> dict:

    cols = ["amplitude"] + [f"T = {p:g} s" for p in grid.periods]
    rows = [[float(a)] + [float(v) for v in values[i]] for i, a in enumerate(grid.amplitudes)]
    return table(cols, rows, units=["deg"] + ["-"] * grid.periods.size, paper=paper,
                 title=f"log10 |WᵀW| of the {what} regressors on the grid (rows: PRBS amplitude, columns: "
                       f"clock period; {grid.duration:g} s runs, mean over {len(grid.seeds)} PRBS seed(s)).")


def design_result(grid: DesignGrid, *, command: str | None = None, sweep: dict | None = None):
    """The D-optimality map as a :class:`shipid.result.Result` (method ``"ebm-design"``) for ``shipid report``.

    Yoon & Rhee (2003) §5.1.4, Fig. 7 (and Fig. 8 when ``sweep`` from :func:`current_sweep` is given).

    Parameters
    ----------
    grid : DesignGrid
        From :func:`prbs_grid`; the whole grid goes into ``series["contours"]["d_optimal"]``
        (sway = yaw regressors, the criterion the optimum is chosen on, paper "Fig. 7", the optimum
        marked) and ``contours["d_optimal_surge"]``, with the values in ``tables["d_optimal_grid"]``
        and ``tables["d_optimal_grid_surge"]``.
    command : str, optional
        The command line, stored in ``provenance["command"]``.
    sweep : dict, optional
        :func:`current_sweep` output at the optimum: ``xy["current_sweep"]`` (paper "Fig. 8").

    Returns
    -------
    shipid.result.Result
        ``estimates``: ``amplitude`` [deg], ``period`` [s] of the best grid point and its
        ``log10_det_sway``; their std is NaN — the optimum is only known to the grid spacing,
        which each note states.
    """

    a, per, val = grid.optimum("sway")
    a_s, per_s, val_s = grid.optimum("surge")
    comp = paper_comparison(grid)
    shape = f"{grid.amplitudes.size} × {grid.periods.size}"
    setting = (f"{shape} grid: amplitudes {_axis_text(grid.amplitudes)}°, periods {_axis_text(grid.periods)} s; "
               f"{grid.duration:g} s runs at dt = {grid.dt:g} s, mean over {len(grid.seeds)} "
               f"PRBS seed(s), current {grid.current_speed:.3g} m/s")
    common = dict(x_label="PRBS clock period", x_unit="s", y_label="PRBS amplitude", y_unit="deg")
    contours = {
        "d_optimal": contour(grid.periods, grid.amplitudes, grid.sway, **common,
                             z_label="log10 |WᵀW| (sway = yaw regressors)",
                             points=[{"x": per, "y": a, "label": f"optimum {a:g}° / {per:g} s"}], paper="Fig. 7",
                             title=f"D-optimality of the PRBS rudder input: log10 |WᵀW| of the sway (= yaw) "
                                   f"regressors over amplitude × clock period ({setting}); optimum {a:g}° / "
                                   f"{per:g} s on this grid (log10 |WᵀW| = {val:.2f}); {comp['text']}."),
        "d_optimal_surge": contour(grid.periods, grid.amplitudes, grid.surge, **common,
                                   z_label="log10 |WᵀW| (surge regressors)",
                                   points=[{"x": per_s, "y": a_s, "label": f"surge optimum {a_s:g}° / {per_s:g} s"}],
                                   title=f"log10 |WᵀW| of the surge regressors on the same grid ({setting})."),
    }
    series: dict = {"contours": contours,
                    "tables": {"d_optimal_grid": _grid_table(grid, grid.sway, "sway (= yaw)", "Fig. 7"),
                               "d_optimal_grid_surge": _grid_table(grid, grid.surge, "surge", None)}}
    if sweep is not None:
        series["xy"] = {"current_sweep": xy(sweep["speeds_knot"], {"surge": sweep["surge"], "sway": sweep["sway"]},
                                            x_label="current speed (towards 45°; negative: towards 225°)",
                                            x_unit="kn", y_label="log10 |WᵀW|", y_unit="-", paper="Fig. 8",
                                            title=f"D-optimality versus current speed at the optimum PRBS "
                                                  f"({a:g}° / {per:g} s), approach speed over ground fixed.")}
    res_note = "grid optimum; only known to the grid spacing (neighbours {})"
    estimates = {
        "amplitude": Estimate(a, unit="deg", status="derived",
                              note=res_note.format(_neighbours(grid.amplitudes, a) + " deg")),
        "period": Estimate(per, unit="s", status="derived",
                           note=res_note.format(_neighbours(grid.periods, per) + " s")),
        "log10_det_sway": Estimate(val, unit="-", status="derived",
                                   note="D-criterion at the optimum (≤ 0; 0 for orthogonal regressors)"),
    }
    warnings = []
    if per in (grid.periods.min(), grid.periods.max()) and grid.periods.size > 1:
        warnings.append(f"the optimum period {per:g} s lies on the edge of the grid: the criterion may peak outside it")
    if a == grid.amplitudes.min() and grid.amplitudes.size > 1:
        warnings.append(f"the optimum amplitude {a:g} deg lies on the lower edge of the grid")
    if not np.all(np.isfinite(grid.sway)):
        warnings.append("some grid points have a singular regressor matrix (log10 |WᵀW| = -inf)")
    # a grid evaluation: no iterative estimator, so no converged / iterations entries
    diagnostics = {"grid_shape": [int(grid.amplitudes.size), int(grid.periods.size)],
                   "evaluations": int(grid.amplitudes.size * grid.periods.size * len(grid.seeds)),
                   "criterion": "log10 |WᵀW| of the unit-length-scaled sway regressors (yaw identical)",
                   "optimum_surge": f"{a_s:g} deg / {per_s:g} s (log10 |WᵀW| = {val_s:.3f})",
                   "resolution": f"amplitudes {', '.join(f'{v:g}' for v in grid.amplitudes)} deg; periods "
                                 f"{', '.join(f'{v:g}' for v in grid.periods)} s",
                   "paper_fig7": comp,
                   "warnings": warnings}
    provenance = {"seed": int(grid.seeds[0]) if grid.seeds else None, "prbs_seeds": list(grid.seeds),
                  "command": command or "shipid.methods.ebm.design.design_result",
                  "settings": {"vessel": grid.vessel, "duration_s": grid.duration, "dt_s": grid.dt,
                               "current_speed_m_s": grid.current_speed,
                               "amplitudes_deg": grid.amplitudes.tolist(), "periods_s": grid.periods.tolist()},
                  "inputs": [{"name": f"simulated PRBS runs ({grid.vessel}, noise-free truth)",
                              "n_samples": int(round(grid.duration / grid.dt)) + 1, "duration_s": grid.duration,
                              "dt_s": grid.dt, "t0_s": 0.0, "channels": ["u_r", "v_r", "r", "delta", "n"],
                              "note": f"one run per grid point and seed: {shape} × {len(grid.seeds)}"}]}
    return Result(method="ebm-design", estimates=estimates,
                  model={"vessel": grid.vessel, "model": "modified Abkowitz (Yoon & Rhee 2003 eqs. 1-3)",
                         "input": "PRBS rudder"},
                  diagnostics=diagnostics, series=series, provenance=provenance)


__all__ = ["log_det_criterion", "prbs_criterion", "DesignGrid", "prbs_grid", "current_sweep", "design_result",
           "paper_comparison", "PAPER_FIG7", "DEFAULT_AMPLITUDES", "DEFAULT_PERIODS"]
