"""Standard measures of turning circles and zig-zags, from a Trial (recorded or simulated).

Definitions after the ITTC Recommended Procedure 7.5-04-02-01 (Full scale manoeuvring
trials) and IMO MSC.137(76):

* turning circle — *advance*: distance travelled along the approach course from
  the execute point until the heading has changed by 90°; *transfer*: the lateral
  distance at that moment; *tactical diameter*: the lateral distance when the
  heading has changed by 180°; *steady turning diameter*: ``2 U / |r|`` averaged
  over the steady part, taken as the second half of the record after execute and
  after 360° of heading change when the turn got that far.
* zig-zag — *overshoot angles*: after each rudder reversal, the largest heading
  excursion beyond the switching angle ψ before the next reversal; *initial
  turning time*: execute to first reversal.

The execute and reversal instants are taken from the commanded rudder
``delta_cmd`` (written by :func:`shipid.simulate.manoeuvres.run_manoeuvre`), or from
``delta`` when there is no command channel.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shipid.io.trial import Trial
from shipid.errors import InputError


def _rudder_events(trial: Trial) -> np.ndarray:
    name = "delta_cmd" if "delta_cmd" in trial else "delta"
    trial.require([name], method="manoeuvre metrics")
    return np.flatnonzero(np.diff(trial[name]) != 0) + 1


def _crossing_time(t: np.ndarray, y: np.ndarray, level: float) -> float | None:
    """First time ``y`` reaches ``level`` (linear interpolation between samples), or None."""
    above = np.flatnonzero(y >= level)
    if above.size == 0:
        return None
    k = int(above[0])
    if k == 0:
        return float(t[0])
    return float(t[k - 1] + (level - y[k - 1]) / (y[k] - y[k - 1]) * (t[k] - t[k - 1]))


@dataclass(frozen=True)
class TurningMetrics:
    """Turning-circle measures (m, rad/s); NaN where the record is too short."""

    advance: float
    transfer: float
    tactical_diameter: float
    steady_diameter: float
    steady_yaw_rate: float
    side: int


def turning_metrics(trial: Trial) -> TurningMetrics:
    """Advance, transfer, tactical and steady diameters of a turning-circle trial.

    Needs ``x, y, psi`` and ``delta_cmd`` (or ``delta``); the speed is ``U`` if
    present, else ``hypot(u, v)``.
    """
    trial.require(["x", "y", "psi", "r"], method="turning metrics")
    ev = _rudder_events(trial)
    if ev.size == 0:
        raise InputError("no rudder order found (constant rudder)", file=trial.meta.get("source"),
                         channel="delta_cmd" if "delta_cmd" in trial else "delta")
    k0 = int(ev[0])
    psi_all = np.unwrap(trial["psi"])          # tolerate models/recorders that wrap ψ
    t, psi = trial.t[k0:], psi_all[k0:] - psi_all[k0]
    side = 1 if psi[-1] >= 0 else -1
    c, s = np.cos(trial["psi"][k0]), np.sin(trial["psi"][k0])
    dx, dy = trial["x"][k0:] - trial["x"][k0], trial["y"][k0:] - trial["y"][k0]
    along, across = c * dx + s * dy, side * (-s * dx + c * dy)

    def at(level):
        tc = _crossing_time(t, side * psi, level)
        if tc is None:
            return np.nan, np.nan
        return float(np.interp(tc, t, along)), float(np.interp(tc, t, across))

    adv, trf = at(np.pi / 2)
    _, tac = at(np.pi)
    t360 = _crossing_time(t, side * psi, 2 * np.pi)
    steady = t >= max(t360 if t360 is not None else t[0], 0.5 * (t[0] + t[-1]))
    if "U" in trial:
        speed = trial["U"][k0:]
    else:
        speed = np.hypot(trial["u"][k0:], trial["v"][k0:] if "v" in trial else 0.0)
    r = trial["r"][k0:][steady]
    r_ss = float(np.mean(r))
    D = float(np.mean(2 * speed[steady] / np.abs(r))) if np.all(r != 0) else np.inf
    return TurningMetrics(advance=adv, transfer=trf, tactical_diameter=tac, steady_diameter=D,
                          steady_yaw_rate=r_ss, side=side)


@dataclass(frozen=True)
class ZigZagMetrics:
    """Zig-zag measures: overshoot angles (rad) and the times (s) of the reversals they follow."""

    overshoots: tuple[float, ...]
    reversal_times: tuple[float, ...]
    initial_turning_time: float
    switch_angle: float


def overshoot(psi_rel: np.ndarray, start: int, end: int, direction: float, switch_angle: float) -> float | None:
    """The overshoot rule: ``max(d (ψ − ψ₀)) − ψ_switch`` over the samples ``start .. end − 1``.

    ``psi_rel`` is the unwrapped heading minus its value at execute, ``start`` the sample of a
    reversal, ``end`` that of the next (or ``psi_rel.size``) and ``d = direction`` (±1) the sense
    of the heading change that triggered the reversal. None when the record ends while the heading
    still grows (the largest value is the last sample): that overshoot is not known.
    """
    seg = direction * psi_rel[start:end]
    j = int(np.argmax(seg))
    if end == psi_rel.size and j == seg.size - 1:
        return None                                # still turning when the record ends
    return float(seg[j] - switch_angle)


def heading_overshoots(t: np.ndarray, psi: np.ndarray, k_exec: int, psi_switch: float, side: int,
                       count: int = 2) -> list[float]:
    """Overshoot angles (rad) of a zig-zag from the heading alone (no rudder signal needed).

    ``ψ₀ = ψ(k_exec)``; the i-th reversal is where ``d_i (ψ − ψ₀)`` first reaches the switch angle
    (``d_1 = side``, alternating), and the i-th overshoot is :func:`overshoot` between that reversal
    and the next. Applied alike to measured and predicted headings, their overshoots are comparable
    whatever the noise of a measured rudder signal; at most ``count`` are returned.
    """
    p = np.unwrap(psi) - np.unwrap(psi)[k_exec]
    out, k, d = [], k_exec, side
    for _ in range(count):
        hit = np.flatnonzero(d * p[k:] >= psi_switch)
        if hit.size == 0:
            break
        k1 = k + int(hit[0])
        nxt = np.flatnonzero(-d * p[k1:] >= psi_switch)
        end = k1 + int(nxt[0]) if nxt.size else p.size
        o = overshoot(p, k1, end, d, psi_switch)
        if o is None:
            break
        out.append(o)
        k, d = k1, -d
    return out


def zigzag_metrics(trial: Trial, switch_angle: float) -> ZigZagMetrics:
    """Overshoot angles of a zig-zag with switching heading ``switch_angle`` (rad).

    The overshoot after reversal ``i`` is ``max(d_i (ψ − ψ_0)) − switch_angle`` over
    the samples from reversal ``i`` to reversal ``i+1`` (or the end), ``d_i`` the
    direction of the heading change that triggered reversal ``i``. The last
    overshoot is reported only if the heading turned back before the record ended
    (:func:`overshoot`).
    """
    trial.require(["psi"], method="zig-zag metrics")
    ev = _rudder_events(trial)
    if ev.size < 2:
        raise InputError("fewer than one rudder reversal after execute",
                         file=trial.meta.get("source"), channel="delta_cmd")
    psi_all = np.unwrap(trial["psi"])
    psi = psi_all - psi_all[ev[0]]
    over, times = [], []
    for i, k in enumerate(ev[1:]):
        d = 1.0 if psi[k] > 0 else -1.0
        end = int(ev[i + 2]) if i + 2 < ev.size else psi.size
        o = overshoot(psi, k, end, d, switch_angle)
        if o is None:
            break
        over.append(o)
        times.append(float(trial.t[k]))
    return ZigZagMetrics(overshoots=tuple(over), reversal_times=tuple(times),
                         initial_turning_time=float(trial.t[ev[1]] - trial.t[ev[0]]),
                         switch_angle=float(switch_angle))


__all__ = ["TurningMetrics", "ZigZagMetrics", "turning_metrics", "zigzag_metrics", "overshoot",
           "heading_overshoots"]
