"""Time offsets between the position and the heading / velocity channels of a run, and re-timing.

The earth-fixed velocity has two measurements in the Esso Osaka runs: the time derivative of
the position ``(ẋ₀, ẏ₀)`` and the body velocities rotated by the heading,
``(u cos ψ − v sin ψ, u sin ψ + v cos ψ)``. If the heading lags the position by ``τ_ψ``, the
second is rotated by ``−r τ_ψ``; its sway part differs from the position's by ``−U r τ_ψ``,
growing with the speed, where a lever arm ``a`` (a velocity reference point off midship) gives
``a r`` at any speed. On the 32 training runs of the 9-run split the per-run slope of
``v − v_pos`` on ``r`` grows from −0.03 m in the slowest runs to −0.32 m in the fastest
zig-zags, and pooled ``v − v_pos = −0.027 r − 0.68 U r`` (m/s): a time offset, not a lever arm.

:func:`estimate_lags` finds the offsets by least squares over a grid: the heading ``τ_ψ`` and
the body velocities ``τ_uv`` that make the two earth-fixed velocities agree best (both smoothed
by the same centred moving average, which delays neither), then the yaw rate ``τ_r`` that makes
``r`` agree with the derivative of the re-timed heading. :func:`retime` moves the channels onto
the position's clock, ``ψ'(t) = ψ(t + τ_ψ)`` (and so on), drops the last ``max τ`` seconds that
would need extrapolation and records the change as one repair line in ``meta["repairs"]``.
With input offsets (``Lags.delta``, ``Lags.n``, ``Lags.wind``, estimated by
:func:`shipid.methods.mmg.timing_inputs.estimate_input_lags` on the state-re-timed runs) it moves
the rudder angle, propeller rate and wind channels onto the same clock, ``δ'(t) = δ(t + τ_δ)``,
drops the samples that would need extrapolation at either end and names the input offsets in the
same repair line; with them zero (the default) the inputs are not moved and the result is that of
the state re-timing alone. The position channels are never moved.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from shipid.io.trial import Trial

#: Width (samples) of the centred moving average applied to both velocity estimates.
SMOOTH = 11


@dataclass(frozen=True)
class Lags:
    """Offsets (s) by which each channel lags the position: heading, body velocities, yaw rate;
    ``mismatch`` the RMS earth-velocity disagreement (m/s) before and after re-timing; ``delta``,
    ``n``, ``wind``: the input offsets (rudder angle, propeller rate, wind; 0 = not moved)."""

    psi: float
    uv: float
    r: float
    mismatch_before: float
    mismatch_after: float
    runs: int
    delta: float = 0.0
    n: float = 0.0
    wind: float = 0.0

    def to_dict(self) -> dict[str, float]:
        return {"psi": self.psi, "uv": self.uv, "r": self.r, "mismatch_before": self.mismatch_before,
                "mismatch_after": self.mismatch_after, "runs": self.runs, "delta": self.delta, "n": self.n,
                "wind": self.wind}


def _smooth(a: np.ndarray) -> np.ndarray:
    k = np.ones(SMOOTH) / SMOOTH
    return np.convolve(a, k, mode="same")


def _arrays(tr: Trial):
    t = np.asarray(tr.t, float)
    Z = np.stack([np.asarray(tr[c], float) for c in ("x", "y", "psi", "u", "v", "r")], axis=1)
    ok = np.all(np.isfinite(Z), axis=1)
    return t[ok], Z[ok]


def _advance(t: np.ndarray, a: np.ndarray, tau: float) -> np.ndarray:
    return np.interp(t + tau, t, a)


def _velocity_sse(t, Z, tau_psi, tau_uv) -> tuple[float, int]:
    x, y, psi, u, v = Z[:, 0], Z[:, 1], np.unwrap(Z[:, 2]), Z[:, 3], Z[:, 4]
    ps, uu, vv = _advance(t, psi, tau_psi), _advance(t, u, tau_uv), _advance(t, v, tau_uv)
    ex = _smooth(np.gradient(x, t) - (uu * np.cos(ps) - vv * np.sin(ps)))
    ey = _smooth(np.gradient(y, t) - (uu * np.sin(ps) + vv * np.cos(ps)))
    m = slice(2 * SMOOTH, -2 * SMOOTH)               # away from the ends (filter edges, extrapolation)
    return float(np.sum(ex[m] ** 2 + ey[m] ** 2)), int(ex[m].size)


def _rate_sse(t, Z, tau_psi, tau_r) -> float:
    ps = _advance(t, np.unwrap(Z[:, 2]), tau_psi)
    e = _smooth(np.gradient(ps, t) - _advance(t, Z[:, 5], tau_r))
    m = slice(2 * SMOOTH, -2 * SMOOTH)
    return float(np.sum(e[m] ** 2))


def estimate_lags(trials: Sequence[Trial], grid: np.ndarray | None = None) -> Lags:
    """Least-squares channel offsets over ``trials`` (module docstring); ``grid`` of offsets in s
    (default −0.5 … 1.5 s in 0.1-s steps)."""
    grid = np.round(np.arange(-0.5, 1.501, 0.1), 10) if grid is None else np.asarray(grid, float)
    data = [_arrays(tr) for tr in trials]
    data = [(t, Z) for t, Z in data if t.size > 6 * SMOOTH]

    def vel(a, b):
        s = [_velocity_sse(t, Z, a, b) for t, Z in data]
        return sum(q[0] for q in s) / max(sum(q[1] for q in s), 1)

    table = np.array([[vel(a, b) for b in grid] for a in grid])
    i, j = np.unravel_index(int(np.argmin(table)), table.shape)
    tau_psi, tau_uv = float(grid[i]), float(grid[j])
    rate = [sum(_rate_sse(t, Z, tau_psi, c) for t, Z in data) for c in grid]
    tau_r = float(grid[int(np.argmin(rate))])
    return Lags(psi=tau_psi, uv=tau_uv, r=tau_r, mismatch_before=float(np.sqrt(vel(0.0, 0.0))),
                mismatch_after=float(np.sqrt(table[i, j])), runs=len(data))


#: Input channels moved by each input offset of :class:`Lags`, and the channels that are angles.
INPUT_CHANNELS = {"delta": ("delta",), "n": ("n",),
                  "wind": ("wind_speed_rel", "wind_dir_rel", "wind_speed", "wind_dir")}
_ANGLES = ("psi", "wind_dir_rel", "wind_dir")


def retime(trial: Trial, lags: Lags) -> Trial:
    """``trial`` with ψ, u, v, r (and the inputs, where ``lags`` has input offsets) moved onto the
    position clock by ``lags`` (module docstring)."""
    t = np.asarray(trial.t, float)
    moves = [("psi", lags.psi), ("u", lags.uv), ("v", lags.uv), ("r", lags.r)]
    inputs = (lags.delta, lags.n, lags.wind)
    for key, tau in zip(("delta", "n", "wind"), inputs):
        moves += [(name, tau) for name in INPUT_CHANNELS[key] if tau != 0.0 and name in trial]
    new = {}
    for name, tau in moves:
        a = np.asarray(trial[name], float)
        ok = np.isfinite(a)
        src = np.unwrap(a[ok]) if name in _ANGLES else a[ok]
        b = np.interp(t + tau, t[ok], src)
        new[name] = np.angle(np.exp(1j * b)) if name in _ANGLES else b
    out = trial.with_channels(**new)
    end = t[-1] - max(lags.psi, lags.uv, lags.r, *inputs, 0.0)
    start = t[0] - min(*inputs, 0.0)
    out = out.slice_time(None if start == t[0] else start - 1e-9, end + 1e-9)
    meta = dict(out.meta)
    text = (f"heading, body velocities and yaw rate re-timed onto the position clock (advanced by "
            f"{lags.psi:.2f} s, {lags.uv:.2f} s and {lags.r:.2f} s, offsets estimated on the training runs); "
            f"last {t[-1] - end:.2f} s dropped")
    if any(inputs):
        text = (f"heading, body velocities and yaw rate (advanced by {lags.psi:.2f} s, {lags.uv:.2f} s and "
                f"{lags.r:.2f} s) and rudder angle, propeller rate and wind (advanced by {lags.delta:.2f} s, "
                f"{lags.n:.2f} s and {lags.wind:.2f} s) re-timed onto the position clock, offsets estimated on "
                f"the training runs; first {start - t[0]:.2f} s and last {t[-1] - end:.2f} s dropped")
    meta["repairs"] = list(meta.get("repairs", []) or []) + [{"kind": "retimed", "text": text}]
    return Trial(out.t, out.channels, out.units, meta)


__all__ = ["SMOOTH", "INPUT_CHANNELS", "Lags", "estimate_lags", "retime"]
