"""The bis system of non-dimensional quantities (Fossen 1994 p. 178; Fossen et al. 1996 eqs. 26–28).

Units: length ``L``, mass ``m``, time ``sqrt(L/g)``; hence speed ``sqrt(L g)``, angular
rate ``sqrt(g/L)``, acceleration ``g``, angular acceleration ``g/L``, force ``m g`` and
moment ``m g L``. Angles are unchanged.

For the 3-DOF surge–sway–yaw model the generalised coordinates have mixed units, so the
matrices convert with diagonal scale matrices (``S`` velocity, ``Sa`` acceleration,
``Sf`` force, ``Th`` time):

* ``ν = S ν''``, ``ν̇ = Sa ν̇''``, ``τ = Sf τ''``, ``Sa = S / Th``;
* ``M = Sf M'' Sa⁻¹`` (eq. 27), ``D = Sf D'' S⁻¹`` (eq. 28), ``A = S A'' S⁻¹ / Th``,
  ``B = Sa B'' Sf⁻¹``;
* momentum ``h = M ν = Sf Th h''``, so ``A_h = (Sf Th) A_h'' (Sf Th)⁻¹ / Th``;
* thrust: ``τ = T K u`` with ``u`` dimensionless (eq. 5), so ``T = diag(1, 1, L) T''``
  (moment arms in metres) and ``K = m g K''``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Bis:
    """Scales of the bis system for a vessel of length ``L`` (m) and mass ``m`` (kg)."""

    L: float
    m: float
    g: float = 9.81

    # -- scalar units ---------------------------------------------------------------
    @property
    def time(self) -> float:
        """Time unit sqrt(L/g) in s."""
        return float(np.sqrt(self.L / self.g))

    @property
    def speed(self) -> float:
        """Speed unit sqrt(L g) in m/s."""
        return float(np.sqrt(self.L * self.g))

    @property
    def rate(self) -> float:
        """Angular-rate unit sqrt(g/L) in rad/s."""
        return float(np.sqrt(self.g / self.L))

    @property
    def force(self) -> float:
        """Force unit m g in N."""
        return self.m * self.g

    @property
    def moment(self) -> float:
        """Moment unit m g L in N m."""
        return self.m * self.g * self.L

    # -- 3-DOF scale matrices ------------------------------------------------------------
    @property
    def S(self) -> np.ndarray:
        """Velocity scales diag(sqrt(gL), sqrt(gL), sqrt(g/L))."""
        return np.diag([self.speed, self.speed, self.rate])

    @property
    def Sa(self) -> np.ndarray:
        """Acceleration scales diag(g, g, g/L)."""
        return np.diag([self.g, self.g, self.g / self.L])

    @property
    def Sf(self) -> np.ndarray:
        """Generalised-force scales diag(m g, m g, m g L)."""
        return np.diag([self.force, self.force, self.moment])

    @property
    def Seta(self) -> np.ndarray:
        """Position scales diag(L, L, 1) for η = [x, y, ψ]."""
        return np.diag([self.L, self.L, 1.0])

    # -- vectors ----------------------------------------------------------------------------
    def t_to_bis(self, t):
        return np.asarray(t, dtype=float) / self.time

    def t_from_bis(self, t):
        return np.asarray(t, dtype=float) * self.time

    def eta_to_bis(self, eta):
        """``[x, y, ψ]`` (m, m, rad) → bis; works on ``(..., 3)``."""
        return np.asarray(eta, dtype=float) / np.diag(self.Seta)

    def eta_from_bis(self, eta):
        return np.asarray(eta, dtype=float) * np.diag(self.Seta)

    def nu_to_bis(self, nu):
        """``[u, v, r]`` (m/s, m/s, rad/s) → bis; works on ``(..., 3)``."""
        return np.asarray(nu, dtype=float) / np.diag(self.S)

    def nu_from_bis(self, nu):
        return np.asarray(nu, dtype=float) * np.diag(self.S)

    def tau_to_bis(self, tau):
        """``[X, Y, N]`` (N, N, N m) → bis; works on ``(..., 3)``."""
        return np.asarray(tau, dtype=float) / np.diag(self.Sf)

    def tau_from_bis(self, tau):
        return np.asarray(tau, dtype=float) * np.diag(self.Sf)

    @property
    def h_scale(self) -> np.ndarray:
        """Momentum scales ``Sf Th`` (diag): ``h = M ν`` in N s, N s, N m s."""
        return self.Sf * self.time

    # -- matrices -------------------------------------------------------------------------------
    def M_from_bis(self, M):
        """Inertia matrix eq. 27 → dimensional: ``Sf M'' Sa⁻¹``."""
        return self.Sf @ np.asarray(M, dtype=float) @ np.linalg.inv(self.Sa)

    def M_to_bis(self, M):
        return np.linalg.inv(self.Sf) @ np.asarray(M, dtype=float) @ self.Sa

    def D_from_bis(self, D):
        """Damping matrix eq. 28 → dimensional: ``Sf D'' S⁻¹``."""
        return self.Sf @ np.asarray(D, dtype=float) @ np.linalg.inv(self.S)

    def D_to_bis(self, D):
        return np.linalg.inv(self.Sf) @ np.asarray(D, dtype=float) @ self.S

    def A_from_bis(self, A):
        """System matrix of ν̇ = A ν (eq. 50) → dimensional: ``S A'' S⁻¹ / Th``."""
        return self.S @ np.asarray(A, dtype=float) @ np.linalg.inv(self.S) / self.time

    def A_to_bis(self, A):
        return np.linalg.inv(self.S) @ np.asarray(A, dtype=float) @ self.S * self.time

    def B_from_bis(self, B):
        """Input matrix of ν̇ = B τ → dimensional: ``Sa B'' Sf⁻¹`` (B acting on forces)."""
        return self.Sa @ np.asarray(B, dtype=float) @ np.linalg.inv(self.Sf)

    def Ah_from_bis(self, Ah):
        """Momentum matrix A_h of eq. 35 → dimensional: ``H A_h'' H⁻¹ / Th`` with ``H = Sf Th``."""
        H = self.h_scale
        return H @ np.asarray(Ah, dtype=float) @ np.linalg.inv(H) / self.time

    def Ah_to_bis(self, Ah):
        H = self.h_scale
        return np.linalg.inv(H) @ np.asarray(Ah, dtype=float) @ H * self.time

    def T_from_bis(self, T):
        """Configuration matrix eq. 29 → moment arms in metres: ``diag(1, 1, L) T''``."""
        return self.Seta @ np.asarray(T, dtype=float)

    def T_to_bis(self, T):
        return np.linalg.inv(self.Seta) @ np.asarray(T, dtype=float)

    def K_from_bis(self, k):
        """Thrust coefficients (diagonal of K, eq. 6) → N: ``m g K''``."""
        return np.asarray(k, dtype=float) * self.force

    def K_to_bis(self, k):
        return np.asarray(k, dtype=float) / self.force


__all__ = ["Bis"]
