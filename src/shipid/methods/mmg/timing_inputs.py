"""Time offsets of the input channels (rudder angle, propeller rate, relative wind) against the position clock.

After :func:`shipid.methods.mmg.timing.retime` the heading, body velocities and yaw rate of a
run are on the position's clock; the inputs are not moved. If the rudder angle is logged
``τ_δ`` late, every predicted yaw response starts ``τ_δ`` early relative to the measured one
(and the other way round); the same for the propeller rate in surge and for the wind.

Estimate (:func:`estimate_input_lags`, training runs only, after the state re-timing): over a
grid of lags, least squares of the yaw acceleration ``ṙ`` (derivative of the re-timed yaw rate,
all columns smoothed by the centred moving average of :mod:`shipid.methods.mmg.timing`, which
delays nothing) on a per-run constant, ``u r``, ``u v``, ``|r| r``, ``|v| v`` and the lagged rudder
``δ(t + τ_δ)`` times ``u²``, ``u n`` and ``n²`` (the rudder normal force of the MMG model,
Yasukawa & Yoshimura 2015 eq. 27–31, in the rudder-inflow speed expanded in ``u`` and ``n``);
``τ_δ`` minimises the pooled residual sum of squares. The propeller rate ``τ_n`` likewise from
the surge acceleration ``u̇`` on a per-run constant, ``u|u|``, ``v r``, ``δ² u²`` and the lagged
``n²``, ``u n`` (thrust, eq. 34–36); the relative wind ``τ_w`` from the yaw equation with the
rudder at ``τ_δ`` and the air moment columns ``V_A² sin γ_A``, ``V_A² sin 2γ_A`` (Fujiwara et al.
1998) lagged. How well determined: the per-run argmin of each lag, its median and the standard
error ``sd / √runs`` across runs, reported with the pooled estimate.
:func:`with_inputs` puts the offsets into a :class:`~shipid.methods.mmg.timing.Lags`, and
:func:`shipid.methods.mmg.timing.retime` then advances the input channels too, ``δ'(t) = δ(t + τ_δ)``
(one repair line for state and inputs); :func:`at_bound` names an offset on the end of the grid
(not determined within it).

The training-run CV that adopted the input offsets, its decision rule and the grid are recorded in
``docs/validation/mmg.md`` (re-timing of the Esso logs).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Sequence

import numpy as np

from shipid.io.trial import Trial
from shipid.methods.mmg.timing import SMOOTH, Lags

#: Default grid of input offsets (s): −1 … 3 s, wide enough for the wind offset of the Esso logs (1.8 s).
GRID = np.round(np.arange(-1.0, 3.001, 0.1), 10)
#: Samples kept clear of each end of a run at least (filter edges); :func:`_edge` adds the largest grid offset.
_EDGE = 2 * SMOOTH + 16


def _edge(d: dict, grid: np.ndarray) -> int:
    """Samples of run ``d`` kept clear of each end: the filter edges, and at least the largest offset of
    ``grid`` plus half the smoothing window (a shifted column is held constant past the run's end)."""
    dt = float(np.median(np.diff(d["t"])))
    return max(_EDGE, int(np.ceil(float(np.max(np.abs(grid))) / dt)) + SMOOTH // 2 + 1)


@dataclass(frozen=True)
class InputLags:
    """Offsets (s) by which the rudder angle, propeller rate and wind lag the position clock.

    ``*_median`` / ``*_se``: median and standard error (``sd / √runs``) of the per-run argmins;
    ``runs``: runs used; ``wind`` is 0 when no run has the relative wind channels."""

    delta: float
    n: float
    wind: float
    delta_median: float = 0.0
    delta_se: float = 0.0
    n_median: float = 0.0
    n_se: float = 0.0
    wind_median: float = 0.0
    wind_se: float = 0.0
    runs: int = 0

    def to_dict(self) -> dict[str, float]:
        return dict(self.__dict__)

    @property
    def zero(self) -> bool:
        return self.delta == 0.0 and self.n == 0.0 and self.wind == 0.0


def _smooth(a: np.ndarray) -> np.ndarray:
    return np.convolve(a, np.ones(SMOOTH) / SMOOTH, mode="same")


def _run_arrays(tr: Trial) -> dict[str, np.ndarray] | None:
    names = ["u", "v", "r", "n", "delta"]
    wind = all(c in tr for c in ("wind_speed_rel", "wind_dir_rel"))
    cols = names + (["wind_speed_rel", "wind_dir_rel"] if wind else [])
    t = np.asarray(tr.t, float)
    Z = np.stack([np.asarray(tr[c], float) for c in cols], axis=1)
    ok = np.all(np.isfinite(Z), axis=1)
    if ok.sum() < 2 * _EDGE + 6 * SMOOTH:
        return None
    out = {"t": t[ok]}
    out.update({c: Z[ok, i] for i, c in enumerate(cols)})
    if wind:
        g = np.unwrap(out.pop("wind_dir_rel"))
        va = out.pop("wind_speed_rel")
        out["wx"], out["wy"] = va * np.cos(g), va * np.sin(g)
    return out


def _shift(d: dict, name: str, tau: float) -> np.ndarray:
    return d[name] if tau == 0.0 else np.interp(d["t"] + tau, d["t"], d[name])


def _wind_cols(d: dict, tau: float) -> list[np.ndarray]:
    wx, wy = _shift(d, "wx", tau), _shift(d, "wy", tau)
    va2, g = wx * wx + wy * wy, np.arctan2(wy, wx)
    return [va2 * np.sin(g), va2 * np.sin(2 * g)]


def _yaw_design(d: dict, tau_d: float, tau_w: float | None):
    u, v, r, n = d["u"], d["v"], d["r"], d["n"]
    dl = _shift(d, "delta", tau_d)
    cols = [u * r, u * v, np.abs(r) * r, np.abs(v) * v, dl * u * u, dl * u * n, dl * n * n]
    if tau_w is not None and "wx" in d:
        cols += _wind_cols(d, tau_w)
    return np.gradient(_smooth(r), d["t"]), cols


def _surge_design(d: dict, tau_n: float):
    u, v, r, dl = d["u"], d["v"], d["r"], d["delta"]
    nn = _shift(d, "n", tau_n)
    cols = [u * np.abs(u), v * r, dl * dl * u * u, nn * nn, u * nn]
    return np.gradient(_smooth(u), d["t"]), cols


def _block(y: np.ndarray, cols: list[np.ndarray], edge: int = _EDGE) -> tuple[np.ndarray, np.ndarray]:
    """Smoothed, interior (``edge`` samples off each end), de-meaned (a per-run constant) response and design."""
    m = slice(edge, -edge)
    X = np.stack([_smooth(c)[m] for c in cols], axis=1)
    y = y[m]
    return y - y.mean(), X - X.mean(axis=0)


def _sse(blocks: list[tuple[np.ndarray, np.ndarray]]) -> float:
    y = np.concatenate([b[0] for b in blocks])
    X = np.concatenate([b[1] for b in blocks])
    s = np.linalg.norm(X, axis=0)
    s[s == 0] = 1.0
    beta = np.linalg.lstsq(X / s, y, rcond=None)[0]
    e = y - (X / s) @ beta
    return float(e @ e)


def _profile(data: list[dict], design, grid: np.ndarray) -> tuple[float, float, float]:
    """Pooled argmin over ``grid``; median and SE of the per-run argmins."""
    edges = [_edge(d, grid) for d in data]
    keep = [i for i, (d, e) in enumerate(zip(data, edges)) if d["t"].size >= 2 * e + 6 * SMOOTH]
    data, edges = [data[i] for i in keep], [edges[i] for i in keep]
    blocks = [[_block(*design(d, tau), e) for tau in grid] for d, e in zip(data, edges)]   # run × offset
    per = np.array([[_sse([b]) for b in row] for row in blocks])
    per_pooled = [_sse([row[j] for row in blocks]) for j in range(len(grid))]
    pooled = float(grid[int(np.argmin(per_pooled))])
    run_min = grid[np.argmin(per, axis=1)]
    se = float(np.std(run_min, ddof=1) / np.sqrt(run_min.size)) if run_min.size > 1 else float("inf")
    return pooled, float(np.median(run_min)), se


def estimate_input_lags(trials: Sequence[Trial], grid: np.ndarray | None = None, *,
                        wind: bool = True) -> InputLags:
    """Least-squares input offsets over ``trials`` (state channels already re-timed; module docstring)."""
    grid = GRID if grid is None else np.asarray(grid, float)
    data = [d for d in (_run_arrays(tr) for tr in trials) if d is not None]
    td, tdm, tds = _profile(data, lambda d, tau: _yaw_design(d, tau, 0.0), grid)
    tn, tnm, tns = _profile(data, _surge_design, grid)
    wdata = [d for d in data if "wx" in d]
    tw = twm = tws = 0.0
    if wind and wdata:
        tw, twm, tws = _profile(wdata, lambda d, tau: _yaw_design(d, td, tau), grid)
    return InputLags(delta=td, n=tn, wind=tw, delta_median=tdm, delta_se=tds, n_median=tnm, n_se=tns,
                     wind_median=twm, wind_se=tws, runs=len(data))


def with_inputs(lags: Lags, inputs: InputLags) -> Lags:
    """``lags`` (state offsets) with the input offsets of ``inputs``, for :func:`shipid.methods.mmg.timing.retime`."""
    return replace(lags, delta=inputs.delta, n=inputs.n, wind=inputs.wind)


def at_bound(inputs: InputLags, grid: np.ndarray | None = None) -> list[str]:
    """The input offsets that sit on an end of ``grid`` (not determined within it)."""
    grid = GRID if grid is None else np.asarray(grid, float)
    lo, hi = float(grid[0]), float(grid[-1])
    names = {"delta": "rudder angle", "n": "propeller rate", "wind": "wind"}
    return [names[k] for k in names if getattr(inputs, k) in (lo, hi)]


__all__ = ["GRID", "InputLags", "estimate_input_lags", "with_inputs", "at_bound"]
