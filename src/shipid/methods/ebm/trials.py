"""Simulated sea trials of ESSO OSAKA as in Yoon & Rhee (2003), §5.1.

Manoeuvres (through :func:`shipid.simulate.manoeuvres.run_manoeuvre`): 35° turning
circles to both sides, a 20°/20° zig-zag and a ±10° PRBS rudder run, with a current
of 2 knots setting towards 45° (eq. 2 convention), measured as eq. 8 with the noise of
eq. 19 (:mod:`shipid.simulate.trials`, which ``shipid.simulate("esso-osaka", ...)`` uses too).
"""

from __future__ import annotations

from shipid.io.trial import Trial
from shipid.models import abkowitz as ab
from shipid.simulate.trials import TRUE_UNITS, add_measurements, simulate_measured

#: The trials of §5.1: name → (manoeuvre spec for run_manoeuvre, default duration in s).
#: The PRBS clock period is ours: the paper's "commanded every 400 second" reads as
#: a garbled figure caption; 40 s is a period the ship follows (cf. Fig. 7's grid).
STANDARD_TRIALS = {
    "turning-35-stbd": ("turning-35", 900.0),
    "turning-35-port": ("turning-35-port", 900.0),
    "zigzag-20": ("zigzag-20", 1200.0),
}
VALIDATION_TRIAL = ("prbs-10-40", 1200.0)


def simulate_trial(manoeuvre: str, duration: float, *, seed: int = 0, dt: float | None = None,
                   current: tuple[float, float] | None = None, theta: ab.AbkowitzParams | None = None,
                   noise: bool = True, vessel: str = "esso-osaka", oversample: int = 5,
                   speed: float | None = None, noise_scale: float = 1.0) -> Trial:
    """Simulate one measured ESSO OSAKA trial (§5.1): :func:`shipid.simulate.trials.simulate_measured`,
    which ``shipid.simulate("esso-osaka", ...)`` runs too; see there for the parameters."""
    return simulate_measured(manoeuvre, duration, seed=seed, dt=dt, current=current, theta=theta, noise=noise,
                             vessel=vessel, oversample=oversample, speed=speed, noise_scale=noise_scale)


def standard_trials(seed: int = 0, *, scale: float = 1.0, dt: float | None = None) -> list[Trial]:
    """The three identification trials of §5.1 (turning both sides, zig-zag); ``scale`` shortens them."""
    return [simulate_trial(m, d * scale, seed=seed + i, dt=dt)
            for i, (m, d) in enumerate(STANDARD_TRIALS.values())]


__all__ = ["STANDARD_TRIALS", "VALIDATION_TRIAL", "simulate_trial", "standard_trials", "add_measurements",
           "TRUE_UNITS"]
