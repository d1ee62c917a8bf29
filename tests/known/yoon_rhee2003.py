"""Yoon & Rhee (2003), seed 002: identification of hydrodynamic coefficients in ship manoeuvring equations
by Estimation-Before-Modelling; the ESSO OSAKA simulation study of its Section 5.1.

The seed text has no page numbers; tables, equations and figures are cited by number. Non-dimensional
coefficients (primed, the paper's (16) scaling).
"""

from __future__ import annotations

#: Table 3, "True" column: spot values of the modified Abkowitz coefficients of ESSO OSAKA.
TABLE3_TRUE = {"Y_v": -2.83e-2, "N_r": -5.00e-3, "eta_3": 3.83e-7}

#: Eq. (21) and the text after it: alpha, the slope of v against r, and the true combined coefficients
#: Y'_v + Y'_r / alpha and N'_v alpha + N'_r (the paper's identified ones: -3.7358e-2 and -6.5222e-4).
EQ21_ALPHA = -0.4104
EQ21_TRUE = {"Yv+Yr/alpha": -3.7807e-2, "Nv*alpha+Nr": -5.2664e-4}
EQ21_IDENTIFIED = {"Yv+Yr/alpha": -3.7358e-2, "Nv*alpha+Nr": -6.5222e-4}

#: Table 4 (standard manoeuvres): condition number kappa of W'W, R and Mallows' C_p per mode.
TABLE4 = {"surge": (3.7220e4, 0.9890, 8.0545), "sway": (2.8251e6, 0.9823, 9.0536),
          "yaw": (2.8166e6, 0.9198, 9.0808)}

#: Fig. 7 and its text (Section 5.1.4): the D-optimal PRBS input, amplitude (deg) and period (s).
FIG7_OPTIMUM = (35.0, 105.0)
