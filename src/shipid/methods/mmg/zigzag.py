"""Zig-zag tests of the KVLCC2 HSVA study: overshoot angles, the tank autopilot, closed-loop prediction.

Kempf's zig-zag manoeuvre (the rudder reversed to ±δ_z whenever the heading passes
±ψ_switch from its value at execute): the overshoot angles read from a heading record
(:func:`overshoots`, which is :func:`shipid.simulate.metrics.heading_overshoots`), the
tank autopilot's reaction delay and steering gear measured from the training runs' rudder
records (:func:`reversal_delays`, :func:`steering_gear`, :func:`kvlcc2_autopilot`), and
the closed-loop simulation of an MMG model with that autopilot from the measured state at
execute (:func:`simulate_zigzag`). The reasons for each choice are in
:mod:`shipid.methods.mmg.study`.
"""

from __future__ import annotations

import re
from typing import Sequence

import numpy as np

from shipid.io.trial import Trial
from shipid.errors import InputError
from shipid.methods.mmg import validate as V
from shipid.models import mmg
from shipid.simulate.metrics import heading_overshoots as overshoots  # the one overshoot rule


def zigzag_angles(name: str) -> tuple[float, float]:
    """(rudder, switch heading) in rad from an HSVA file name ``..._Z_20_10_P.dat``."""
    m = re.search(r"_Z_(\d+)_(\d+)", name)
    if not m:
        raise InputError(f"cannot read the zig-zag angles from '{name}'")
    return np.deg2rad(float(m.group(1))), np.deg2rad(float(m.group(2)))


def execute_index(delta: np.ndarray, threshold: float = np.deg2rad(1.0)) -> int:
    """First sample where the rudder has moved more than ``threshold`` from its initial value."""
    k = np.flatnonzero(np.abs(delta - delta[0]) > threshold)
    if k.size == 0:
        raise InputError("no rudder execute found")
    return max(int(k[0]) - 1, 0)


def reversal_delays(tr: Trial, psi_switch: float, threshold: float = np.deg2rad(0.5)) -> list[float]:
    """Delays (s) between each measured heading crossing of ±ψ_switch and the rudder starting to reverse.

    The tank's autopilot does not reverse the rudder at the very sample the heading
    passes the switch angle: on the HSVA runs it starts 0.3–0.7 s later. The start is
    the first sample after the crossing where the rudder has left its value at the
    crossing by ``threshold`` towards the other side.
    """
    k0 = execute_index(tr["delta"])
    p = np.unwrap(tr["psi"]) - np.unwrap(tr["psi"])[k0]
    d = tr["delta"]
    side = 1 if np.mean(d[k0:k0 + int(round(5 / tr.dt))]) > 0 else -1
    out, k, s = [], k0, side
    while True:
        hit = np.flatnonzero(s * p[k:] >= psi_switch)
        if hit.size == 0:
            break
        k1 = k + int(hit[0])
        mv = np.flatnonzero(s * (d[k1:] - d[k1]) < -threshold)
        if mv.size == 0:
            break
        out.append(float(tr.t[k1 + int(mv[0])] - tr.t[k1]))
        k, s = k1, -s
    return out


def simulate_zigzag(model: mmg.MmgModel, tr: Trial, delta_z: float, psi_switch: float, *,
                    rate: float, delay: float = 0.0, accel: float = np.inf,
                    duration: float | None = None) -> np.ndarray:
    """Closed-loop zig-zag of ``model`` from the measured state at execute; heading history (n,).

    The rudder moves towards ``±delta_z`` with the rate limited to ``rate`` (rad/s) and
    the rate's change to ``accel`` (rad/s², :func:`steering_gear`; ``inf``: rate limit
    only), and reverses ``delay``
    seconds after the *predicted* heading passes ``±psi_switch`` from ψ at execute
    (Kempf's rule with the tank autopilot's reaction time); propeller revolutions are
    the measured ones.
    """
    Z = V.measured_states(tr)
    Uin = V.trial_inputs(tr)
    k0 = execute_index(tr["delta"])
    t = tr.t[k0:] if duration is None else tr.t[k0:k0 + int(round(duration / tr.dt))]
    dt = float(np.median(np.diff(t)))
    x = Z[k0][None].copy()
    psi0 = x[0, 2]
    side = 1 if np.mean(tr["delta"][k0:k0 + int(5 / dt)]) > 0 else -1   # MMG: δ > 0 turns to starboard
    d = side
    delta = float(tr["delta"][k0])
    out = np.full(t.size, np.nan)
    out[0] = x[0, 2]
    switches = 0
    w = 0.0                            # rudder rate
    pending: float | None = None       # time at which an ordered reversal takes effect
    cmd = d
    for k in range(t.size - 1):
        tk = t[k] - t[0]
        if pending is None and d * (x[0, 2] - psi0) >= psi_switch:
            d = -d
            switches += 1
            pending = tk + delay
            if switches > 3:          # the second overshoot ends at the third reversal
                return out[:k + 1]
        if pending is not None and tk >= pending - 1e-9:
            cmd, pending = d, None
        target = cmd * delta_z
        if np.isfinite(accel):
            err = target - delta
            w_des = np.sign(err) * min(rate, np.sqrt(2.0 * accel * abs(err)))   # brake to stop at the target
            w += np.clip(w_des - w, -accel * dt, accel * dt)
            if abs(err) <= abs(w) * dt and abs(w_des) <= accel * dt:
                delta, w = target, 0.0
            else:
                delta += w * dt
        else:
            delta += np.clip(target - delta, -rate * dt, rate * dt)
        u = np.array([[delta, Uin[k0 + k, 1], 0.0, 0.0]])
        x = mmg.simulate_batch(model, np.array([0.0, dt]), x, u[:, None, :].repeat(2, axis=1))[:, -1]
        out[k + 1] = x[0, 2]
    return out


