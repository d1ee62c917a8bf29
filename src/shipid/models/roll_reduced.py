"""Reduced roll model of Linder et al. (2015): eqs. (18)–(26) and the bilinear discretisation (32)–(37).

With ``v'`` eliminated through the measured tangential acceleration (20), the roll equation is

    A2 phi'' = -(k - K_vdot g) phi - d phi' - (K_vdot + M z_g + m z_m) a_s + K_r r + K_delta delta + tau  (23)

    A2 = A_x + M z_g (z_g - z_s) + m z_m (z_m - z_s) - K_vdot z_s                                      (22)

with ``z_g = zg_bar + z_f``, ``z_m = zm_bar + z_f``, ``z_s = zs_bar + z_f`` (24). As a transfer function
from ``a_s + F_r r + F_delta delta`` to the roll **rate** ``y = p`` (ERRATA 000: (25) maps to p, not phi)

    G(s) = beta1 s / (s^2 + alpha1 s + alpha2),  alpha1 = d/A2,  alpha2 = (k - K_vdot g)/A2,
    beta1 = -(K_vdot + M z_g + m z_m)/A2,  gamma1 = K_delta/A2,  kappa1 = K_r/A2                         (26)

and after the bilinear transform ``s = (2/T)(q - 1)/(q + 1)`` (32)–(33)

    y_t = phi_t^T g(theta) + noise,  phi_t = [-y_{t-1}, -y_{t-2}, a_t - a_{t-2}, r_t - r_{t-2}, delta_t - delta_{t-2}]
    g = [alpha1_bar, alpha2_bar, beta0_bar, kappa0_bar, gamma0_bar]                                      (35)–(37)

The unknown physical parameters (30) are ordered as :data:`THETA_NAMES`. All functions accept
complex arrays so that exact Jacobians can be taken by complex-step differentiation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from shipid.vessels import load_vessel

#: Unknown parameters of (30), in this order.
THETA_NAMES: tuple[str, ...] = ("k", "A_x", "d", "K_r", "K_vdot", "K_delta", "z_f", "m", "zm_bar")
#: The estimator's internal parameterisation: ``m`` replaced by the load moment ``q = m (zm_bar + z_f)``.
THETA_Q_NAMES: tuple[str, ...] = THETA_NAMES[:7] + ("q", "zm_bar")
THETA_UNITS: dict[str, str] = {"k": "N*m/rad", "A_x": "kg*m^2", "d": "N*m*s/rad", "K_r": "kg*m^2/s",
                               "K_vdot": "kg*m", "K_delta": "N*m/rad", "z_f": "m", "m": "kg", "zm_bar": "m", "q": "kg*m"}
#: Names of the discrete coefficients g(theta) of (36).
G_NAMES: tuple[str, ...] = ("alpha1_bar", "alpha2_bar", "beta0_bar", "kappa0_bar", "gamma0_bar")

NOMINAL, CALIBRATION, LOADED = "nominal", "calibration", "loaded"


@dataclass(frozen=True)
class KnownParams:
    """Known parameters (§4.3): nominal mass and CM, calibration load, IMU position, g, speed."""

    U: float
    M: float
    zg_bar: float
    m_c: float
    zc_bar: float
    zs_bar: float
    g: float = 9.81

    @classmethod
    def from_vessel(cls, vessel="fishing-vessel") -> "KnownParams":
        v = load_vessel(vessel) if isinstance(vessel, str) else vessel
        s = v.values("general")
        return cls(U=s["U"], M=s["M"], zg_bar=s["zg_bar"], m_c=s["m_c"], zc_bar=s["zc_bar"],
                   zs_bar=s["zs_bar"], g=s["g"])


def condition_loads(theta, known: KnownParams, conditions, moment: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Load of each dataset: ``(q_i, zbar_i)`` with the first moment ``q_i = m_i z_mi`` about the CR.

    Nominal: ``q = 0``; calibration: ``q = m_c (zc_bar + z_f)``; loaded: from theta, where
    ``theta[7]`` is ``m`` (``moment=False``) or already ``q = m z_m`` (``moment=True``).
    """
    z_f = theta[6]
    q_i, z_i = [], []
    for c in conditions:
        if c == NOMINAL:
            q_i.append(0.0 * z_f); z_i.append(0.0 * z_f)
        elif c == CALIBRATION:
            q_i.append(known.m_c * (known.zc_bar + z_f)); z_i.append(known.zc_bar + 0.0 * z_f)
        elif c == LOADED:
            q_i.append(theta[7] if moment else theta[7] * (theta[8] + z_f)); z_i.append(theta[8] + 0.0 * z_f)
        else:
            raise ValueError(f"unknown loading condition {c!r}")
    return np.array(q_i), np.array(z_i)


