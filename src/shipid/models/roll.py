"""Linearised surge–sway–roll–yaw model and IMU measurement model (Linder et al. 2015, eqs. 8–14).

State ``x = [phi, psi, v, p, r]`` (roll, yaw, sway velocity, roll rate, yaw rate; SNAME body axes,
z down), input ``u = [delta]`` (rudder, rad), constant surge speed ``U``. The model is

    M~ x' = A x + b delta + e tau                                   (11)

with the inertia matrix (12), the linearised hydrodynamics (13) and the rudder column (14). The
nominal mass ``M`` sits at ``z_g`` and the load mass ``m`` at ``z_m``; both are measured from the
centre of rotation, ``z_g = zg_bar + z_f`` and ``z_m = zm_bar + z_f`` (24). The process disturbance
``tau`` enters the roll equation (18) only (our reading: the paper's τ is a roll moment in (18)–(25)).

Restoring moment: ``-(k + M g z_g + m g z_m) phi`` (eq. 17a rearranged), roll damping ``-d p``
(17b), yaw coupling ``(K_ur + M z_g + m z_m) U r`` (15).

IMU (eqs. 8–9): the tangential acceleration at the IMU is

    a_s = z_s p' + g phi - v' - U r,   z_s = zs_bar + z_f           (8), (19), (20)

and the gyros measure the roll rate ``p`` and the yaw rate ``r`` (SNAME sign, see ERRATA on 9c).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.linalg import expm

from shipid.models.ship_model import ShipModel
from shipid.vessels import Vessel, load_vessel

STATE_NAMES = ("phi", "psi", "v", "p", "r")


@dataclass(frozen=True)
class RollShipParams:
    """Physical parameters of the linear model (11) for one loading condition.

    Symbols follow Linder et al. (2015) Table 2; ``m, zm_bar`` are the load of this condition
    (0, 0 for the nominal dataset; ``m_c, zc_bar`` for calibration).
    """

    U: float
    M: float
    zg_bar: float
    m: float
    zm_bar: float
    z_f: float
    zs_bar: float
    g: float
    Y_vdot: float
    Y_pdot: float
    Y_rdot: float
    Y_phiuu: float
    Y_uv: float
    Y_ur: float
    K_vdot: float
    A_x: float
    K_rdot: float
    k: float
    d: float
    K_ur: float
    K_uv: float
    N_vdot: float
    N_pdot: float
    A_z: float
    N_ur: float
    N_phiuu: float
    N_p: float
    N_uv: float
    C2: float
    z_r: float
    x_r: float

    @property
    def z_g(self) -> float:
        return self.zg_bar + self.z_f

    @property
    def z_m(self) -> float:
        return self.zm_bar + self.z_f

    @property
    def z_s(self) -> float:
        return self.zs_bar + self.z_f

    @property
    def K_delta(self) -> float:
        """K_delta = -z_r C_2 (17c)."""
        return -self.z_r * self.C2

    @property
    def K_r(self) -> float:
        """Lumped K_r = (K_ur - K_vdot) U (below eq. 22)."""
        return (self.K_ur - self.K_vdot) * self.U

    def loaded(self, m: float, zm_bar: float) -> "RollShipParams":
        """The same ship with another load (m at zm_bar)."""
        return replace(self, m=float(m), zm_bar=float(zm_bar))


def params_from_vessel(vessel: Vessel | str = "fishing-vessel", condition: str = "loaded") -> RollShipParams:
    """Build :class:`RollShipParams` from a packaged vessel.

    Parameters
    ----------
    vessel : Vessel or str
    condition : {"nominal", "calibration", "loaded"}
        Which load to put aboard: none, ``(m_c, zc_bar)`` or ``(m, zm_bar)`` (§3.1, §5).
    """
    v = load_vessel(vessel) if isinstance(vessel, str) else vessel
    vals: dict[str, float] = {}
    for sec in ("general", "sway", "roll", "yaw", "rudder"):
        vals.update({k: float(x) for k, x in v.values(sec).items()})
    m_c, zc = vals.pop("m_c"), vals.pop("zc_bar")
    if condition == "nominal":
        vals["m"], vals["zm_bar"] = 0.0, 0.0
    elif condition == "calibration":
        vals["m"], vals["zm_bar"] = m_c, zc
    elif condition != "loaded":
        raise ValueError(f"condition must be nominal, calibration or loaded, not {condition!r}")
    fields = RollShipParams.__dataclass_fields__
    return RollShipParams(**{k: vals[k] for k in fields})


def system_matrices(th: RollShipParams) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Matrices of (11): ``(Mt, A, b, e)`` with ``Mt x' = A x + b delta + e tau``.

    Mt is (12), A is (13) with the ERRATA signs already in the vessel values, b is (14).
    """
    U, M, m = th.U, th.M, th.m
    zg, zm = th.z_g, th.z_m
    Mz = M * zg + m * zm
    A1 = th.A_x + M * zg**2 + m * zm**2                                  # (16)
    Mt = np.array([
        [1.0, 0, 0, 0, 0],
        [0, 1.0, 0, 0, 0],
        [0, 0, M + m - th.Y_vdot, -Mz - th.Y_pdot, -th.Y_rdot],
        [0, 0, -Mz - th.K_vdot, A1, -th.K_rdot],
        [0, 0, -th.N_vdot, -th.N_pdot, th.A_z],
    ])
    aU = abs(U)
    A = np.array([
        [0, 0, 0, 1.0, 0],
        [0, 0, 0, 0, 1.0],
        [th.Y_phiuu * U**2, 0, th.Y_uv * aU, 0, (th.Y_ur - M - m) * U],
        [-(th.k + M * th.g * zg + m * th.g * zm), 0, th.K_uv * aU, -th.d, (th.K_ur + Mz) * U],
        [th.N_phiuu * U * aU, 0, th.N_uv * aU, th.N_p, th.N_ur * aU],
    ])
    b = np.array([0, 0, th.C2, th.K_delta, th.x_r * th.C2])
    e = np.array([0, 0, 0, 1.0, 0])
    return Mt, A, b, e


