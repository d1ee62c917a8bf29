"""Low-speed rudder-inflow, propeller-walk and wind-arm columns of the Esso Osaka model (structure ``esso-lowspeed-ext2``).

``esso-lowspeed-ext2`` is ``esso-lowspeed-ext`` (:mod:`shipid.models.mmg_esso_ext`) with five
more linear coefficients, each zero in the published model, so that the structure with
them at zero is ``esso-lowspeed-ext`` term for term:

``YR_r``, ``NR_r``
    a correction of the yaw-rate part of the rudder inflow angle. The low-speed rudder of
    Yoshimura (mmg-1p1r-simulator c54ef807) has the inflow ``v_R = −γ_R (v + l_R r)`` with a
    fixed ``l_R``; an extra angle ``c r L / U_R`` times the normal-force slope
    ``∂F_N/∂α = ½ ρ A_R U_R² f_α cos α_R`` (Fujii's ``f_α``) gives the columns
    ``Y: −½ ρ A_R f_α cos α_R U_R (r L) cos δ`` and ``N``: the same times ``L`` (the rudder's
    side force at its lever arm, ``NR_r`` a non-dimensional arm). ``U_R`` enters once, so the
    column stays bounded at low inflow speed;
``YP_J``, ``NP_J``
    the side force and moment of the ahead propeller growing with the advance ratio:
    ``Y = YP_J ρ n² D⁴ J``, ``N = NP_J ρ n² D⁴ J L`` (``n > 0``; the base's ``YP_n``, ``NP_n``
    are the ``J = 0`` part);
``NW_y``
    a shift of the centre of effort of the air side force: ``N = NW_y L Y_A`` with ``Y_A``
    Fujiwara's side force of :func:`shipid.models.mmg_forces.wind_forces`.

:func:`ext2_columns` appends them to the ``esso-lowspeed-ext`` regressors; the order is
:data:`EXT2_COEFS`.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from shipid.models.mmg_forces import fujii_f_alpha, wind_forces

#: The extra coefficients of ``esso-lowspeed-ext2`` per mode, in column order.
EXT2_COEFS: dict[str, tuple[str, ...]] = {"X": (), "Y": ("YR_r", "YP_J"), "N": ("NR_r", "NP_J", "NW_y")}


def ext2_columns(p: Mapping[str, float], u, v, r, delta, n, out: dict, U_A=0.0, gamma_A=0.0) -> dict:
    """``out`` (the ``esso-lowspeed-ext`` regressors, before wind) with the :data:`EXT2_COEFS` columns appended."""
    L, rho, D = p["L"], p["rho"], p["D_p"]
    a = out["aux"]
    f_alpha = fujii_f_alpha(p["lambda_R"])
    yaw = -0.5 * rho * p["A_R"] * f_alpha * np.cos(a["alpha_R"]) * a["U_R"] * (r * L) * np.cos(delta)
    TJ = (n > 0) * rho * D ** 4 * n * n * a["J"]
    _, YA, _ = wind_forces(p, np.asarray(U_A, float), np.asarray(gamma_A, float))
    YA = np.broadcast_to(YA, np.shape(u))
    cols = {"Y": (yaw, TJ), "N": (yaw * L, TJ * L, YA * L)}
    res = dict(out)
    for m, extra in cols.items():
        H, F0 = out[m]
        res[m] = (np.concatenate([H, np.stack(extra, axis=-1)], axis=-1), F0)
    return res


__all__ = ["EXT2_COEFS", "ext2_columns"]
