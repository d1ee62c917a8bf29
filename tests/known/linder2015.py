"""Linder, Enqvist, Fossen, Johansen & Gustafsson (2015), seed 000: online estimation of ship mass and centre
of mass from an IMU and the rudder (the simulation study of its Section 5).

The seed text has no page numbers; tables are cited by number. Parameter order of the 9-vectors is
:data:`shipid.models.roll_reduced.THETA_NAMES` = (k, A_x, d, K_r, K_vdot, K_delta, z_f, m, zm_bar), which is
not the column order of Table 3 (A_x, d, k, K_delta, K_r, K_vdot, z_f, m, zm_bar).
"""

from __future__ import annotations

import numpy as np

#: Names of the 9 parameters, in the order of the vectors below.
NAMES = ("k", "A_x", "d", "K_r", "K_vdot", "K_delta", "z_f", "m", "zm_bar")

#: Table 3 row T ("true"), equal to the simulation parameters of Table 2 (k = 10.38 N m/rad,
#: A_x = 0.1385 kg m², d = 0.2067, K_r = -0.5 (Table 2: K_ur = -0.4 <=> K_r = -0.5), K_vdot = 0.1,
#: K_delta = -0.405, z_f = -0.028 m, m = 0.4 kg, zm_bar = -0.182 m).
TABLE3_TRUE = np.array([10.38, 0.1385, 0.2067, -0.5, 0.1, -0.405, -0.028, 0.4, -0.182])

#: Table 3 rows M and S: mean and standard deviation of Algorithm 1 over 10 000 initial values (noise-free,
#: z_f estimated, five implausible runs left out), same order as :data:`TABLE3_TRUE`.
TABLE3_MEAN = np.array([13.297, 0.1261, 0.2194, -0.5318, 0.3396, -0.4302, -0.0403, 0.4007, -0.1821])
TABLE3_STD = np.array([5.3579, 0.0296, 0.0233, 0.0584, 0.4367, 0.0454, 0.0225, 0.0018, 0.0004])

#: Table 2 "General": the known quantities (U m/s, M kg, zg_bar m, m_c kg, zc_bar m, zs_bar m, g m/s²)
#: and the load (m kg at zm_bar m) and centre of rotation z_f (m) the estimator must find.
TABLE2_KNOWN = {"U": 1.0, "M": 22.04, "zg_bar": 0.0, "m_c": 0.2, "zc_bar": -0.172, "zs_bar": -0.2, "g": 9.82}
TABLE2_LOAD = {"m": 0.4, "zm_bar": -0.182, "z_f": -0.028}


def true_value(name: str) -> float:
    """The Table 3 row-T value of one parameter by name."""
    return float(TABLE3_TRUE[NAMES.index(name)])


def paper_mean(name: str) -> float:
    """The Table 3 row-M value (mean over the paper's 10 000 runs) of one parameter by name."""
    return float(TABLE3_MEAN[NAMES.index(name)])
