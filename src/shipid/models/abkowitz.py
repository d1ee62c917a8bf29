"""Modified Abkowitz manoeuvring model of Hwang (1980) with current (Yoon & Rhee 2003).

Equations of motion (eq. 1, written in relative velocities after eq. 2)::

    M [u̇_r, v̇_r, ṙ]ᵀ = [ m(v_r r + x_G r²) + X,
                         −m u_r r + Y,
                         −m x_G u_r r + N ]

with ``M`` the rigid-body plus added-mass inertia matrix, and the kinematics
(eq. 3) ``ẋ = u cos ψ − v sin ψ``, ``ẏ = u sin ψ + v cos ψ``, ``ψ̇ = r`` in
absolute velocities ``u = u_r + U_c cos(ψ − ψ_c)``, ``v = v_r − U_c sin(ψ − ψ_c)``
(eq. 2, ``ψ_c`` the direction the current sets towards).

Hydrodynamic forces without the added-mass part (eqs. 12–14)::

    X = H_X θ_X,   Y = H_Y θ_Y,   N = H_N θ_N,   H_N = L H_Y

with the coefficient vectors of eq. 13 and the regressors of eqs. 14–15. The
sway regressor list is garbled in the paper's text; our reading (9 entries, every
one of dimension velocity², matching the 9 coefficients of θ_Y)::

    h_Y = [ (u_A∞/2)², U_r v_r, L U_r r, v_r³/U_r, L v_r² r/U_r, L² v_r r²/U_r,
            L³ r³/U_r, (c − c₀)(L r/2 − v_r) + c² δ, c² e³ ]

and ``h_X = [u_r², L n u_r, L² n², v_r², L v_r r, L² r², L² v_r² r²/U_r², c² e²]``.

The rudder-inflow quantities are not defined in the paper; we use actuator-disc
momentum theory with the propeller of the vessel file (state the reading):

* ``u_a = (1 − w) u_r`` (advance speed), ``J = u_a / (n D)``,
  ``K_T = kt0 + kt1 J + kt2 J²`` (clipped at 0);
* ``u_A∞ = sqrt(u_a² + (8/π) K_T (n D)²)`` — the fully developed slipstream speed;
* ``c = (u_a + u_A∞)/2`` — the speed at the propeller disc, taken as the rudder
  inflow speed; ``c₀`` is its value in the straight run at (U0, n0);
* effective rudder angle ``e = δ + (L r/2 − v_r)/c`` (rudder at x = −L/2), so that
  ``c² e − c₀ (L r/2 − v_r)`` is exactly the Y'_δ regressor above.

These choices make the simulated "true" ship and the regression model of step 2
share one structure, as in Yoon & Rhee's simulation study (§5.1).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from shipid.models.ship_model import ShipModel
from shipid.vessels import Vessel, load_vessel

KNOT = 1852.0 / 3600.0

#: Coefficient names of eq. 13, in order.
THETA_X_NAMES = ("eta_CR", "eta_2", "eta_3", "X_vv", "X_vr", "X_rr", "X_vvrr", "X_ee")
THETA_Y_NAMES = ("Y_0", "Y_v", "Y_r", "Y_vvv", "Y_vvr", "Y_vrr", "Y_rrr", "Y_delta", "Y_eee")
THETA_N_NAMES = ("N_0", "N_v", "N_r", "N_vvv", "N_vvr", "N_vrr", "N_rrr", "N_delta", "N_eee")
#: Regressor names (eqs. 14–15), for tables.
REGRESSORS_X = ("u^2", "Lnu", "L^2n^2", "v^2", "Lvr", "L^2r^2", "L^2v^2r^2/U^2", "c^2e^2")
REGRESSORS_Y = ("(uA/2)^2", "Uv", "LUr", "v^3/U", "Lv^2r/U", "L^2vr^2/U", "L^3r^3/U",
                "rudder", "c^2e^3")

STATE_NAMES = ("u_r", "v_r", "r", "x", "y", "psi")


@dataclass(frozen=True)
class AbkowitzParams:
    """Parameters of the modified Abkowitz model (SI; coefficients non-dimensional).

    Attributes
    ----------
    L, rho, m, x_G, I_z : float
        Length (m), water density (kg/m³), mass (kg), centre of gravity forward of
        the body origin (m), yaw inertia (kg m²).
    X_udot, Y_vdot, Y_rdot, N_vdot, N_rdot : float
        Added-mass derivatives (SI, SNAME signs).
    D, w, kt : float, float, tuple
        Propeller diameter (m), wake fraction, K_T(J) polynomial coefficients.
    theta_X, theta_Y, theta_N : tuple of float
        Coefficient vectors of eq. 13 (primes by ρ/2 L² and ρ/2 L³).
    U0, n0, c0 : float
        Approach speed (m/s), propeller rate (1/s) balancing it, and the rudder
        inflow speed in that straight run (m/s).
    current_speed, current_dir : float
        U_c (m/s) and ψ_c (rad) of eq. 2.
    yaw_rudder_variant : bool
        Use the simplified yaw rudder regressors of eq. 22 (``U_r² δ``, ``U_r² e³``).
    """

    L: float
    rho: float
    m: float
    x_G: float
    I_z: float
    X_udot: float
    Y_vdot: float
    Y_rdot: float
    N_vdot: float
    N_rdot: float
    D: float
    w: float
    kt: tuple[float, float, float]
    theta_X: tuple[float, ...]
    theta_Y: tuple[float, ...]
    theta_N: tuple[float, ...]
    U0: float
    n0: float
    c0: float
    current_speed: float = 0.0
    current_dir: float = 0.0
    yaw_rudder_variant: bool = False

    @property
    def mass_matrix(self) -> np.ndarray:
        """Inertia matrix M of eq. 6 (rigid body + added mass), 3×3."""
        return np.array([[self.m - self.X_udot, 0.0, 0.0],
                         [0.0, self.m - self.Y_vdot, self.m * self.x_G - self.Y_rdot],
                         [0.0, self.m * self.x_G - self.N_vdot, self.I_z - self.N_rdot]])

    @property
    def current_xy(self) -> tuple[float, float]:
        """Earth-fixed current components (c_x, c_y) (m/s)."""
        return (self.current_speed * np.cos(self.current_dir),
                self.current_speed * np.sin(self.current_dir))

    def with_current(self, speed: float, direction: float) -> "AbkowitzParams":
        """A copy with current ``speed`` (m/s) setting towards ``direction`` (rad)."""
        return replace(self, current_speed=float(speed), current_dir=float(direction))

    def with_theta(self, theta_X=None, theta_Y=None, theta_N=None) -> "AbkowitzParams":
        """A copy with other coefficient vectors (e.g. identified ones, for validation)."""
        return replace(self,
                       theta_X=self.theta_X if theta_X is None else tuple(map(float, theta_X)),
                       theta_Y=self.theta_Y if theta_Y is None else tuple(map(float, theta_Y)),
                       theta_N=self.theta_N if theta_N is None else tuple(map(float, theta_N)))


# -- propeller / rudder inflow -----------------------------------------------------------
def rudder_inflow(u_r, n, p: AbkowitzParams):
    """Slipstream speed ``u_A∞`` and rudder inflow speed ``c`` (momentum theory; module docstring).

    Works elementwise on arrays.
    """
    u_r = np.asarray(u_r, dtype=float)
    n = np.asarray(n, dtype=float)
    ua = (1.0 - p.w) * u_r
    nD = n * p.D
    with np.errstate(divide="ignore", invalid="ignore"):
        J = np.where(np.abs(nD) > 1e-9, ua / np.where(np.abs(nD) > 1e-9, nD, 1.0), 0.0)
    kt = np.maximum(p.kt[0] + p.kt[1] * J + p.kt[2] * J * J, 0.0)
    uA = np.sqrt(ua * ua + (8.0 / np.pi) * kt * nD * nD)
    c = 0.5 * (ua + uA)
    return uA, c


def regressors(u_r, v_r, r, delta, n, p: AbkowitzParams):
    """Regressor matrices ``H_X`` (N, 8), ``H_Y`` (N, 9), ``H_N`` (N, 9) of eq. 14.

    Includes the factors ρ/2 L² (and L for ``H_N``), so that ``X = H_X @ θ_X`` is in N.
    With ``p.yaw_rudder_variant`` the last two columns of ``H_N`` are those of eq. 22
    (``U_r² δ`` and ``U_r² e³``).
    """
    u_r, v_r, r, delta, n = (np.atleast_1d(np.asarray(a, dtype=float)) for a in (u_r, v_r, r, delta, n))
    L = p.L
    U2 = u_r * u_r + v_r * v_r
    U = np.sqrt(U2)
    Us = np.maximum(U, 1e-6)
    uA, c = rudder_inflow(u_r, n, p)
    cs = np.maximum(c, 1e-6)
    trans = 0.5 * L * r - v_r
    e = delta + trans / cs
    q = 0.5 * p.rho * L * L
    HX = q * np.column_stack([u_r * u_r, L * n * u_r, L * L * n * n, v_r * v_r, L * v_r * r,
                              L * L * r * r, L * L * v_r * v_r * r * r / np.maximum(U2, 1e-12),
                              c * c * e * e])
    HY = q * np.column_stack([(0.5 * uA) ** 2, U * v_r, L * U * r, v_r ** 3 / Us,
                              L * v_r * v_r * r / Us, L * L * v_r * r * r / Us, L ** 3 * r ** 3 / Us,
                              (c - p.c0) * trans + c * c * delta, c * c * e ** 3])
    HN = L * HY
    if p.yaw_rudder_variant:
        HN = HN.copy()
        HN[:, 7] = q * L * U2 * delta
        HN[:, 8] = q * L * U2 * e ** 3
    return HX, HY, HN


def forces(u_r, v_r, r, delta, n, p: AbkowitzParams):
    """Hydrodynamic X, Y (N) and N (N m) without the added-mass part (eq. 12)."""
    HX, HY, HN = regressors(u_r, v_r, r, delta, n, p)
    return HX @ np.asarray(p.theta_X), HY @ np.asarray(p.theta_Y), HN @ np.asarray(p.theta_N)


def rigid_body_rhs(u_r, v_r, r, X, Y, N, p: AbkowitzParams):
    """Right-hand side of eq. 6's first three rows (before M⁻¹)."""
    m, xg = p.m, p.x_G
    return np.array([m * (v_r * r + xg * r * r) + X, -m * u_r * r + Y, -m * xg * u_r * r + N])


