"""A generic first-order Nomoto ship, packaged so the simulator works without any paper's model.

Dynamics (Nomoto et al. 1957; Fossen 1994 eq. 6.76, first-order approximation)::

    T ṙ + r = K δ,     ψ̇ = r,     ẋ = u cos ψ,     ẏ = u sin ψ,     u̇ = 0

State ``x = [x, y, psi, u, r]``, input ``u = [delta]``. The surge speed is a state
held constant so that ``x0(speed)`` can set it. Sway is neglected (``v = 0``); this
is a steering model for testing manoeuvres and estimators, not a vessel of the papers.

Default coefficients: a generic cargo ship of L = 100 m at U = 7.5 m/s with the
non-dimensional K' = 2.0 and T' = 1.5, K = K' U / L, T = T' L / U. These are a
chosen order of magnitude for a directionally stable cargo ship, not values taken
from a paper. Positive δ
gives positive (starboard) yaw rate here; the manoeuvres do not rely on that sign.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shipid.models.ship_model import ShipModel


@dataclass(frozen=True)
class NomotoParams:
    """First-order Nomoto coefficients.

    Attributes
    ----------
    K : float
        Rudder gain (1/s).
    T : float
        Yaw time constant (s).
    """

    K: float
    T: float


def nomoto_f(t: float, x: np.ndarray, u: np.ndarray, theta: NomotoParams) -> np.ndarray:
    """``dx/dt`` of the first-order Nomoto ship (see module docstring)."""
    _, _, psi, spd, r = x
    return np.array([spd * np.cos(psi), spd * np.sin(psi), r, 0.0,
                     (theta.K * u[0] - r) / theta.T])


def _outputs(t: np.ndarray, X: np.ndarray, U: np.ndarray) -> dict[str, np.ndarray]:
    return {"x": X[:, 0], "y": X[:, 1], "psi": X[:, 2], "u": X[:, 3],
            "v": np.zeros(len(t)), "r": X[:, 4]}


def nomoto_model(K: float | None = None, T: float | None = None, *, L: float = 100.0,
                 U: float = 7.5, name: str = "nomoto", rudder_limit: float = np.deg2rad(35.0),
                 rudder_rate_limit: float = np.deg2rad(2.33)) -> ShipModel:
    """A first-order Nomoto :class:`~shipid.models.ship_model.ShipModel`.

    Parameters
    ----------
    K, T : float, optional
        Gain (1/s) and time constant (s); default from K' = 2.0, T' = 1.5 at ``L``, ``U``.
    L, U : float
        Length (m) and service speed (m/s) used for the defaults.
    rudder_limit, rudder_rate_limit : float
        Steering gear limits (rad, rad/s); 2.33 °/s is the IMO minimum (35° to 30° the other side in 28 s).
    """
    K = 2.0 * U / L if K is None else float(K)
    T = 1.5 * L / U if T is None else float(T)

    def x0(speed: float) -> np.ndarray:
        return np.array([0.0, 0.0, 0.0, float(speed), 0.0])

    return ShipModel(name=name, f=nomoto_f, theta=NomotoParams(K=K, T=T),
                     state_names=("x", "y", "psi", "u", "r"), input_names=("delta",),
                     x0=x0, outputs=_outputs, service_speed=U, heading_index=2,
                     rudder_limit=rudder_limit, rudder_rate_limit=rudder_rate_limit)


def ship_model(vessel: object = None) -> ShipModel:
    """Registry entry: the default Nomoto ship (``vessel`` is ignored)."""
    return nomoto_model()
