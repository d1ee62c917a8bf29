"""Pitch-controlled thrusters of a DP vessel (Fossen, Sagatun & Sørensen 1996, §2.1).

Symbols (paper → code):

* ``p = P/D`` pitch ratio (eq. 2) → ``p``; ``p_0`` zero-thrust offset (eq. 3) → ``p0``;
* ``F = K(n) |p − p0| (p − p0)`` (eq. 1) → :func:`thrust`;
* control vector ``u_i = |p_i − p_i0| (p_i − p_i0)`` (eq. 5) → :func:`control_vector`;
* ``K = diag{K_1 … K_r}`` (eq. 6) → :func:`coefficient_matrix`;
* thruster configuration matrix ``T`` (eq. 7) → :func:`configuration_matrix`, with the
  azimuth column read as ``[cos α, sin α, l6 sin α]`` (ERRATA 001: the printed matrix is
  garbled there; eq. 29 is the case α = 90°);
* ``τ = T K u`` (eq. 4) → :func:`thrust_vector`.
"""

from __future__ import annotations

import numpy as np


def thrust(K: float | np.ndarray, p: float | np.ndarray, p0: float | np.ndarray = 0.0) -> np.ndarray:
    """Thrust of a pitch-controlled propeller, eq. 1: ``F = K |p − p0| (p − p0)``.

    Parameters
    ----------
    K : float or ndarray
        Thrust coefficient K(n) at the (constant) propeller revolution n.
    p, p0 : float or ndarray
        Pitch ratio P/D (eq. 2) and its zero-thrust offset (eq. 3).
    """
    d = np.asarray(p, dtype=float) - p0
    return np.asarray(K, dtype=float) * np.abs(d) * d


def control_vector(p: np.ndarray, p0: np.ndarray | float = 0.0) -> np.ndarray:
    """Control vector of eq. 5, ``u_i = |p_i − p_i0| (p_i − p_i0)``, elementwise over ``(..., r)``."""
    d = np.asarray(p, dtype=float) - np.asarray(p0, dtype=float)
    return np.abs(d) * d


def pitch_from_control(u: np.ndarray, p0: np.ndarray | float = 0.0) -> np.ndarray:
    """Inverse of :func:`control_vector`: ``p = p0 + sign(u) sqrt(|u|)``."""
    u = np.asarray(u, dtype=float)
    return np.asarray(p0, dtype=float) + np.sign(u) * np.sqrt(np.abs(u))


def coefficient_matrix(k: np.ndarray) -> np.ndarray:
    """Diagonal thrust-coefficient matrix of eq. 6, ``K = diag{K_1, …, K_r}``."""
    return np.diag(np.asarray(k, dtype=float))


def configuration_matrix(arms: np.ndarray, alpha: float = np.pi / 2) -> np.ndarray:
    """Thruster configuration matrix of eq. 7 for the supply-vessel layout (3 × 6).

    Columns: port and starboard main propellers, aft tunnel thrusters I and II, bow tunnel
    thruster, bow azimuth thruster at angle ``alpha`` (rad, 0 = thrust forward, π/2 = thrust
    to starboard).

    Parameters
    ----------
    arms : ndarray, shape (6,)
        Yaw moment arms ``l1 … l6`` (positive numbers; the signs are those of eq. 7).
    alpha : float
        Azimuth angle of thruster 6 in rad.

    Notes
    -----
    ERRATA 001 reading of eq. 7: the azimuth column is ``[cos α, sin α, l6 sin α]``. The
    other columns follow eq. 7 as printed: ``[1, 0, l1]``, ``[1, 0, −l2]``, ``[0, 1, −l3]``,
    ``[0, 1, −l4]``, ``[0, 1, l5]``. With the arms of eq. 29 and α = 90° this gives eq. 29.
    """
    l1, l2, l3, l4, l5, l6 = np.asarray(arms, dtype=float)
    ca, sa = np.cos(alpha), np.sin(alpha)
    return np.array([[1.0, 1.0, 0.0, 0.0, 0.0, ca],
                     [0.0, 0.0, 1.0, 1.0, 1.0, sa],
                     [l1, -l2, -l3, -l4, l5, l6 * sa]])


def azimuth_column(l6: float, alpha: float | np.ndarray) -> np.ndarray:
    """Column 6 of eq. 7 (ERRATA reading) ``[cos α, sin α, l6 sin α]``; shape ``(3,)`` or ``(3, n)``."""
    a = np.asarray(alpha, dtype=float)
    return np.array([np.cos(a), np.sin(a), l6 * np.sin(a)])


def thrust_vector(T: np.ndarray, k: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Thrust forces and moment, eq. 4: ``τ = T K u`` (``u`` of eq. 5, ``k`` the diagonal of K)."""
    return np.asarray(T, dtype=float) @ (np.asarray(k, dtype=float) * np.asarray(u, dtype=float))


__all__ = ["thrust", "control_vector", "pitch_from_control", "coefficient_matrix",
           "configuration_matrix", "azimuth_column", "thrust_vector"]