def make_dynamics(p: AbkowitzParams):
    """Return ``f(t, x, u, theta)`` for state ``[u_r, v_r, r, x, y, ψ]`` and input ``[δ, n]``.

    ``theta`` passed at call time is used (an :class:`AbkowitzParams`); ``M⁻¹`` is cached
    per parameter object.
    """
    # the cache holds the parameter object itself, so an identity test is safe
    cache: dict[str, object] = {"theta": None, "Minv": None}

    def f(t, x, u, theta):
        th = p if theta is None else theta
        if cache["theta"] is not th:
            cache["theta"] = th
            cache["Minv"] = np.linalg.inv(th.mass_matrix)
        Minv = cache["Minv"]
        ur, vr, r, _, _, psi = x
        delta = u[0]
        n = u[1] if len(u) > 1 else th.n0
        X, Y, N = forces(ur, vr, r, delta, n, th)
        acc = Minv @ rigid_body_rhs(ur, vr, r, X[0], Y[0], N[0], th)
        cx, cy = th.current_xy
        cp, sp = np.cos(psi), np.sin(psi)
        return np.array([acc[0], acc[1], acc[2],
                         ur * cp - vr * sp + cx, ur * sp + vr * cp + cy, r])

    return f


def dynamics(t, x, u, theta: AbkowitzParams):
    """``f(t, x, u, θ)`` of eqs. 1–3 (uncached ``M⁻¹``; see :func:`make_dynamics`)."""
    ur, vr, r, _, _, psi = x
    n = u[1] if len(u) > 1 else theta.n0
    X, Y, N = forces(ur, vr, r, u[0], n, theta)
    acc = np.linalg.solve(theta.mass_matrix, rigid_body_rhs(ur, vr, r, X[0], Y[0], N[0], theta))
    cx, cy = theta.current_xy
    cp, sp = np.cos(psi), np.sin(psi)
    return np.array([acc[0], acc[1], acc[2], ur * cp - vr * sp + cx, ur * sp + vr * cp + cy, r])


