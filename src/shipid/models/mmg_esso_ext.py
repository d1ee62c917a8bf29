"""Extra surge and rudder-inflow columns of the low-speed Esso Osaka model (structure ``esso-lowspeed-ext``).

``esso-lowspeed-ext`` is the ``esso-lowspeed-asym`` structure of :mod:`shipid.models.mmg`
with nine more linear coefficients, each zero in the published model (so that the
structure with them at zero is the published one, term for term): high-speed /
high-propeller-rate terms that the low-speed hull of Yoshimura (as coded in
NAOE-5thLab/mmg-1p1r-simulator c54ef807) leaves out, and gains on its fixed air force:

``X_vv``, ``X_rr``
    the second-order surge hull terms of the MMG standard method (Yasukawa & Yoshimura
    2015, J Mar Sci Technol 20:37, eq. 8), in the low-speed model's scaling:
    ``X = ½ρLd (X_vv v² + X_rr (rL)²)``, the speed lost to drift and turning;
``XR_D``
    the rudder's profile drag, ``X = −XR_D ½ρ A_R U_R u_R`` (``u_R`` the axial inflow at
    the rudder, ``U_R`` its magnitude): a drag that grows with the slipstream speed, not
    with the hull speed, so with the propeller rate;
``XR_s``, ``YR_s``, ``NR_s``
    a rudder force gain on the slipstream part of the inflow: the rudder columns
    (``−F_N sin δ``, ``−F_N cos δ`` in X, Y, N) times the slipstream share of the inflow
    dynamic pressure ``φ = 1 − (ε_R u_P)² / U_R²`` (``u_P = u (1 − w_P) = J n D`` the
    propeller inflow; ``φ = 0`` unless ``n > 0`` and ``u > 0``). With ``YR_gain`` this makes
    the rudder's effective gain ``YR_gain + YR_s φ``: a rudder inflow that depends on the
    propeller loading more (or less) than the slipstream model of Yoshimura's low-speed
    rudder gives, the propeller-rate-dependent rudder force of the fastest runs.

:func:`ext_columns` appends these columns to the regressors of
:func:`shipid.models.mmg.basis`; the order is :data:`EXT_COEFS`.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from shipid.models.mmg_forces import wind_forces

#: The extra coefficients of ``esso-lowspeed-ext`` per mode, in column order.
EXT_COEFS: dict[str, tuple[str, ...]] = {"X": ("X_vv", "X_rr", "XR_D", "XR_s", "XW_g"), "Y": ("YR_s", "YW_g"),
                                         "N": ("NR_s", "NW_g")}


def slipstream_share(p: Mapping[str, float], u, n, J, U_R):
    """``φ = 1 − (ε_R J n D)² / U_R²`` clipped to [0, 1] where ``n > 0`` and ``u > 0``, else 0 (module docstring)."""
    eps_R, D = p["eps_R"], p["D_p"]
    ok = (n > 0) & (u > 0) & (U_R > 1e-6)
    uP = np.where(ok, J * n * D, 0.0)
    UR = np.where(ok, U_R, 1.0)
    return np.where(ok, np.clip(1.0 - (eps_R * uP / UR) ** 2, 0.0, 1.0), 0.0)


def ext_columns(p: Mapping[str, float], u, v, r, delta, n, out: dict, U_A=0.0, gamma_A=0.0) -> dict:
    """``out`` (the ``esso-lowspeed-asym`` regressors of :func:`shipid.models.mmg.basis`, before wind)
    with the :data:`EXT_COEFS` columns appended to each mode; ``U_A``, ``gamma_A`` the apparent wind."""
    L, d, rho = p["L"], p["d"], p["rho"]
    a = out["aux"]
    qX = 0.5 * rho * L * d
    U_R, alpha_R, FN = a["U_R"], a["alpha_R"], a["F_N"]
    u_R = U_R * np.cos(delta - alpha_R)           # alpha_R = delta - atan2(v_R, u_R)
    phi = slipstream_share(p, u, n, a["J"], U_R)
    sd, cd = np.sin(delta), np.cos(delta)
    XA, YA, NA = (np.broadcast_to(F, u.shape) for F in wind_forces(p, np.asarray(U_A, float),
                                                                    np.asarray(gamma_A, float)))
    cols = {"X": (qX * v * v, qX * (r * L) ** 2, -0.5 * rho * p["A_R"] * U_R * u_R, -FN * sd * phi, XA),
            "Y": (-FN * cd * phi, YA),
            "N": (-FN * cd * phi, NA)}
    res = dict(out)
    for m, extra in cols.items():
        H, F0 = out[m]
        res[m] = (np.concatenate([H, np.stack(extra, axis=-1)], axis=-1), F0)
    res["aux"] = dict(a, phi=phi)
    return res


__all__ = ["EXT_COEFS", "slipstream_share", "ext_columns"]
