"""The 17-state model of step 1 of Estimation-Before-Modelling (Yoon & Rhee 2003, eqs. 4–8).

State (eq. 7)::

    x = [u_r, v_r, r, x_r, y_r, ψ, X, Ẋ, Ẍ, Y, Ẏ, Ÿ, N, Ṅ, N̈, c_x, c_y]

* ``u_r, v_r, r``: velocities relative to the water (eq. 2) and yaw rate;
* ``x_r, y_r``: position in the frame moving with the current (so the earth-fixed
  position is ``x_r + c_x t``), ``ψ`` heading;
* ``X, Y, N`` and two time derivatives each: hydrodynamic forces without the
  added-mass part, modelled as third-order Gauss–Markov processes (eq. 4, read as
  ``d³X/dt³ = w_X``: the state holds X, Ẋ, Ẍ, so the white noise drives Ẍ);
* ``c_x, c_y``: earth-fixed current velocity, constant plus white noise (eq. 5).

State equation (eq. 6)::

    M [u̇_r, v̇_r, ṙ]ᵀ = [m(v_r r + x_G r²) + X, −m u_r r + Y, −m x_G u_r r + N]
    ẋ_r = u_r cos ψ − v_r sin ψ,  ẏ_r = u_r sin ψ + v_r cos ψ,  ψ̇ = r

Measurements (eq. 8): DGPS antenna position and earth-fixed velocity, heading and
speed log::

    z = [x_r + x_D cos ψ − y_D sin ψ + c_x t,
         y_r + x_D sin ψ + y_D cos ψ + c_y t,
         (u_r − y_D r) cos ψ − (v_r + x_D r) sin ψ + c_x,
         (u_r − y_D r) sin ψ + (v_r + x_D r) cos ψ + c_y,
         ψ,
         u_r − y_S r]

:class:`EbmModel` also offers the *absolute-position* variant of §3.2 (``x, y``
instead of ``x_r, y_r``: ``ẋ = … + c_x`` and no ``c t`` in the measurement), which
loses one rank of observability (see :mod:`shipid.analysis.observability`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shipid.models.abkowitz import AbkowitzParams

STATE_NAMES = ("u_r", "v_r", "r", "x_r", "y_r", "psi", "X", "X_dot", "X_ddot", "Y", "Y_dot",
               "Y_ddot", "N", "N_dot", "N_ddot", "c_x", "c_y")
MEAS_NAMES = ("x_gps", "y_gps", "x_dot_gps", "y_dot_gps", "psi", "u_log")
NX = 17
NZ = 6


@dataclass(frozen=True)
class EbmModel:
    """Parameters of the 17-state model.

    Attributes
    ----------
    m, x_G : float
        Mass (kg), centre of gravity forward of the origin (m).
    Minv : ndarray (3, 3)
        Inverse of the inertia matrix M (rigid body + added mass).
    x_D, y_D, y_S : float
        DGPS antenna and speed-log positions in body axes (m), eq. 8.
    q_force : tuple of 3 floats
        Spectral densities of w_X, w_Y, w_N (N²/s⁵, N²m²/s⁵).
    q_current : float
        Spectral density of w_cx, w_cy ((m/s)²/s).
    q_kin : float
        Small spectral density on u_r, v_r, r (model error; (m/s)²/s), default 0.
    absolute : bool
        Use absolute positions (x, y) instead of (x_r, y_r) (§3.2 variant).
    """

    m: float
    x_G: float
    Minv: np.ndarray
    x_D: float
    y_D: float
    y_S: float
    q_force: tuple[float, float, float] = (1e6, 1e6, 1e12)
    q_current: float = 1e-10
    q_kin: float = 0.0
    absolute: bool = False

    @classmethod
    def from_abkowitz(cls, p: AbkowitzParams, x_D: float, y_D: float, y_S: float, **kw) -> "EbmModel":
        return cls(m=p.m, x_G=p.x_G, Minv=np.linalg.inv(p.mass_matrix), x_D=x_D, y_D=y_D, y_S=y_S, **kw)

    def kernel_params(self) -> np.ndarray:
        """Parameter vector of the compiled kernels of :mod:`shipid.methods.ebm.model_kernels`.

        ``[m, x_G, Minv (3 × 3, row-major), x_D, y_D, y_S, absolute]`` (15 floats):
        ``ebm_f/F/h/H`` there compute exactly :meth:`f`, :meth:`F`, :meth:`h`, :meth:`H`.
        """
        return np.concatenate([[self.m, self.x_G], np.asarray(self.Minv, dtype=float).ravel(),
                               [self.x_D, self.y_D, self.y_S, 1.0 if self.absolute else 0.0]])

    # -- dynamics ------------------------------------------------------------------------
    def f(self, t: float, x: np.ndarray, u=None, theta=None) -> np.ndarray:
        """State equation (eq. 6) without noise; signature ``f(t, x, u, θ)``."""
        ur, vr, r, _, _, psi = x[0], x[1], x[2], x[3], x[4], x[5]
        m, xg = self.m, self.x_G
        rhs0 = m * (vr * r + xg * r * r) + x[6]
        rhs1 = -m * ur * r + x[9]
        rhs2 = -m * xg * ur * r + x[12]
        Mi = self.Minv
        dx = np.zeros(NX)
        dx[0] = Mi[0, 0] * rhs0 + Mi[0, 1] * rhs1 + Mi[0, 2] * rhs2
        dx[1] = Mi[1, 0] * rhs0 + Mi[1, 1] * rhs1 + Mi[1, 2] * rhs2
        dx[2] = Mi[2, 0] * rhs0 + Mi[2, 1] * rhs1 + Mi[2, 2] * rhs2
        c, s = np.cos(psi), np.sin(psi)
        dx[3] = ur * c - vr * s
        dx[4] = ur * s + vr * c
        if self.absolute:
            dx[3] += x[15]
            dx[4] += x[16]
        dx[5] = r
        dx[6], dx[7] = x[7], x[8]
        dx[9], dx[10] = x[10], x[11]
        dx[12], dx[13] = x[13], x[14]
        return dx

    def F(self, t: float, x: np.ndarray, u=None, theta=None) -> np.ndarray:
        """Jacobian ∂f/∂x (17 × 17); signature ``F(t, x, u, θ)`` as :meth:`f`."""
        ur, vr, r, psi = x[0], x[1], x[2], x[5]
        m, xg = self.m, self.x_G
        # d rhs / d (ur, vr, r)
        J = np.array([[0.0, m * r, m * (vr + 2 * xg * r)],
                      [-m * r, 0.0, -m * ur],
                      [-m * xg * r, 0.0, -m * xg * ur]])
        F = np.zeros((NX, NX))
        F[0:3, 0:3] = self.Minv @ J
        F[0:3, 6] = self.Minv[:, 0]
        F[0:3, 9] = self.Minv[:, 1]
        F[0:3, 12] = self.Minv[:, 2]
        c, s = np.cos(psi), np.sin(psi)
        F[3, 0], F[3, 1], F[3, 5] = c, -s, -ur * s - vr * c
        F[4, 0], F[4, 1], F[4, 5] = s, c, ur * c - vr * s
        if self.absolute:
            F[3, 15] = 1.0
            F[4, 16] = 1.0
        F[5, 2] = 1.0
        for i in (6, 9, 12):
            F[i, i + 1] = 1.0
            F[i + 1, i + 2] = 1.0
        return F

    def Q(self) -> np.ndarray:
        """Spectral density matrix of the process noise w(t) (17 × 17, diagonal)."""
        q = np.zeros(NX)
        q[[8, 11, 14]] = self.q_force
        q[[15, 16]] = self.q_current
        q[[0, 1]] = self.q_kin
        return np.diag(q)

    # -- measurements --------------------------------------------------------------------
    def h(self, t: float, x: np.ndarray) -> np.ndarray:
        """Measurement function of eq. 8."""
        ur, vr, r, xr, yr, psi, cx, cy = x[0], x[1], x[2], x[3], x[4], x[5], x[15], x[16]
        c, s = np.cos(psi), np.sin(psi)
        xD, yD = self.x_D, self.y_D
        tt = 0.0 if self.absolute else t
        a = ur - yD * r
        b = vr + xD * r
        return np.array([xr + xD * c - yD * s + cx * tt,
                         yr + xD * s + yD * c + cy * tt,
                         a * c - b * s + cx,
                         a * s + b * c + cy,
                         psi,
                         ur - self.y_S * r])

    def H(self, t: float, x: np.ndarray) -> np.ndarray:
        """Jacobian ∂h/∂x (6 × 17)."""
        ur, vr, r, psi = x[0], x[1], x[2], x[5]
        c, s = np.cos(psi), np.sin(psi)
        xD, yD = self.x_D, self.y_D
        tt = 0.0 if self.absolute else t
        a = ur - yD * r
        b = vr + xD * r
        H = np.zeros((NZ, NX))
        H[0, 3] = 1.0
        H[0, 5] = -xD * s - yD * c
        H[0, 15] = tt
        H[1, 4] = 1.0
        H[1, 5] = xD * c - yD * s
        H[1, 16] = tt
        H[2, 0], H[2, 1], H[2, 2] = c, -s, -yD * c - xD * s
        H[2, 5] = -a * s - b * c
        H[2, 15] = 1.0
        H[3, 0], H[3, 1], H[3, 2] = s, c, -yD * s + xD * c
        H[3, 5] = a * c - b * s
        H[3, 16] = 1.0
        H[4, 5] = 1.0
        H[5, 0], H[5, 2] = 1.0, -self.y_S
        return H


def measurement_noise(sigma_xy: float, sigma_xy_dot: float, sigma_psi: float, sigma_u_log: float) -> np.ndarray:
    """Measurement covariance R of eq. 8 from the standard deviations of eq. 19."""
    return np.diag(np.array([sigma_xy, sigma_xy, sigma_xy_dot, sigma_xy_dot, sigma_psi, sigma_u_log]) ** 2)


def initial_state(z0: np.ndarray, model: EbmModel, u_r0: float | None = None,
                  v_r0: float = 0.0, current: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
    """A first guess of the state from the first measurement.

    Position from the DGPS fix minus the antenna lever arm, heading from the gyro,
    u_r from the speed log, v_r and r zero, forces zero, current ``current``. The
    second pass of §5.1.1 passes the first pass's current estimate and the
    relative velocities it implies.
    """
    psi = z0[4]
    c, s = np.cos(psi), np.sin(psi)
    x = np.zeros(NX)
    x[0] = z0[5] if u_r0 is None else u_r0
    x[1] = v_r0
    x[3] = z0[0] - (model.x_D * c - model.y_D * s)
    x[4] = z0[1] - (model.x_D * s + model.y_D * c)
    x[5] = psi
    x[15], x[16] = current
    return x


__all__ = ["EbmModel", "STATE_NAMES", "MEAS_NAMES", "NX", "NZ", "measurement_noise", "initial_state"]
