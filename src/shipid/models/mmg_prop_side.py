"""Small separate terms of a single-screw ship's port/starboard asymmetry in the MMG standard method.

Two optional particulars of :func:`shipid.models.mmg_forces.basis_yasukawa` (Yasukawa & Yoshimura 2015,
J. Mar. Sci. Technol. 20:37-52), each absent or 0 by default (forces bit-identical), each a scalar or one
value per row of a batch:

* ``rudder_neutral_angle`` ``δ_0`` (rad): the effective rudder inflow angle becomes
  ``α_R = δ − δ_0 − atan(v_R / u_R)`` (eq. 23 with an angle offset). A propeller's slipstream swirl
  reaches the rudder with a transverse velocity that does not cancel over the span behind a hull (the
  upper disc works in the larger wake); its net effect is an offset of the rudder angle that gives no
  rudder force, the neutral rudder angle (Molland & Turnock, Marine Rudders and Control Surfaces, 2007,
  §3.9 and ch. 5). For a right-handed propeller (clockwise seen from astern) the upper blades and the
  swirl above the shaft move to starboard, the stern is pushed to starboard and ``δ_0 > 0`` (a little
  starboard helm holds the course).
* ``prop_side_thrust`` ``c`` (-): a propeller side force ``Y_P = c T`` acting at the propeller,
  ``N_P = x_P L Y_P`` (``T`` the thrust of eq. 10, ``x_P`` the propeller's longitudinal position,
  ``/L``): the transverse force of the blades working in the non-uniform wake. Its sign is fixed by
  the rotation: a right-handed propeller pushes the stern to starboard, ``c ≥ 0``, ``N_P ≤ 0``.

They are the fixed parts ``F0`` (``Y_P``, ``N_P``) or a change of ``α_R`` (``δ_0``), not regression
columns: they are set (calibrated) from what the runs measure and held fixed in the regression.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

#: Particulars of the optional asymmetry terms of this module.
PROP_SIDE_TERMS = ("rudder_neutral_angle", "prop_side_thrust")


def neutral_angle_offset(p: Mapping, alpha_R):
    """``α_R − δ_0`` with ``δ_0`` = ``rudder_neutral_angle`` (absent or 0: ``α_R`` itself, unchanged)."""
    d0 = p.get("rudder_neutral_angle", 0.0)
    if not np.any(d0):
        return alpha_R
    return alpha_R - d0


def propeller_side_force(p: Mapping, T):
    """``(Y_P, N_P)`` = ``(c T, x_P L c T)`` with ``c`` = ``prop_side_thrust``, or None when absent or 0."""
    c = p.get("prop_side_thrust", 0.0)
    if not np.any(c):
        return None
    Y = c * T
    return Y, p["x_P"] * p["L"] * Y


__all__ = ["PROP_SIDE_TERMS", "neutral_angle_offset", "propeller_side_force"]
