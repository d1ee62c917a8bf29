"""Simulated sea trials of ESSO OSAKA as in Yoon & Rhee (2003), §5.1.

Manoeuvres (through :func:`shipid.simulate.manoeuvres.run_manoeuvre`): 35° turning
circles to both sides, a 20°/20° zig-zag and a ±10° PRBS rudder run, with a current
of 2 knots setting towards 45° (eq. 2 convention). Measurements follow eq. 8 with
the noise of eq. 19:

* ``x, y``: DGPS antenna position, earth-fixed (σ = 10 m);
* ``x_dot, y_dot``: DGPS antenna earth-fixed velocity (σ = 0.01 m/s);
* ``psi``: gyro heading (σ = 0.0008°);
* ``U``: speed log ``u_r − y_S r`` (σ = 0.01 m/s);
* ``delta``, ``n``: rudder angle and propeller rate, noise-free (known inputs).

The noise-free truth is kept in channels prefixed ``true_`` (``true_u_r``,
``true_v_r``, ``true_r``, ``true_X``, ``true_Y``, ``true_N``, ``true_x``, ``true_y``)
so that step 1 can be checked; :mod:`shipid.methods.ebm.estimator` never reads them.
"""

from __future__ import annotations

import numpy as np

from shipid.io.trial import Trial
from shipid.models import abkowitz as ab
from shipid.simulate.manoeuvres import run_manoeuvre

#: The trials of §5.1: name → (manoeuvre spec for run_manoeuvre, default duration in s).
#: The PRBS clock period is ours: the seed's "commanded every 400 second" reads as
#: a garbled figure caption; 40 s is a period the ship follows (cf. Fig. 7's grid).
STANDARD_TRIALS = {
    "turning-35-stbd": ("turning-35", 900.0),
    "turning-35-port": ("turning-35-port", 900.0),
    "zigzag-20": ("zigzag-20", 1200.0),
}
VALIDATION_TRIAL = ("prbs-10-40", 1200.0)

TRUE_UNITS = {"true_u_r": "m/s", "true_v_r": "m/s", "true_r": "rad/s", "true_X": "N", "true_Y": "N",
              "true_N": "N*m", "true_x": "m", "true_y": "m", "true_psi": "rad"}


def add_measurements(truth: Trial, conds: dict, seed: int, *, noise: bool = True) -> Trial:
    """Turn a noise-free simulated trial into the measured record of eq. 8 + eq. 19."""
    rng = np.random.default_rng(seed)
    t = truth.t
    psi = truth["psi"]
    ur, vr, r = truth["u_r"], truth["v_r"], truth["r"]
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


def simulate_trial(manoeuvre: str, duration: float, *, seed: int = 0, dt: float | None = None,
                   current: tuple[float, float] | None = None, theta: ab.AbkowitzParams | None = None,
                   noise: bool = True, vessel: str = "esso-osaka", oversample: int = 5,
                   speed: float | None = None, noise_scale: float = 1.0) -> Trial:
    """Simulate one measured ESSO OSAKA trial.

    Parameters
    ----------
    manoeuvre : str
        A :func:`shipid.simulate.manoeuvres.run_manoeuvre` name (``"turning-35"``,
        ``"zigzag-20"``, ``"prbs-10-40"`` ...).
    duration : float
        Seconds.
    seed : int
        Seeds the PRBS register and (``seed + 1000``) the measurement noise.
    dt : float, optional
        Sample interval (default the vessel file's ``[trials].dt``, 1 s).
    current : (speed m/s, direction rad), optional
        Default the §5.1 current (2 kn towards 45°).
    theta : AbkowitzParams, optional
        Coefficients to simulate with (default the true ones of Table 3); the approach
        propeller rate is ``theta.n0`` (scaled with ``speed / theta.U0``), so a ship from
        :func:`shipid.models.abkowitz.with_coefficients` starts in its own straight run.
    noise : bool
        Add the eq. 19 measurement noise.
    oversample : int
        The ship is simulated with a step ``dt / oversample`` (the rudder moves in
        correspondingly small zero-order-hold steps, close to a continuous steering
        gear) and recorded every ``oversample`` steps. With ``oversample = 1`` the
        rudder jumps 2.3° at each 1-s sample while it moves, and the recorded force
        (evaluated just after the jump) leads the force the ship felt over the
        previous interval by half a sample — an artefact that biases step 2.
    speed : float, optional
        Approach speed through the water (m/s), default the vessel's U0.
    noise_scale : float
        Multiplies every standard deviation of eq. 19 (the estimator is not told).
    """
    from dataclasses import replace

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
    fine = run_manoeuvre(model, manoeuvre, duration=duration, dt=dt / ov, seed=seed, speed=speed)
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


def standard_trials(seed: int = 0, *, scale: float = 1.0, dt: float | None = None) -> list[Trial]:
    """The three identification trials of §5.1 (turning both sides, zig-zag); ``scale`` shortens them."""
    return [simulate_trial(m, d * scale, seed=seed + i, dt=dt)
            for i, (m, d) in enumerate(STANDARD_TRIALS.values())]


__all__ = ["STANDARD_TRIALS", "VALIDATION_TRIAL", "simulate_trial", "standard_trials", "add_measurements"]