def state_space(th: RollShipParams) -> tuple[np.ndarray, np.ndarray]:
    """Explicit form ``x' = Ac x + Bc [delta, tau]``."""
    Mt, A, b, e = system_matrices(th)
    Ac = np.linalg.solve(Mt, A)
    Bc = np.linalg.solve(Mt, np.column_stack([b, e]))
    return Ac, Bc


def dynamics(t: float, x: np.ndarray, u: np.ndarray, theta: RollShipParams) -> np.ndarray:
    """``f(t, x, u, theta)`` of (11) with ``u = [delta]`` or ``[delta, tau]``."""
    Ac, Bc = state_space(theta)
    uu = np.zeros(2)
    uu[: np.size(u)] = np.ravel(u)[:2]
    return Ac @ x + Bc @ uu


def imu_outputs(th: RollShipParams, X: np.ndarray, Xdot: np.ndarray) -> dict[str, np.ndarray]:
    """True IMU signals (8)–(9) from states ``X`` (n, 5) and their derivatives ``Xdot`` (n, 5).

    Returns ``p`` (roll rate), ``a_s`` (tangential acceleration, eq. 8 with a_y = v' + U r, eq. 19)
    and ``r`` (yaw rate, SNAME sign).
    """
    phi, p, r = X[:, 0], X[:, 3], X[:, 4]
    vdot, pdot = Xdot[:, 2], Xdot[:, 3]
    a_s = th.z_s * pdot + th.g * phi - vdot - th.U * r
    return {"phi": phi, "p": p, "a_s": a_s, "r": r, "v": X[:, 2], "psi": X[:, 1]}


