"""Low-frequency DP ship model (Fossen, Sagatun & Sørensen 1996, §2.2–2.3 and §4).

Two forms of the same 3-DOF (surge, sway, yaw) model:

* the LF model of eq. 8 with kinematics eqs. 13–14, used to simulate (dimensional, SI)::

      M ν̇ + C(ν) ν + D (ν − ν_c) = τ + w,    η̇ = J(ψ) ν,    ν̇_c = 0

  with ``C(ν)`` built from the elements of ``M`` (eqs. 11–12; ERRATA 001: ``m_ij = m_ji``);
* the momentum form of eqs. 34–38 used by the estimator (bis system)::

      ḣ = −C(M⁻¹h) M⁻¹h + A_h h + T(α) K u + b_h + w_h,
      η̇ = J(ψ) M⁻¹ h,    ḃ_h = w_b,    θ̇ = w_θ

  with the ERRATA 001 readings: eq. 35 has ``ḣ`` (missing dot), eq. 40 means
  ``C_h(h) h = C(ν) ν`` with ``ν = M⁻¹ h``, and eq. 39 is ``A_h = −D M⁻¹``.

The parameter vector θ'' = [θ1 … θ9] is organised as in eqs. 46–47::

    A_h = [[θ1, 0, 0], [0, θ2, θ3], [0, θ4, θ5]],   K'' = diag{θ6, θ6, θ7, θ7, θ8, θ9}.

Derived DP control model (eqs. 50–52): ``A'' = M''⁻¹ A_h M''``, ``B'' = M''⁻¹ T'' K''``
(ERRATA 001: eq. 50 prints ``B'' = M''⁻¹``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shipid.errors import ShipidError
from shipid.models.bis import Bis
from shipid.models.thrusters import configuration_matrix, control_vector
from shipid.models.ship_model import ShipModel

#: Names of θ1..θ9 (eqs. 46–47) and what each one is.
THETA_NAMES = tuple(f"theta{i}" for i in range(1, 10))
THETA_MEANING = {
    "theta1": "A_h[1,1] (surge)", "theta2": "A_h[2,2] (sway)", "theta3": "A_h[2,3] (sway-yaw)",
    "theta4": "A_h[3,2] (yaw-sway)", "theta5": "A_h[3,3] (yaw)", "theta6": "K1 = K2 (main propellers)",
    "theta7": "K3 = K4 (aft tunnel thrusters)", "theta8": "K5 (bow tunnel thruster)",
    "theta9": "K6 (bow azimuth thruster)",
}
#: Index of θ1..θ9 in A_h (row, col), eq. 46.
_AH_INDEX = {0: (0, 0), 1: (1, 1), 2: (1, 2), 3: (2, 1), 4: (2, 2)}
#: Which thrusters share θ6..θ9, eq. 47.
_K_GROUPS = {5: (0, 1), 6: (2, 3), 7: (4,), 8: (5,)}


# ---------------------------------------------------------------------------------------------
# Parameters
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class DPVessel:
    """A DP vessel in the bis system (eqs. 26–30, 46–49).

    Attributes
    ----------
    M : ndarray (3, 3)
        Inertia matrix M'' incl. added mass (eq. 30).
    A_h : ndarray (3, 3)
        Momentum-equation matrix (eq. 48; ``A_h = −D M⁻¹``).
    K : ndarray (6,)
        Thrust coefficients, diagonal of K'' (eq. 49).
    arms : ndarray (6,)
        Yaw moment arms l1..l6 in units of L (eq. 7/29).
    p0 : ndarray (6,)
        Pitch-ratio offsets (eq. 1).
    bis : Bis
        Scales (L, m, g) for conversion to SI.
    """

    M: np.ndarray
    A_h: np.ndarray
    K: np.ndarray
    arms: np.ndarray
    p0: np.ndarray
    bis: Bis
    name: str = "supply"

    @property
    def Minv(self) -> np.ndarray:
        return np.linalg.inv(self.M)

    @property
    def D(self) -> np.ndarray:
        """Damping D'' = −A_h M'' (eq. 39, ERRATA reading A_h = −D M⁻¹)."""
        return -self.A_h @ self.M

    def T(self, alpha: float = np.pi / 2) -> np.ndarray:
        """Configuration matrix T'' (eq. 7, ERRATA reading) at azimuth angle ``alpha``."""
        return configuration_matrix(self.arms, alpha)

    @property
    def theta(self) -> np.ndarray:
        """θ1..θ9 of eqs. 46–47."""
        return theta_from_matrices(self.A_h, self.K)

    def with_theta(self, theta: np.ndarray) -> "DPVessel":
        A_h, K = matrices_from_theta(theta)
        return DPVessel(self.M, A_h, K, self.arms, self.p0, self.bis, self.name)


def dp_vessel(vessel) -> DPVessel:
    """Build a :class:`DPVessel` from a packaged vessel (``load_vessel("supply")``).

    Needs ``[particulars]`` L, m, g and ``[bis]`` M, arms, p0; ``[identified]`` A_h and K are
    optional (NaN when absent: a vessel still to be identified).
    """

    try:
        part = vessel.values("particulars")
        b = vessel.values("bis")
        ident = vessel.values("identified") if "identified" in vessel.sections else {}
        return DPVessel(M=np.asarray(b["M"]), A_h=np.asarray(ident.get("A_h", np.full((3, 3), np.nan))),
                        K=np.asarray(ident.get("K", np.full(6, np.nan))),
                        arms=np.asarray(b["arms"]), p0=np.asarray(b["p0"]),
                        bis=Bis(L=float(part["L"]), m=float(part["m"]), g=float(part["g"])),
                        name=vessel.name)
    except KeyError as err:
        raise ShipidError(f"vessel {vessel.name!r} has no DP model ({err.args[0]}; needs [particulars] L, m, g "
                          "and [bis] M, arms, p0)") from None


def matrices_from_theta(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(A_h, K)`` from θ1..θ9 (eqs. 46–47)."""
    th = np.asarray(theta, dtype=float)
    A_h = np.zeros((3, 3))
    for i, (r, c) in _AH_INDEX.items():
        A_h[r, c] = th[i]
    K = np.empty(6)
    for i, cols in _K_GROUPS.items():
        K[list(cols)] = th[i]
    return A_h, K


