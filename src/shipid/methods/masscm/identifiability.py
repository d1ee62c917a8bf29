"""Structural identifiability of the mass / centre-of-mass model (Linder et al. 2015, eqs. 22–26, 30–33).

Question: which of the unknowns ``theta = [k, A_x, d, K_r, K_vdot, K_delta, z_f, m, zm_bar]`` (30) are
determined by the transfer functions of the nominal, calibration and loaded datasets together?

Answer (derived here, checked numerically by :func:`jacobian_rank` and exactly by
:func:`exact_fit_family`): the map ``theta -> g`` (15 discrete coefficients) has rank 8, not 9.
Every coefficient depends on the physical parameters only through the ratios of
``(d, k - K_vdot g, B_i, K_r, K_delta)`` to ``A2_i``, so a common factor ``c`` on all of them leaves
``g`` unchanged. Moving the centre of rotation to ``z_f'`` and taking

    c        = (zc_bar + z_f') / (zc_bar + z_f)               (calibration moment m_c z_c scales by c)
    K_vdot'  = c B_n - M (zg_bar + z_f')                      (nominal B)
    A_x'     = c A2_n - M (zg_bar + z_f')(zg_bar - zs_bar) + K_vdot' (zs_bar + z_f')
    k'       = c (k - K_vdot g) + K_vdot' g,   d' = c d,   K_r' = c K_r,   K_delta' = c K_delta
    zm_bar'  = zm_bar,   m' = c m z_m / (zm_bar + z_f')

reproduces every dataset's transfer function exactly. Hence ``z_f`` is not identifiable;
``zm_bar`` and the moment ratio ``rho = m z_m / (m_c z_c)`` are (both invariant); ``m`` follows from
``rho`` once ``z_f`` is fixed: ``m = rho m_c (zc_bar + z_f)/(zm_bar + z_f)``, with slope
``dm/dz_f = rho m_c (zm_bar - zc_bar)/(zm_bar + z_f)^2``. With Table 2 values ``dm/dz_f = -0.095 kg/m``;
the Table 3 spread of z_f (0.0225 m) then predicts a spread of m of about 0.0021 kg, close to the
0.0018 kg printed, and the scale factor c explains the wide spread of k, K_vdot and A_x.
"""

from __future__ import annotations

import numpy as np

from shipid.models.roll_reduced import (CALIBRATION, LOADED, NOMINAL, THETA_NAMES, KnownParams,
                                        discrete_coeffs, jacobian_complex_step, roll_terms)

CONDS = (NOMINAL, CALIBRATION, LOADED)


def coefficient_jacobian(theta, known: KnownParams, T: float = 0.02, conditions=CONDS) -> np.ndarray:
    """Jacobian (15 × 9) of the stacked discrete coefficients g of all datasets w.r.t. theta (exact)."""
    return jacobian_complex_step(lambda th: discrete_coeffs(th, known, list(conditions), T).ravel(), theta)


def jacobian_rank(theta, known: KnownParams, T: float = 0.02, rtol: float = 1e-9) -> dict:
    """Numerical rank of the parameter-to-coefficient map, its singular values and null direction.

    Columns are scaled by the parameter magnitudes first (so that the rank does not depend on units).
    """
    theta = np.asarray(theta, dtype=float)
    J = coefficient_jacobian(theta, known, T)
    scale = np.maximum(np.abs(theta), 1e-3)
    U, s, Vt = np.linalg.svd(J * scale, full_matrices=True)
    rank = int(np.sum(s > rtol * s[0]))
    null = Vt[-1] * scale                      # back to physical units
    null = null / null[THETA_NAMES.index("z_f")] if abs(null[THETA_NAMES.index("z_f")]) > 0 else null
    return {"rank": rank, "n_params": theta.size, "singular_values": s.tolist(),
            "null_direction": dict(zip(THETA_NAMES, null.tolist()))}


def exact_fit_family(theta, known: KnownParams, z_f_new: float) -> np.ndarray:
    """The parameters with centre of rotation ``z_f_new`` that give exactly the same transfer functions."""
    th = np.asarray(theta, dtype=float)
    k, A_x, d, K_r, K_v, K_d, z_f, m, zm = th
    t = roll_terms(th, known, [NOMINAL])
    A2n, Bn = t["A2"][0], t["B"][0]
    c = (known.zc_bar + z_f_new) / (known.zc_bar + z_f)
    K_v2 = c * Bn - known.M * (known.zg_bar + z_f_new)
    A_x2 = c * A2n - known.M * (known.zg_bar + z_f_new) * (known.zg_bar - known.zs_bar) + K_v2 * (known.zs_bar + z_f_new)
    k2 = c * (k - K_v * known.g) + K_v2 * known.g
    m2 = c * m * (zm + z_f) / (zm + z_f_new)
    return np.array([k2, A_x2, c * d, c * K_r, K_v2, c * K_d, z_f_new, m2, zm])


def rho(theta, known: KnownParams) -> float:
    """``rho = m z_m / (m_c z_c)`` (moments about the centre of rotation), identifiable."""
    z_f, m, zm = theta[6], theta[7], theta[8]
    return m * (zm + z_f) / (known.m_c * (known.zc_bar + z_f))


def m_of_zf(rho_value: float, zm_bar: float, z_f, known: KnownParams):
    """Load mass implied by the identifiable ``rho`` and ``zm_bar`` for a chosen ``z_f``."""
    return rho_value * known.m_c * (known.zc_bar + np.asarray(z_f)) / (zm_bar + np.asarray(z_f))


def dm_dzf(theta, known: KnownParams) -> float:
    """Slope of ``m(z_f)`` along the exact-fit family at theta."""
    z_f, zm = theta[6], theta[8]
    return rho(theta, known) * known.m_c * (zm - known.zc_bar) / (zm + z_f) ** 2


def report(theta, known: KnownParams, T: float = 0.02) -> dict:
    """Identifiability summary at theta: rank, the unidentifiable direction and what is invariant along it."""
    r = jacobian_rank(theta, known, T)
    nd = r["null_direction"]
    return {**r,
            "identifiable": ["zm_bar", "rho"] if r["rank"] == len(THETA_NAMES) - 1 else [],
            "not_identifiable": ["z_f"] if r["rank"] == len(THETA_NAMES) - 1 else [],
            "null_direction_zm_bar": nd["zm_bar"],
            "dm_dzf": dm_dzf(theta, known),
            "statement": ("z_f is not structurally identifiable from nominal+calibration+loaded data; "
                          "zm_bar and rho = m z_m/(m_c z_c) are; m = rho m_c (zc_bar+z_f)/(zm_bar+z_f) "
                          "needs z_f from elsewhere")}


__all__ = ["coefficient_jacobian", "jacobian_rank", "exact_fit_family", "rho", "m_of_zf", "dm_dzf", "report"]
