"""Actuators with angle and rate limits: the steering gear and thruster pitch/azimuth servos.

A commanded value ``c`` (rudder angle δ_c, pitch ratio, azimuth angle) is followed
by the actual value ``a`` moving at most at the rate limit and clipped at the angle
limit. On a sample grid with step ``dt`` the servo is applied once per sample::

    a_k = clip(a_{k-1} + clip(c_k - a_{k-1}, -rate*dt, rate*dt), lo, hi)

with ``a_{-1}`` the initial value; ``a_k`` is then held over ``[t_k, t_{k+1})`` (the
integrators hold inputs over each step). So the recorded actual value never moves
by more than ``rate*dt`` between samples and never leaves ``[lo, hi]``. This is the
usual first-order description of a steering gear (Fossen 1994, §6 "rudder
servo": rate saturation |δ̇| ≤ δ̇_max, typically 2.3–7 °/s, and angle saturation
|δ| ≤ 35°), here without the small servo time constant.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class RateLimitedActuator:
    """A servo with magnitude and rate limits, stepped once per sample.

    Parameters
    ----------
    dt : float
        Sample interval (s).
    rate_limit : float
        Maximum rate (units/s); ``inf`` for none.
    lo, hi : float
        Limits of the actual value.
    value : float
        Initial actual value ``a_{-1}``.
    """

    dt: float
    rate_limit: float = np.inf
    lo: float = -np.inf
    hi: float = np.inf
    value: float = 0.0
    _max_step: float = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not self.dt > 0:
            raise ValueError(f"actuator sample interval must be positive, got {self.dt}")
        if not self.rate_limit > 0:
            raise ValueError(f"actuator rate limit must be positive, got {self.rate_limit}")
        self._max_step = self.rate_limit * self.dt
        self.value = float(np.clip(self.value, self.lo, self.hi))

    def step(self, command: float) -> float:
        """Move toward ``command`` for one sample; return the new actual value."""
        move = float(np.clip(command - self.value, -self._max_step, self._max_step))
        self.value = float(np.clip(self.value + move, self.lo, self.hi))
        return self.value


def steering_gear(dt: float, rudder_limit: float, rudder_rate_limit: float,
                  initial: float = 0.0) -> RateLimitedActuator:
    """The steering gear: rudder angle limited to ``±rudder_limit`` (rad), rate to ``rudder_rate_limit`` (rad/s)."""
    return RateLimitedActuator(dt=dt, rate_limit=rudder_rate_limit, lo=-rudder_limit,
                               hi=rudder_limit, value=initial)