def theta_from_matrices(A_h: np.ndarray, K: np.ndarray) -> np.ndarray:
    """θ1..θ9 from ``A_h`` and the diagonal of ``K`` (eqs. 46–47; K1 and K3 represent their pairs)."""
    A_h = np.asarray(A_h, dtype=float)
    K = np.asarray(K, dtype=float)
    return np.array([A_h[r, c] for r, c in _AH_INDEX.values()] + [K[cols[0]] for cols in _K_GROUPS.values()])


# ---------------------------------------------------------------------------------------------
# Coriolis and kinematics (eqs. 11–14)
# ---------------------------------------------------------------------------------------------
def coriolis(M: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """Coriolis–centripetal matrix C(ν) of eq. 11 from the elements of M (eq. 12, ``m_ij = m_ji``)."""
    m11, m22, m23 = M[0, 0], M[1, 1], M[1, 2]
    u, v, r = nu
    a = m22 * v + m23 * r
    return np.array([[0.0, 0.0, -a], [0.0, 0.0, m11 * u], [a, -m11 * u, 0.0]])


def coriolis_times_nu(M: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """``C(ν) ν`` of eq. 11."""
    m11, m22, m23 = M[0, 0], M[1, 1], M[1, 2]
    u, v, r = nu
    a = m22 * v + m23 * r
    return np.array([-a * r, m11 * u * r, a * u - m11 * u * v])


def coriolis_times_nu_jacobian(M: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """∂(C(ν) ν)/∂ν (3 × 3)."""
    m11, m22, m23 = M[0, 0], M[1, 1], M[1, 2]
    u, v, r = nu
    a = m22 * v + m23 * r
    return np.array([[0.0, -m22 * r, -a - m23 * r],
                     [m11 * r, 0.0, m11 * u],
                     [a - m11 * v, (m22 - m11) * u, m23 * u]])


def rotation(psi: float) -> np.ndarray:
    """J(η) of eq. 14."""
    c, s = np.cos(psi), np.sin(psi)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rotation_dpsi(psi: float) -> np.ndarray:
    """∂J/∂ψ."""
    c, s = np.cos(psi), np.sin(psi)
    return np.array([[-s, -c, 0.0], [c, -s, 0.0], [0.0, 0.0, 0.0]])


# ---------------------------------------------------------------------------------------------
# LF model, eq. 8 (dimensional), for simulation
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class LFParams:
    """Dimensional (SI) parameters of eq. 8: M (kg, kg m, kg m²), D, T (m arms), K (N), p0."""

    M: np.ndarray
    D: np.ndarray
    arms: np.ndarray
    K: np.ndarray
    p0: np.ndarray

    @property
    def Minv(self) -> np.ndarray:
        return np.linalg.inv(self.M)


def lf_params(v: DPVessel) -> LFParams:
    """SI parameters of eq. 8 from the bis vessel (conversions of eqs. 26–28)."""
    b = v.bis
    return LFParams(M=b.M_from_bis(v.M), D=b.D_from_bis(v.D), arms=np.asarray(v.arms) * b.L,
                    K=b.K_from_bis(v.K), p0=np.asarray(v.p0))


#: State of the LF simulation model: position/heading, velocities, current (body frame, eq. 8).
LF_STATES = ("x", "y", "psi", "u", "v", "r", "u_c", "v_c", "r_c")
#: Inputs of the supply vessel: pitch ratios and azimuth angle (Trial channel names).
LF_INPUTS = ("p1", "p2", "p3", "p4", "p5", "p6", "alpha6")


def lf_dynamics(t: float, x: np.ndarray, u: np.ndarray, theta: LFParams) -> np.ndarray:
    """Eq. 8 with kinematics eq. 13: ``dx/dt`` for ``x = [η, ν, ν_c]`` (SI).

    ``u = [p1 … p6, α6]`` or ``[p1 … p6, α6, w_X, w_Y, w_N]`` with an external
    generalised force ``w`` (N, N, N m), the disturbance term of eq. 8. The current
    ``ν_c`` is a state with zero derivative ("slowly varying", §2.2).
    """
    eta, nu, nuc = x[0:3], x[3:6], x[6:9]
    uc = control_vector(u[:6], theta.p0)
    T = configuration_matrix(theta.arms, u[6])
    tau = T @ (theta.K * uc)
    if u.size > 7:
        tau = tau + u[7:10]
    rhs = tau - coriolis_times_nu(theta.M, nu) - theta.D @ (nu - nuc)
    return np.concatenate([rotation(eta[2]) @ nu, theta.Minv @ rhs, np.zeros(3)])


def ship_model(vessel):
    """The :class:`shipid.models.ship_model.ShipModel` of a DP vessel (``"supply"``).

    Inputs ``p1..p6`` (pitch ratios) and ``alpha6`` (rad); states ``x, y, psi, u, v, r,
    u_c, v_c, r_c`` (SI). Outputs the Trial channels ``x, y, psi, u, v, r``.
    """

    v = vessel if isinstance(vessel, DPVessel) else dp_vessel(vessel)
    par = lf_params(v)

    def x0(speed: float) -> np.ndarray:
        s = np.zeros(9)
        s[3] = speed
        return s

    def outputs(t, X, U):
        X = np.asarray(X)
        return {n: X[:, i] for i, n in enumerate(LF_STATES[:6])}

    return ShipModel(name=v.name, f=lf_dynamics, theta=par, state_names=LF_STATES,
                     input_names=LF_INPUTS, x0=x0, outputs=outputs, service_speed=0.0,
                     heading_index=2)


# ---------------------------------------------------------------------------------------------
# Momentum form, eqs. 34–38 (bis), for estimation
# ---------------------------------------------------------------------------------------------
#: State of one trial in the momentum model (eqs. 41–42): x_i = [h, η, b_h].
MOMENTUM_STATES = ("h_u", "h_v", "h_r", "x", "y", "psi", "b_u", "b_v", "b_r")


def momentum_rhs(x: np.ndarray, uc: np.ndarray, alpha: float, M: np.ndarray, Minv: np.ndarray,
                 A_h: np.ndarray, K: np.ndarray, arms: np.ndarray) -> np.ndarray:
    """Right-hand side of eqs. 35–37 (bis) for ``x = [h, η, b_h]`` (9,), ``uc`` of eq. 5."""
    h, psi, b = x[0:3], x[5], x[6:9]
    nu = Minv @ h
    T = configuration_matrix(arms, alpha)
    hdot = -coriolis_times_nu(M, nu) + A_h @ h + T @ (K * uc) + b
    return np.concatenate([hdot, rotation(psi) @ nu, np.zeros(3)])


def momentum_jacobian(x: np.ndarray, uc: np.ndarray, alpha: float, M: np.ndarray, Minv: np.ndarray,
                      A_h: np.ndarray, K: np.ndarray, arms: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Jacobians of :func:`momentum_rhs`: ``(∂f/∂x (9×9), ∂f/∂θ (9×9))`` with θ = θ1..θ9 (eqs. 46–47)."""
    h, psi = x[0:3], x[5]
    nu = Minv @ h
    Fx = np.zeros((9, 9))
    Fx[0:3, 0:3] = A_h - coriolis_times_nu_jacobian(M, nu) @ Minv
    Fx[0, 6] = Fx[1, 7] = Fx[2, 8] = 1.0
    c, s = np.cos(psi), np.sin(psi)
    Fx[3, 0:3] = c * Minv[0] - s * Minv[1]
    Fx[4, 0:3] = s * Minv[0] + c * Minv[1]
    Fx[5, 0:3] = Minv[2]
    Fx[3, 5] = -s * nu[0] - c * nu[1]
    Fx[4, 5] = c * nu[0] - s * nu[1]
    Ft = np.zeros((9, 9))
    # eq. 46: θ1 = A_h[1,1], θ2 = A_h[2,2], θ3 = A_h[2,3], θ4 = A_h[3,2], θ5 = A_h[3,3]
    Ft[0, 0], Ft[1, 1], Ft[1, 2], Ft[2, 3], Ft[2, 4] = h[0], h[1], h[2], h[1], h[2]
    # eq. 47 with the columns of eq. 7: θ6 (u1, u2), θ7 (u3, u4), θ8 (u5), θ9 (u6 at α)
    l1, l2, l3, l4, l5, l6 = arms
    Ft[0, 5] = uc[0] + uc[1]
    Ft[2, 5] = l1 * uc[0] - l2 * uc[1]
    Ft[1, 6] = uc[2] + uc[3]
    Ft[2, 6] = -l3 * uc[2] - l4 * uc[3]
    Ft[1, 7] = uc[4]
    Ft[2, 7] = l5 * uc[4]
    ca, sa = np.cos(alpha), np.sin(alpha)
    Ft[0, 8], Ft[1, 8], Ft[2, 8] = ca * uc[5], sa * uc[5], l6 * sa * uc[5]
    return Fx, Ft


#: State of one trial with the current kept as earth-fixed states (eq. 8's ν_c):
#: x_i = [h, η, b_h, V_x, V_y].
MOMENTUM_CURRENT_STATES = MOMENTUM_STATES + ("Vc_x", "Vc_y")


def momentum_current_rhs(x: np.ndarray, uc: np.ndarray, alpha: float, M: np.ndarray, Minv: np.ndarray,
                         A_h: np.ndarray, K: np.ndarray, arms: np.ndarray) -> np.ndarray:
    """Eqs. 35–38 with the current of eq. 8 as earth-fixed states, ``x = [h, η, b_h, V_c]`` (11,).

    With ``A_h = −D M⁻¹`` the current term of eq. 8, ``+D ν_c``, becomes ``−A_h M ν_c`` with
    ``ν_c = J(ψ)ᵀ [V_x, V_y, 0]`` (a current fixed in the earth frame turns in the body frame
    as the heading changes; a body-fixed bias b_h alone cannot follow that without a large
    random walk, which then swallows thrust information). ``ḣ = −C(ν)ν + A_h (h − M ν_c)
    + T K u + b_h``; ``V̇_c = 0``.
    """
    psi = x[5]
    nuc = rotation(psi).T @ np.array([x[9], x[10], 0.0])
    f9 = momentum_rhs(x[:9], uc, alpha, M, Minv, A_h, K, arms)
    f9[0:3] -= A_h @ (M @ nuc)
    return np.concatenate([f9, [0.0, 0.0]])


def momentum_current_jacobian(x: np.ndarray, uc: np.ndarray, alpha: float, M: np.ndarray, Minv: np.ndarray,
                              A_h: np.ndarray, K: np.ndarray, arms: np.ndarray
                              ) -> tuple[np.ndarray, np.ndarray]:
    """Jacobians of :func:`momentum_current_rhs`: ``(∂f/∂x (11×11), ∂f/∂θ (11×9))``."""
    psi = x[5]
    Vc = np.array([x[9], x[10], 0.0])
    nuc = rotation(psi).T @ Vc
    Fx9, Ft9 = momentum_jacobian(x[:9], uc, alpha, M, Minv, A_h, K, arms)
    Fx = np.zeros((11, 11))
    Fx[:9, :9] = Fx9
    AM = A_h @ M
    Fx[0:3, 5] -= AM @ (rotation_dpsi(psi).T @ Vc)
    Fx[0:3, 9:11] = -AM @ rotation(psi).T[:, :2]
    Ft = np.zeros((11, 9))
    Ft[:9] = Ft9
    w = M @ nuc
    for i, (r, c) in _AH_INDEX.items():
        Ft[r, i] -= w[c]
    return Fx, Ft


# ---------------------------------------------------------------------------------------------
# Derived DP control model, eqs. 50–52
# ---------------------------------------------------------------------------------------------
def derived_A(M: np.ndarray, A_h: np.ndarray) -> np.ndarray:
    """``A'' = M''⁻¹ A_h M''`` (eq. 50), i.e. ``−M⁻¹ D`` with ``A_h = −D M⁻¹``."""
    return np.linalg.solve(M, A_h @ M)


def derived_B(M: np.ndarray, T: np.ndarray, K: np.ndarray) -> np.ndarray:
    """``B'' = M''⁻¹ T'' K''`` (eq. 50, ERRATA reading; 3 × r)."""
    return np.linalg.solve(M, np.asarray(T) * np.asarray(K)[None, :])


__all__ = ["THETA_NAMES", "THETA_MEANING", "DPVessel", "dp_vessel", "matrices_from_theta",
           "theta_from_matrices", "coriolis", "coriolis_times_nu", "coriolis_times_nu_jacobian",
           "rotation", "rotation_dpsi", "LFParams", "lf_params", "LF_STATES", "LF_INPUTS", "lf_dynamics",
           "ship_model", "MOMENTUM_STATES", "momentum_rhs", "momentum_jacobian", "MOMENTUM_CURRENT_STATES",
           "momentum_current_rhs", "momentum_current_jacobian", "derived_A", "derived_B"]