def absolute_velocities(u_r, v_r, psi, p: AbkowitzParams):
    """Body-fixed velocities over ground (eq. 2 inverted)."""
    psic = np.asarray(psi) - p.current_dir
    return u_r + p.current_speed * np.cos(psic), v_r - p.current_speed * np.sin(psic)


def outputs(t, X, U, p: AbkowitzParams) -> dict[str, np.ndarray]:
    """Noise-free Trial channels from state and input histories.

    ``x, y`` body origin (midships) earth-fixed; ``u, v`` over ground; ``u_r, v_r``
    through the water; ``U`` the speed-log reading ``u_r`` (no lever arm);
    ``x_dot, y_dot`` earth-fixed velocity of the origin; ``X, Y, N`` the hydrodynamic
    forces of eq. 12 (true values, for checking step 1).
    """
    X = np.atleast_2d(X)
    U = np.atleast_2d(U)
    ur, vr, r, x, y, psi = X.T
    delta = U[:, 0]
    n = U[:, 1] if U.shape[1] > 1 else np.full_like(delta, p.n0)
    u, v = absolute_velocities(ur, vr, psi, p)
    Fx, Fy, Fn = forces(ur, vr, r, delta, n, p)
    cx, cy = p.current_xy
    return {"x": x, "y": y, "psi": psi, "u": u, "v": v, "r": r, "u_r": ur, "v_r": vr, "U": ur,
            "x_dot": ur * np.cos(psi) - vr * np.sin(psi) + cx,
            "y_dot": ur * np.sin(psi) + vr * np.cos(psi) + cy,
            "delta": delta, "n": n, "X": Fx, "Y": Fy, "N": Fn}


