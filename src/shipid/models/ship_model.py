"""The interface between a vessel's dynamics and the simulator, the CLI and the manoeuvres.

Each model family (``shipid.models.roll``, ``shipid.models.dp``,
``shipid.models.abkowitz``) provides a function ``ship_model(vessel) -> ShipModel``;
:mod:`shipid.simulate.registry` maps vessel names to those functions, so
``shipid simulate VESSEL MANOEUVRE`` works for every packaged vessel.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

import numpy as np


@dataclass(frozen=True)
class ShipModel:
    """A simulatable ship.

    Attributes
    ----------
    name : str
        Vessel name.
    f : callable
        ``f(t, x, u, theta) -> dx/dt``.
    theta : object
        Parameters passed to ``f`` (a frozen dataclass).
    state_names, input_names : tuple of str
        Names of the entries of ``x`` and ``u``; input names are Trial channel names
        (``"delta"``, ``"n"``, ``"p1"`` ...).
    x0 : callable
        ``x0(speed) -> (nx,)``: straight-ahead initial state at the given speed (m/s).
    outputs : callable
        ``outputs(t, X, U) -> dict[str, ndarray]``: Trial channels (SI) from the
        state and input histories (``x, y, psi, u, v, r`` ... as the model has them).
    service_speed : float
        Default speed (m/s) for manoeuvres.
    heading_index : int or None
        Index of ψ in ``x`` (for heading-based rules such as the zig-zag), None if absent.
    rudder_limit, rudder_rate_limit : float
        Rudder angle (rad) and rate (rad/s) limits of the steering gear.
    u0 : callable or None
        ``u0(speed) -> (nu,)``: the input vector that holds the straight-ahead state
        ``x0(speed)`` (propeller rps, thruster pitch offsets p_i0 giving zero thrust,
        azimuth angle ...). ``None`` means all zeros. Manoeuvres change only the
        inputs they drive (``delta``, or ``p1``...``p6``, ``alpha6``) and hold the
        others at these values; DP pitch steps are added to them.
    input_limits, input_rate_limits : mapping of str to float
        Optional magnitude limits (about 0) and rate limits (per second) of other
        actuators, by input name (``"p1": 0.1`` ...); the manoeuvres use their own
        documented defaults where a name is absent.
    output_units : mapping of str to str
        SI units of output channels that are not standard Trial channels
        (``"u_r": "m/s"``); standard names take their unit from
        :data:`shipid.io.trial.CHANNELS`, anything else is ``"-"``.
    """

    name: str
    f: Callable[[float, np.ndarray, np.ndarray, Any], np.ndarray]
    theta: Any
    state_names: tuple[str, ...]
    input_names: tuple[str, ...]
    x0: Callable[[float], np.ndarray]
    outputs: Callable[[np.ndarray, np.ndarray, np.ndarray], dict[str, np.ndarray]]
    service_speed: float
    heading_index: int | None = None
    rudder_limit: float = np.deg2rad(35.0)
    rudder_rate_limit: float = np.deg2rad(2.33)
    u0: Callable[[float], np.ndarray] | None = None
    input_limits: Mapping[str, float] = field(default_factory=dict)
    input_rate_limits: Mapping[str, float] = field(default_factory=dict)
    output_units: Mapping[str, str] = field(default_factory=dict)

    def nominal_input(self, speed: float) -> np.ndarray:
        """``u0(speed)`` as a float array of shape ``(nu,)`` (zeros when ``u0`` is None)."""
        if self.u0 is None:
            return np.zeros(len(self.input_names))
        u = np.atleast_1d(np.asarray(self.u0(speed), dtype=float)).copy()
        if u.shape != (len(self.input_names),):
            raise ValueError(f"{self.name}: u0 gives shape {u.shape}, inputs are {self.input_names}")
        return u
