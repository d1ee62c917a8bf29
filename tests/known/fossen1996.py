"""Fossen, Sagatun & Sørensen (1996), seed 001: identification of dynamically positioned ships; the
supply vessel of its Section 4.2 (values in the bis system, marked '').

The seed text has no page numbers; equations are cited by number. The readings of misprinted
equations are those of ERRATA.md (001): (50) B'' = M''^-1 T'' K''; (49) K5'' is printed to 0.1e-3.
"""

from __future__ import annotations

import numpy as np

#: Eq. (48): the identified momentum-equation matrix A_h''.
A_H_EQ48 = np.array([[-0.0318, 0.0, 0.0], [0.0, -0.0602, 0.0618], [0.0, -0.0075, -0.2454]])

#: Eq. (49): K'' = 1e-3 diag{9.3, 9.3, 2.0, 2.0, 2.8, 2.6} (thruster gains; K1 = K2, K3 = K4).
K_EQ49 = 1e-3 * np.array([9.3, 9.3, 2.0, 2.0, 2.8, 2.6])

#: Eqs. (46)-(49): the 9 free parameters theta1..theta9 (shipid.models.dp.THETA_NAMES) of (48)-(49):
#: A_h''[0,0], A_h''[1,1], A_h''[1,2], A_h''[2,1], A_h''[2,2], K1'' = K2'', K3'' = K4'', K5'', K6''.
THETA_EQ46_49 = np.array([-0.0318, -0.0602, 0.0618, -0.0075, -0.2454, 9.3e-3, 2.0e-3, 2.8e-3, 2.6e-3])

#: Eq. (51): A'' = M''^-1 A_h'' M''.
A_EQ51 = np.array([[-0.0318, 0, 0], [0, -0.0628, -0.0030], [0, -0.0045, -0.2428]])

#: Eq. (52): B'' = M''^-1 T'' K'' (3 x 6; printed to 1e-4, so compare with a tolerance that respects it).
B_EQ52 = np.array([[0.0082, 0.0082, 0, 0, 0, 0],
                   [0.0001, -0.0001, 0.0008, 0.0008, 0.0020, 0.0017],
                   [0.0035, -0.0035, -0.0059, -0.0055, 0.0113, 0.0079]])

#: Eq. (29): the thruster configuration matrix T'' (azimuth thruster 6 at 90 degrees).
T_EQ29 = np.array([[1, 1, 0, 0, 0, 0], [0, 0, 1, 1, 1, 1],
                   [0.0472, -0.0472, -0.4108, -0.3858, 0.4554, 0.3373]])