def roll_terms(theta, known: KnownParams, conditions, moment: bool = False) -> dict[str, np.ndarray]:
    """Physical coefficients of (23) per dataset: ``A2`` (22), ``B = K_vdot + M z_g + m z_m``,
    ``kp = k - K_vdot g``, ``A1`` (16) and the restoring ``k1 = k + M g z_g + m g z_m`` (18).

    Written in the load moment ``q = m z_m``: ``m z_m (z_m - z_s) = q (zm_bar - zs_bar)`` and
    ``m z_m^2 = q z_m``, so the map is polynomial in ``q`` (no division by ``z_m``). With
    ``moment=True`` ``theta[7]`` is ``q`` (the parameterisation used by the estimator).
    """
    k, A_x, d, K_r, K_v, K_d, z_f = (theta[i] for i in range(7))
    q_i, zb_i = condition_loads(theta, known, conditions, moment)
    zg = known.zg_bar + z_f
    zs = known.zs_bar + z_f
    zm = zb_i + z_f
    A2 = A_x + known.M * zg * (known.zg_bar - known.zs_bar) + q_i * (zb_i - known.zs_bar) - K_v * zs
    B = K_v + known.M * zg + q_i
    kp = k - K_v * known.g
    A1 = A_x + known.M * zg**2 + q_i * zm
    k1 = k + known.M * known.g * zg + q_i * known.g
    one = np.ones_like(A2)
    return {"A2": A2, "B": B, "kp": kp * one, "d": d * one, "K_r": K_r * one, "K_delta": K_d * one,
            "A1": A1, "k1": k1, "z_s": zs * one, "Kyaw": K_r + known.U * B}


def continuous_coeffs(theta, known: KnownParams, conditions, moment: bool = False) -> np.ndarray:
    """``[alpha1, alpha2, beta1, kappa1, gamma1]`` of (26) per dataset, shape (n_datasets, 5)."""
    t = roll_terms(theta, known, conditions, moment)
    A2 = t["A2"]
    return np.stack([t["d"] / A2, t["kp"] / A2, -t["B"] / A2, t["K_r"] / A2, t["K_delta"] / A2], axis=-1)


def discrete_coeffs(theta, known: KnownParams, conditions, T, moment: bool = False) -> np.ndarray:
    """``g(theta)`` of (36) per dataset via the bilinear transform (33), shape (n_datasets, 5).

    ``T`` is the sample period, a scalar or one per dataset.
    """
    t = roll_terms(theta, known, conditions, moment)
    A2, kp, d = t["A2"], t["kp"], t["d"]
    den = 2 * d * T + kp * T**2 + 4 * A2                      # "A_2(theta)" below (33)
    return np.stack([(2 * kp * T**2 - 8 * A2) / den, (-2 * d * T + kp * T**2 + 4 * A2) / den,
                     -2 * T * t["B"] / den, 2 * T * t["K_r"] / den, 2 * T * t["K_delta"] / den], axis=-1)


def continuous_to_discrete(c: np.ndarray, T: float) -> np.ndarray:
    """Bilinear map of ``[alpha1, alpha2, beta1, kappa1, gamma1]`` to ``g`` (32)–(33), any leading shape."""
    a1, a2, b1, k1, g1 = (c[..., i] for i in range(5))
    den = 4 + 2 * a1 * T + a2 * T**2
    return np.stack([(2 * a2 * T**2 - 8) / den, (4 - 2 * a1 * T + a2 * T**2) / den,
                     2 * T * b1 / den, 2 * T * k1 / den, 2 * T * g1 / den], axis=-1)


def jacobian_complex_step(fun, theta: np.ndarray, h: float = 1e-30) -> np.ndarray:
    """Exact (to rounding) Jacobian of a real-analytic ``fun`` by complex-step differentiation."""
    theta = np.asarray(theta, dtype=float)
    f0 = np.asarray(fun(theta.astype(complex))).real
    J = np.empty(f0.shape + (theta.size,))
    for j in range(theta.size):
        tc = theta.astype(complex)
        tc[j] += 1j * h
        J[..., j] = np.asarray(fun(tc)).imag / h
    return J


def bilinear_tf(num_s, den_s, T: float) -> tuple[np.ndarray, np.ndarray]:
    """Bilinear (Tustin) discretisation of a continuous transfer function of order <= 2.

    ``num_s, den_s`` are coefficient lists in descending powers of s, padded to length 3. Returns
    ``(b, a)`` in powers of q^{-1}, normalised so that ``a[0] = 1`` (usable with ``lfilter``).
    """
    n = np.zeros(3); n[3 - len(num_s):] = num_s
    dd = np.zeros(3); dd[3 - len(den_s):] = den_s
    c = 2.0 / T

    def poly(p):  # p2 s^2 + p1 s + p0 with s = c (1 - z)/(1 + z), times (1 + z)^2; z = q^{-1}
        p2, p1, p0 = p
        return np.array([p2 * c * c + p1 * c + p0,
                         -2 * p2 * c * c + 2 * p0,
                         p2 * c * c - p1 * c + p0])

    b, a = poly(n), poly(dd)
    return b / a[0], a / a[0]


def to_moment(theta) -> np.ndarray:
    """``[.., m, zm_bar] -> [.., q, zm_bar]`` with ``q = m (zm_bar + z_f)``."""
    th = np.array(theta, dtype=np.result_type(theta, float))
    th[7] = theta[7] * (theta[8] + theta[6])
    return th


def from_moment(theta_q) -> np.ndarray:
    """``[.., q, zm_bar] -> [.., m, zm_bar]`` with ``m = q / (zm_bar + z_f)`` (inf/nan where z_m = 0)."""
    th = np.array(theta_q, dtype=np.result_type(theta_q, float))
    with np.errstate(divide="ignore", invalid="ignore"):
        th[7] = theta_q[7] / (theta_q[8] + theta_q[6])
    return th


__all__ = ["THETA_NAMES", "THETA_Q_NAMES", "to_moment", "from_moment", "THETA_UNITS", "G_NAMES", "KnownParams", "NOMINAL", "CALIBRATION", "LOADED",
           "condition_loads", "roll_terms", "continuous_coeffs", "discrete_coeffs", "continuous_to_discrete",
           "jacobian_complex_step", "bilinear_tf"]