def rudder_rate(tr: Trial) -> float:
    """Rudder rate of the run (rad/s): 95th percentile of |dδ/dt| over samples where the rudder moves."""
    dd = np.abs(np.diff(tr["delta"])) / np.diff(tr.t)
    moving = dd[dd > np.deg2rad(1.0)]
    return float(np.percentile(moving, 95)) if moving.size else float(np.deg2rad(15.0))


def reversal_times(tr: Trial, delta_z: float, tol: float = np.deg2rad(0.5)) -> list[tuple[float, float]]:
    """``(delta_z, duration)`` of each measured rudder reversal: from the last sample within ``tol``
    of one side (±``delta_z``) to the first within ``tol`` of the other (rad, s)."""
    d = tr["delta"]
    side = np.where(d > delta_z - tol, 1, np.where(d < -delta_z + tol, -1, 0))
    k = np.flatnonzero(side != 0)
    return [(float(delta_z), float(tr.t[b] - tr.t[a])) for a, b in zip(k[:-1], k[1:]) if side[a] != side[b]]


def steering_gear(trials: Sequence[Trial], names: Sequence[str],
                  tol: float = np.deg2rad(0.5)) -> tuple[float, float]:
    """Rudder rate limit (rad/s) and rate-change limit (rad/s²) from the measured reversals.

    A trapezoidal rudder motion (accelerate at ``a``, run at ``r``, brake at ``a``)
    swings ``2 δ_z`` in ``2 δ_z / r + r / a``; between the ``tol`` thresholds of
    :func:`reversal_times` that is ``2 δ_z / r + r / a − 2 √(2 tol / a)``. ``(r, a)``
    are the least-squares fit of that time to every reversal of the given runs. On
    the HSVA runs the effective rate grows with the swing (about 10.6°/s for ±5°,
    14.7°/s for ±30°), which a pure rate limit cannot reproduce. Falls back to the
    95th-percentile rate and no acceleration limit with fewer than two rudder angles.
    """
    from scipy.optimize import least_squares

    st = [x for f, tr in zip(names, trials) for x in reversal_times(tr, zigzag_angles(f)[0], tol)]
    fallback = (float(np.median([rudder_rate(tr) for tr in trials])), float("inf"))
    if len({round(dz, 6) for dz, _ in st}) < 2:
        return fallback
    dz = np.array([x[0] for x in st])
    T = np.array([x[1] for x in st])

    def res(p):
        r, a = np.exp(p)
        return 2 * dz / r + r / a - 2 * np.sqrt(2 * tol / a) - T

    sol = least_squares(res, np.log([np.deg2rad(15.0), np.deg2rad(50.0)]))
    if not sol.success:
        return fallback
    r, a = np.exp(sol.x)
    return float(r), float(a)


def kvlcc2_autopilot(trials: Sequence[Trial], names: Sequence[str]) -> dict[str, float]:
    """Tank autopilot from the given (training) runs.

    ``rate`` (rad/s) and ``accel`` (rad/s²) of the steering gear (:func:`steering_gear`);
    ``delay`` (s): the command delay after the heading crosses ±ψ_switch — the median
    measured delay until the rudder has moved 0.5° (:func:`reversal_delays`) less the
    time the modelled gear takes to move those 0.5° from rest (``√(2·0.5°/a)``).
    """
    thr = np.deg2rad(0.5)
    delays = [dl for f, tr in zip(names, trials) for dl in reversal_delays(tr, zigzag_angles(f)[1], thr)]
    rate, accel = steering_gear(trials, names)
    start = np.sqrt(2 * thr / accel) if np.isfinite(accel) else thr / rate
    measured = float(np.median(delays)) if delays else 0.0
    return {"delay": max(0.0, measured - float(start)), "measured_delay": measured, "rate": rate, "accel": accel}


def first_side(tr: Trial, k0: int) -> int:
    return 1 if np.mean(tr["delta"][k0:k0 + int(round(5.0 / tr.dt))]) > 0 else -1


__all__ = ["zigzag_angles", "execute_index", "overshoots", "reversal_delays", "simulate_zigzag",
           "rudder_rate", "reversal_times", "steering_gear", "kvlcc2_autopilot", "first_side"]