# -- parameters from the vessel file -----------------------------------------------------
def service_rpm(U0: float, thX, L: float) -> float:
    """Propeller rate n0 (1/s) with zero surge force in the straight run at U0 (eq. 14, e = v = r = 0)."""
    a, b, c = thX[2], thX[1], thX[0]  # eta_3 s² + eta_2 s + eta_CR = 0 with s = L n / u
    disc = b * b - 4.0 * a * c
    if a == 0.0 or disc < 0.0:
        raise ValueError("no straight-run propeller rate balances the resistance")
    s = (-b + np.sqrt(disc)) / (2.0 * a)
    return float(s * U0 / L)


def particulars_from_vessel(vessel: Vessel | str = "esso-osaka") -> AbkowitzParams:
    """What a user knows of the ship, without any hydrodynamic coefficient of eq. 13.

    Mass, inertia and centre of gravity ([particulars]), the added masses of eq. 6
    ([added_mass]; EBM takes M as known, Yoon & Rhee 2003, §2) and the propeller particulars
    used by the rudder-inflow model ([propulsion]). ``theta_X/Y/N`` are NaN and so are
    the approach condition ``U0, n0, c0``: identification must take those from the
    trial (:func:`with_approach`), never from the packaged Table 3 — any use of a
    packaged coefficient would turn the estimate into NaN.
    """
    v = load_vessel(vessel) if isinstance(vessel, str) else vessel
    P = v.values("particulars")
    A = v.values("added_mass")
    R = v.values("propulsion")
    nan = float("nan")
    return AbkowitzParams(L=float(P["L"]), rho=float(P["rho"]), m=float(P["m"]), x_G=float(P["x_G"]),
                          I_z=float(P["I_z"]), X_udot=float(A["X_udot"]), Y_vdot=float(A["Y_vdot"]),
                          Y_rdot=float(A["Y_rdot"]), N_vdot=float(A["N_vdot"]), N_rdot=float(A["N_rdot"]),
                          D=float(R["D"]), w=float(R["w"]),
                          kt=(float(R["kt0"]), float(R["kt1"]), float(R["kt2"])),
                          theta_X=(nan,) * len(THETA_X_NAMES), theta_Y=(nan,) * len(THETA_Y_NAMES),
                          theta_N=(nan,) * len(THETA_N_NAMES), U0=nan, n0=nan, c0=nan)


def with_approach(p: AbkowitzParams, U0: float, n0: float) -> AbkowitzParams:
    """A copy with the approach condition (speed ``U0`` m/s through the water, propeller rate
    ``n0`` 1/s) and the rudder inflow speed ``c0`` it gives (module docstring)."""
    base = replace(p, U0=float(U0), n0=float(n0), c0=1.0)
    _, c0 = rudder_inflow(float(U0), float(n0), base)
    return replace(base, c0=float(c0))


