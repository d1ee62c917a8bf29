"""Measured sea trials of a vessel whose file states its trial conditions (``[trials]``).

Yoon & Rhee (2003) §5.1 define how ESSO OSAKA's trials are measured: a current (2 kn setting towards
45°, eq. 2), the sensor positions of eq. 8 (DGPS antenna, speed log) and the noise of eq. 19, sampled
every ``dt``. A vessel file carries these in its ``[trials]`` section; :func:`simulate_measured`
simulates a manoeuvre under them and records what the sensors read:

* ``x, y``: DGPS antenna position, earth-fixed (σ_xy);
* ``x_dot, y_dot``: DGPS antenna earth-fixed velocity (σ_xy_dot);
* ``psi``: gyro heading (σ_psi);
* ``U``: speed log ``u_r − y_S r`` (σ_u_log);
* ``delta``, ``n``: rudder angle and propeller rate, noise-free (known inputs).

The noise-free truth is kept in channels prefixed ``true_`` (``true_u_r``, ``true_v_r``, ``true_r``,
``true_X``, ``true_Y``, ``true_N``, ``true_x``, ``true_y``, ``true_psi``) so that an estimator's
first step can be checked; the estimators never read them.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from shipid.io.trial import Trial
from shipid.models import abkowitz as ab
from shipid.simulate.manoeuvres import run_manoeuvre
from shipid.vessels import load_vessel

TRUE_UNITS = {"true_u_r": "m/s", "true_v_r": "m/s", "true_r": "rad/s", "true_X": "N", "true_Y": "N",
              "true_N": "N*m", "true_x": "m", "true_y": "m", "true_psi": "rad"}
#: Simulation steps per recorded sample (the rudder moves in small zero-order-hold steps).
OVERSAMPLE = 5


def has_trial_conditions(vessel: str) -> bool:
    """Whether a packaged vessel's file states measured-trial conditions (a ``[trials]`` section of an
    Abkowitz ship, :func:`shipid.models.abkowitz.trial_conditions`)."""
    try:
        v = load_vessel(vessel)
    except Exception:  # noqa: BLE001 - an unknown name is reported by the simulator that follows
        return False
    return "trials" in v.sections and "abkowitz" in v.sections


def add_measurements(truth: Trial, conds: dict, seed: int, *, noise: bool = True) -> Trial:
    """Turn a noise-free simulated trial into the measured record of eq. 8 + eq. 19 (Yoon & Rhee 2003)."""
    rng = np.random.default_rng(seed)
    t = truth.t
    psi = truth["psi"]
    ur, r = truth["u_r"], truth["r"]
    c, s = np.cos(psi), np.sin(psi)
    xD, yD, yS = conds["x_D"], conds["y_D"], conds["y_S"]
    ex = np.asarray(truth["x_dot"]) - r * (xD * s + yD * c)
    ey = np.asarray(truth["y_dot"]) + r * (xD * c - yD * s)
    meas = {
        "x": truth["x"] + xD * c - yD * s,
        "y": truth["y"] + xD * s + yD * c,
        "x_dot": ex,
        "y_dot": ey,
        "psi": psi.copy(),
        "U": ur - yS * r,
    }
    if noise:
        sig = {"x": conds["sigma_xy"], "y": conds["sigma_xy"], "x_dot": conds["sigma_xy_dot"],
               "y_dot": conds["sigma_xy_dot"], "psi": conds["sigma_psi"], "U": conds["sigma_u_log"]}
        for k in ("x", "y", "x_dot", "y_dot", "psi", "U"):
            meas[k] = meas[k] + rng.normal(0.0, sig[k], t.size)
    ch = dict(meas)
    ch["delta"] = truth["delta"]
    ch["n"] = truth["n"]
    units = {"x": "m", "y": "m", "x_dot": "m/s", "y_dot": "m/s", "psi": "rad", "U": "m/s",
             "delta": "rad", "n": "1/s"}
    for k, src in (("true_u_r", "u_r"), ("true_v_r", "v_r"), ("true_r", "r"), ("true_X", "X"),
                   ("true_Y", "Y"), ("true_N", "N"), ("true_x", "x"), ("true_y", "y"),
                   ("true_psi", "psi")):
        ch[k] = truth[src]
        units[k] = TRUE_UNITS[k]
    meta = dict(truth.meta)
    meta.update({"measurement_seed": int(seed), "x_D": xD, "y_D": yD, "y_S": yS,
                 "noise": "yr2003 eq. 19" if noise else "none"})
    return Trial(t, ch, units, meta)


def simulate_measured(manoeuvre: str, duration: float, *, seed: int = 0, dt: float | None = None,
                      current: tuple[float, float] | None = None, theta: ab.AbkowitzParams | None = None,
                      noise: bool = True, vessel: str = "esso-osaka", oversample: int = OVERSAMPLE,
                      speed: float | None = None, noise_scale: float = 1.0, progress=None) -> Trial:
    """One measured trial of ``vessel`` under its ``[trials]`` conditions (module docstring).

    Parameters
    ----------
    manoeuvre : str
        A :func:`shipid.simulate.manoeuvres.run_manoeuvre` name (``"turning-35"``, ``"zigzag-20"``,
        ``"prbs-35-105"`` ...).
    duration : float
        Seconds.
    seed : int
        Seeds the PRBS register and (``seed + 1000``) the measurement noise.
    dt : float, optional
        Sample interval (default the vessel file's ``[trials].dt``).
    current : (speed m/s, direction rad), optional
        Default the vessel file's current.
    theta : AbkowitzParams, optional
        Coefficients to simulate with (default the vessel's); the approach propeller rate is
        ``theta.n0`` (scaled with ``speed / theta.U0``).
    noise : bool
        Add the measurement noise of the vessel file (eq. 19 for ESSO OSAKA).
    oversample : int
        The ship is simulated with a step ``dt / oversample`` (the rudder moves in correspondingly small
        zero-order-hold steps, close to a continuous steering gear) and recorded every ``oversample``
        steps; with 1 the rudder jumps at each sample and the recorded force leads the force the ship
        felt by half a sample, which biases a force regression.
    speed : float, optional
        Approach speed through the water (m/s), default the vessel's U0.
    noise_scale : float
        Multiplies every noise standard deviation (an estimator is not told).
    """
    conds = ab.trial_conditions(vessel)
    dt = conds["dt"] if dt is None else float(dt)
    if current is None:
        current = (conds["current_speed"], conds["current_dir"])
    model = ab.ship_model(vessel, current_speed=current[0], current_dir=current[1])
    if theta is not None:
        th = theta.with_current(*current)
        # the approach propeller rate is theta's (it balances theta's resistance at theta.U0)
        model = replace(model, theta=th, f=ab.make_dynamics(th),
                        outputs=lambda t, X, U, _p=th: ab.outputs(t, X, U, _p),
                        u0=lambda s, _p=th: np.array([0.0, _p.n0 * float(s) / _p.U0]))
    ov = max(1, int(oversample))
    fine = run_manoeuvre(model, manoeuvre, duration=duration, dt=dt / ov, seed=seed, speed=speed,
                         progress=progress)
    if ov > 1:
        keep = np.arange(0, fine.t.size, ov)
        truth = Trial(fine.t[keep], {k: v[keep] for k, v in fine.channels.items()}, fine.units,
                      dict(fine.meta, dt=dt, oversample=ov))
    else:
        truth = fine
    mconds = dict(conds)
    for k in ("sigma_xy", "sigma_xy_dot", "sigma_psi", "sigma_u_log"):
        mconds[k] = conds[k] * float(noise_scale)
    out = add_measurements(truth, mconds, seed + 1000, noise=noise)
    meta = dict(out.meta)
    meta.update({"current_speed": float(current[0]), "current_dir": float(current[1])})
    return Trial(out.t, out.channels, out.units, meta)


__all__ = ["has_trial_conditions", "add_measurements", "simulate_measured", "TRUE_UNITS", "OVERSAMPLE"]