def simulate_zoh(th: RollShipParams, delta: np.ndarray, dt: float, tau: np.ndarray | None = None,
                 x0: np.ndarray | None = None, hold: str = "foh") -> tuple[np.ndarray, np.ndarray]:
    """Exact sampled simulation of (11) on a uniform grid.

    ``hold="foh"`` (default): inputs vary linearly between samples (a rate-limited rudder, a smooth
    wave moment); ``hold="zoh"``: held constant over each interval. The discretisation is the matrix
    exponential of the augmented system, so there is no integration error either way.

    Returns
    -------
    X, Xdot : ndarray (n, 5)
        States at the sample instants and their time derivatives (with the input at that instant),
        as needed by :func:`imu_outputs`.
    """
    delta = np.asarray(delta, dtype=float)
    n = delta.size
    tau = np.zeros(n) if tau is None else np.asarray(tau, dtype=float)
    Ac, Bc = state_space(th)
    nx, nu = Ac.shape[0], Bc.shape[1]
    U = np.column_stack([delta, tau])
    if hold == "zoh":
        big = np.zeros((nx + nu, nx + nu))
        big[:nx, :nx], big[:nx, nx:] = Ac, Bc
        E = expm(big * dt)
        Ad, B0, B1 = E[:nx, :nx], E[:nx, nx:], np.zeros((nx, nu))
    elif hold == "foh":
        # [x; u; u'] with u' constant over the interval (Franklin, Powell & Workman, FOH / triangle hold)
        big = np.zeros((nx + 2 * nu, nx + 2 * nu))
        big[:nx, :nx], big[:nx, nx:nx + nu] = Ac, Bc
        big[nx:nx + nu, nx + nu:] = np.eye(nu)
        E = expm(big * dt)
        Ad, G1, G2 = E[:nx, :nx], E[:nx, nx:nx + nu], E[:nx, nx + nu:] / dt
        B0, B1 = G1 - G2, G2                      # x_{k+1} = Ad x_k + B0 u_k + B1 u_{k+1}
    else:
        raise ValueError("hold must be 'foh' or 'zoh'")
    X = np.zeros((n, nx))
    x = np.zeros(nx) if x0 is None else np.asarray(x0, dtype=float)
    Unext = np.vstack([U[1:], U[-1:]])
    BU = U @ B0.T + Unext @ B1.T
    for i in range(n):
        X[i] = x
        x = Ad @ x + BU[i]
    Xdot = X @ Ac.T + U @ Bc.T
    return X, Xdot


def ship_model(vessel: Vessel | str = "fishing-vessel"):
    """The :class:`shipid.models.ship_model.ShipModel` of the fishing vessel (loaded condition).

    The state is ``[phi, psi, v, p, r]`` of (11); earth-fixed position is not part of the linear
    model. Outputs are the Trial channels ``phi, psi, v, p, r, a_s, u, delta``.
    """

    v = load_vessel(vessel) if isinstance(vessel, str) else vessel
    th = params_from_vessel(v, "loaded")

    def outputs(t: np.ndarray, X: np.ndarray, Uin: np.ndarray) -> dict[str, np.ndarray]:
        X = np.atleast_2d(X)
        Uin = np.asarray(Uin, dtype=float).reshape(X.shape[0], -1)
        Xdot = np.array([dynamics(ti, xi, ui, th) for ti, xi, ui in zip(t, X, Uin)])
        out = imu_outputs(th, X, Xdot)
        out["u"] = np.full(X.shape[0], th.U)
        out["delta"] = Uin[:, 0]
        return out

    return ShipModel(
        name=v.name, f=dynamics, theta=th, state_names=STATE_NAMES, input_names=("delta",),
        x0=lambda speed: np.zeros(5), outputs=outputs, service_speed=th.U, heading_index=1,
        rudder_limit=np.deg2rad(35.0), rudder_rate_limit=np.deg2rad(20.0),
    )


__all__ = ["RollShipParams", "params_from_vessel", "system_matrices", "state_space", "dynamics",
           "imu_outputs", "simulate_zoh", "ship_model", "STATE_NAMES"]