def params_from_vessel(vessel: Vessel | str = "esso-osaka") -> AbkowitzParams:
    """The simulator's ship: :func:`particulars_from_vessel` plus the packaged coefficients of
    [abkowitz] (Table 3) and the approach at [particulars].U0 with the propeller rate that
    balances it (:func:`service_rpm`). For simulation and for comparing with the truth only;
    identification uses :func:`particulars_from_vessel`."""
    v = load_vessel(vessel) if isinstance(vessel, str) else vessel
    C = v.values("abkowitz")
    thX = tuple(float(C[k]) for k in THETA_X_NAMES)
    thY = tuple(float(C[k]) for k in THETA_Y_NAMES)
    thN = tuple(float(C[k]) for k in THETA_N_NAMES)
    base = replace(particulars_from_vessel(v), theta_X=thX, theta_Y=thY, theta_N=thN)
    U0 = float(v.value("particulars", "U0"))
    return with_approach(base, U0, service_rpm(U0, thX, base.L))


def with_coefficients(p: AbkowitzParams, theta_X, theta_Y, theta_N) -> AbkowitzParams:
    """Another ship of the same hull particulars: coefficients ``theta_*`` and the approach at
    ``p.U0`` with the propeller rate that balances them (a perturbed "unknown" ship)."""
    q = p.with_theta(theta_X, theta_Y, theta_N)
    return with_approach(q, p.U0, service_rpm(p.U0, q.theta_X, p.L))


def trial_conditions(vessel: Vessel | str = "esso-osaka") -> dict[str, float]:
    """The §5.1 trial conditions in SI: current, noise levels of eq. 19, sensor positions."""
    v = load_vessel(vessel) if isinstance(vessel, str) else vessel
    T = v.values("trials")
    return {"current_speed": float(T["current_speed"]) * KNOT,
            "current_dir": float(np.deg2rad(T["current_direction"])),
            "sigma_xy": float(T["sigma_xy"]), "sigma_xy_dot": float(T["sigma_xy_dot"]),
            "sigma_psi": float(np.deg2rad(T["sigma_psi"])), "sigma_u_log": float(T["sigma_u_log"]),
            "x_D": float(T["x_D"]), "y_D": float(T["y_D"]), "y_S": float(T["y_S"]), "dt": float(T["dt"])}


def ship_model(vessel: Vessel | str = "esso-osaka", *, current_speed: float = 0.0,
               current_dir: float = 0.0) -> ShipModel:
    """The :class:`ShipModel` for ESSO OSAKA (inputs δ and n; no current by default).

    Parameters
    ----------
    vessel : Vessel or str
    current_speed, current_dir : float
        U_c (m/s) and ψ_c (rad) of eq. 2; §5.1 uses 2 kn towards 45°
        (:func:`trial_conditions`).
    """
    v = load_vessel(vessel) if isinstance(vessel, str) else vessel
    p = params_from_vessel(v).with_current(current_speed, current_dir)
    S = v.values("steering")

    def x0(speed: float) -> np.ndarray:
        return np.array([float(speed), 0.0, 0.0, 0.0, 0.0, 0.0])

    def u0(speed: float) -> np.ndarray:
        # straight-run propeller rate: n0 scales with speed (eq. 14 surge balance is homogeneous)
        return np.array([0.0, p.n0 * float(speed) / p.U0])

    kwargs = dict(name=v.name, f=make_dynamics(p), theta=p, state_names=STATE_NAMES,
                  input_names=("delta", "n"), x0=x0,
                  outputs=lambda t, X, U, _p=p: outputs(t, X, U, _p),
                  service_speed=p.U0, heading_index=5,
                  rudder_limit=float(np.deg2rad(S["rudder_limit"])),
                  rudder_rate_limit=float(np.deg2rad(S["rudder_rate_limit"])))
    if "u0" in ShipModel.__dataclass_fields__:  # nominal inputs (newer ShipModel)
        kwargs["u0"] = u0
    return ShipModel(**kwargs)


__all__ = ["AbkowitzParams", "THETA_X_NAMES", "THETA_Y_NAMES", "THETA_N_NAMES", "REGRESSORS_X",
           "REGRESSORS_Y", "STATE_NAMES", "rudder_inflow", "regressors", "forces", "dynamics",
           "make_dynamics", "outputs", "params_from_vessel", "particulars_from_vessel", "with_approach",
           "with_coefficients", "service_rpm", "ship_model",
           "trial_conditions", "absolute_velocities", "KNOT"]
