"""MMG-type 3-DOF manoeuvring model: hull, propeller and rudder forces apart (surge, sway, yaw).

Two structures share the rigid-body equations and the state/input layout:

``"esso-lowspeed"``
    The low-speed MMG model of the 3 m Esso Osaka used by Miyauchi et al. (2022,
    J Mar Sci Technol 27:1065, §2) and Wakita et al. (2022, J Mar Sci Technol 27:772),
    as coded in NAOE-5thLab/mmg-1p1r-simulator (``python_module/subroutine``, commit
    c54ef807): hull after Yoshimura (drag that blends between ahead and astern with
    ``|β|/π``, linear terms plus a cross-flow drag integral), propeller thrust in four
    quadrants (Hachii's model for ``n < 0``, Ueno's polynomial side force/moment),
    Yoshimura's low-speed rudder inflow and Kitagawa's model for reversing, Fujii's
    normal-force coefficient, Fujiwara's wind-force regression. Parameters are read at
    run time from ``data_root()/params/esso_osaka_3m_mmg_*.csv`` (never copied).
``"yasukawa2015"``
    The MMG standard method (Yasukawa & Yoshimura 2015, J Mar Sci Technol 20:37,
    eqs. 4–12, Table 3 for KVLCC2): 3rd-order polynomial hull forces in ``v'``, ``r'``,
    propeller thrust with ``K_T(J)`` quadratic, rudder normal force with the
    flow-straightening ``γ_R``. The KVLCC2 L7 set is read from
    ``data_root()/params/kvlcc2_L7_mmg_shipmmg.yml``.

Every force is written linear in its coefficients, ``F = H(x, u) θ + F_fixed(x, u)``
(:func:`basis`): the simulator and the regression of :mod:`shipid.methods.mmg.estimator`
use the same expression, so an identified coefficient means in simulation exactly
what it meant in the regression.

State ``x = [x0, y0, ψ, u, v_m, r]`` (earth-fixed midship position, heading, surge,
sway at midship, yaw rate; SI); inputs ``u = [δ, n, U_T, γ_T]`` (rudder angle rad,
propeller rev/s, true wind speed m/s and the direction it blows *from*, rad clockwise
from the x0 axis; checked against the Esso data, whose relative wind the transform of
:func:`apparent_wind` reproduces to 3e-5 rad). Equations of motion (Yasukawa &
Yoshimura 2015, eq. 4, about midship)::

    (m + m_x) u̇ − (m + m_y) v_m r − x_G m r² = X
    (m + m_y) v̇_m + x_G m ṙ = Y − (m + m_x) u r
    (I_zG + x_G² m + J_z) ṙ + x_G m v̇_m = N − x_G m u r

Units: the Esso CSVs give masses and forces non-dimensionalised by ``0.5 ρ L² d`` and
``0.5 ρ L d U²`` with the *engineering* density ρ/g (kgf s²/m⁴) of the Japanese
code; as every term carries the same ρ, SI ρ = 998 kg/m³ gives the same motion in N.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from shipid.io.paths import data_root
from shipid.errors import InputError
from shipid.models.mmg_forces import (apparent_wind, basis_esso, basis_yasukawa, crossflow_integrals, cubic_hull,
                                      fujii_f_alpha, fujiwara_coefficients, wind_forces)
from shipid.models import mmg_kernels
from shipid.models.mmg_esso_ext import EXT_COEFS, ext_columns
from shipid.numerics.integrate import rk4_step
from shipid.models.ship_model import ShipModel

STATE_NAMES = ("x", "y", "psi", "u", "v", "r")
INPUT_NAMES = ("delta", "n", "wind_speed", "wind_dir")
STRUCTURES = ("esso-lowspeed", "yasukawa2015", "esso-cubic-hull", "esso-lowspeed-asym")
MODES = ("X", "Y", "N")

# ----------------------------------------------------------------------------- coefficients
#: Linear coefficients of each mode, by structure (the regression's unknowns).
COEFS: dict[str, dict[str, tuple[str, ...]]] = {
    "esso-lowspeed": {
        "X": ("X_0F", "X_0A", "X_vr", "XP_k0", "XP_k1", "XP_k2", "XP_c0", "XP_c1", "XP_c2", "XR_gain"),
        "Y": ("Y_v", "Y_r", "CD_Y", "YP_a0", "YP_a1", "YP_a2", "YP_a3", "YP_a4", "YP_a5", "YP_a6",
              "YP_a7", "YR_gain"),
        "N": ("N_v", "N_r", "CD_N", "NP_b0", "NP_b1", "NP_b2", "NP_b3", "NP_b4", "NP_b5", "NP_b6",
              "NP_b7", "NR_arm"),
    },
    "yasukawa2015": {
        "X": ("R_0", "X_vv", "X_vr", "X_rr", "X_vvvv", "XP_gain", "XR_gain"),
        "Y": ("Y_v", "Y_r", "Y_vvv", "Y_vvr", "Y_vrr", "Y_rrr", "YR_gain"),
        "N": ("N_v", "N_r", "N_vvv", "N_vvr", "N_vrr", "N_rrr", "NR_arm"),
    },
}
# The Esso propeller/rudder sub-models with the hull of the standard MMG (a cubic
# expansion in v' = v/U, r' = rL/U about steady forward motion, forces ∝ U²): the
# "service-speed expansion" the low-speed structure is compared against.
_HULL_CUBIC = {"X": ("R_0", "X_vv", "X_vr", "X_rr", "X_vvvv"),
               "Y": ("Y_v", "Y_r", "Y_vvv", "Y_vvr", "Y_vrr", "Y_rrr"),
               "N": ("N_v", "N_r", "N_vvv", "N_vvr", "N_vrr", "N_rrr")}
COEFS["esso-cubic-hull"] = {m: _HULL_CUBIC[m] + COEFS["esso-lowspeed"][m][3:] for m in MODES}
# The low-speed Esso model with two port/starboard terms that are zero in it: the side force and
# moment of the ahead-turning propeller, ``Y = YP_n ρ n² D⁴``, ``N = NP_n ρ n² D⁴ L`` (n > 0; the
# lateral force of a single propeller behind the hull), and a rudder neutral offset, the force of
# the rudder's normal-force slope ``∂F_N/∂α = ½ ρ A_R U_R² f_α cos α_R`` times a constant angle
# (``YR_0``, ``NR_0``: an offset of the rudder-angle zero or of the inflow angle at the rudder).
COEFS["esso-lowspeed-asym"] = {"X": COEFS["esso-lowspeed"]["X"],
                               "Y": COEFS["esso-lowspeed"]["Y"] + ("YP_n", "YR_0"),
                               "N": COEFS["esso-lowspeed"]["N"] + ("NP_n", "NR_0")}
# ``esso-lowspeed-asym`` with the surge and slipstream-rudder columns of :mod:`shipid.models.mmg_esso_ext`.
STRUCTURES = STRUCTURES + ("esso-lowspeed-ext",)
COEFS["esso-lowspeed-ext"] = {m: COEFS["esso-lowspeed-asym"][m] + EXT_COEFS[m] for m in MODES}

#: Units of the linear coefficients (dimensional gains; hull coefficients are non-dimensional).
COEF_UNITS = {"NR_arm": "m", "NR_s": "m"}

@dataclass(frozen=True)
class MmgModel:
    """An MMG model: structure, vessel particulars (SI) and coefficients.

    Attributes
    ----------
    structure : {"esso-lowspeed", "yasukawa2015"}
    particulars : mapping of str to float
        ``L, B, d, m, x_G, rho, m_x, m_y, J_z, I_zG`` (SI; ``I_zG`` may be folded into
        ``J_z`` as the Esso set does, with ``I_zG = 0``), the sub-model constants of
        the structure (propeller, rudder, wind geometry) and, where known, ``L_ship``: the
        full-scale length of the ship a model-scale hull represents (m).
    coef : mapping of str to float
        The linear coefficients :data:`COEFS` of the structure.
    name : str
    sources : mapping of str to str
        Where the numbers come from.
    """

    structure: str
    particulars: Mapping[str, float]
    coef: Mapping[str, float]
    name: str = "mmg"
    sources: Mapping[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.structure not in STRUCTURES:
            raise InputError(f"unknown MMG structure '{self.structure}' (choose from {', '.join(STRUCTURES)})")
        missing = [c for m in MODES for c in COEFS[self.structure][m] if c not in self.coef]
        if missing:
            raise InputError(f"MMG model '{self.name}': coefficient(s) missing: {', '.join(missing)}")

    def with_coef(self, values: Mapping[str, float], name: str | None = None) -> "MmgModel":
        c = dict(self.coef)
        c.update({k: float(v) for k, v in values.items()})
        return replace(self, coef=c, name=name or self.name)

    def theta(self, mode: str) -> np.ndarray:
        return np.array([self.coef[c] for c in COEFS[self.structure][mode]], dtype=float)

    def to_dict(self) -> dict[str, Any]:
        return {"family": "mmg", "structure": self.structure, "name": self.name,
                "state": list(STATE_NAMES), "inputs": list(INPUT_NAMES),
                "particulars": {k: float(v) for k, v in self.particulars.items()},
                "coefficients": {k: float(v) for k, v in self.coef.items()},
                "sources": dict(self.sources)}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "MmgModel":
        if d.get("family", "mmg") != "mmg":
            raise InputError(f"not an MMG model (family '{d.get('family')}')")
        return cls(structure=d["structure"], particulars=dict(d["particulars"]),
                   coef=dict(d["coefficients"]), name=d.get("name", "mmg"),
                   sources=dict(d.get("sources", {})))


# ----------------------------------------------------------------------------- basis
def basis(model: MmgModel, u, v, r, delta, n, U_A=0.0, gamma_A=0.0):
    """Regressors and fixed parts of the three modes.

    Parameters
    ----------
    model : MmgModel
        Supplies the particulars and the fixed sub-model constants.
    u, v, r, delta, n : array_like, same shape (...)
        Surge, midship sway, yaw rate, rudder angle, propeller revolutions.
    U_A, gamma_A : array_like
        Relative wind speed and direction (from :func:`apparent_wind`).

    Returns
    -------
    dict
        ``{"X": (H, F0), "Y": (H, F0), "N": (H, F0)}`` with ``H`` shape (..., p) whose
        columns follow :data:`COEFS` and the fixed part ``F0`` shape (...); the force
        is ``H @ θ + F0``. Also ``"aux"``: intermediate quantities (``U_R``,
        ``alpha_R``, ``J``, ``F_N_unit``...).
    """
    u, v, r, delta, n = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (u, v, r, delta, n)))
    p = model.particulars
    if model.structure == "esso-lowspeed":
        out = basis_esso(p, u, v, r, delta, n)
    elif model.structure == "esso-cubic-hull":
        out = basis_esso(p, u, v, r, delta, n)
        for m, H in zip(MODES, cubic_hull(p, u, v, r)):
            out[m] = (np.concatenate([H, out[m][0][..., 3:]], axis=-1), out[m][1])
    elif model.structure in ("esso-lowspeed-asym", "esso-lowspeed-ext"):
        out = basis_esso(p, u, v, r, delta, n)
        a = out["aux"]
        T4 = (n > 0) * p["rho"] * p["D_p"] ** 4 * n * n
        f_alpha = fujii_f_alpha(p["lambda_R"])
        dFN = 0.5 * p["rho"] * p["A_R"] * a["U_R"] ** 2 * f_alpha * np.cos(a["alpha_R"]) * np.cos(delta)
        for m, extra in (("Y", (T4, dFN)), ("N", (T4 * p["L"], dFN * p["L"]))):
            out[m] = (np.concatenate([out[m][0], np.stack(extra, axis=-1)], axis=-1), out[m][1])
        if model.structure == "esso-lowspeed-ext":
            out = ext_columns(p, u, v, r, delta, n, out, U_A, gamma_A)
    else:
        out = basis_yasukawa(p, u, v, r, delta, n)
    XA, YA, NA = wind_forces(p, np.asarray(U_A, float), np.asarray(gamma_A, float))
    for m, F in zip(MODES, (XA, YA, NA)):
        H, F0 = out[m]
        out[m] = (H, F0 + F)
    return out


# ----------------------------------------------------------------------------- dynamics
def mass_terms(model: MmgModel) -> tuple[float, float, float, float, float]:
    """``(m + m_x, m + m_y, I_zG + x_G² m + J_z, x_G m, m)``."""
    p = model.particulars
    m, xG = p["m"], p["x_G"]
    return m + p["m_x"], m + p["m_y"], p["I_zG"] + xG * xG * m + p["J_z"], xG * m, m


def forces(model: MmgModel, u, v, r, delta, n, U_A=0.0, gamma_A=0.0):
    """Total forces ``(X, Y, N)`` (N, N m) of the model at the given motions and inputs."""
    b = basis(model, u, v, r, delta, n, U_A, gamma_A)
    out = []
    for m in MODES:
        H, F0 = b[m]
        out.append(H @ model.theta(m) + F0)
    return tuple(out)


def accelerations(model: MmgModel, u, v, r, X, Y, N):
    """``(u̇, v̇_m, ṙ)`` from the forces by the equations of motion (module docstring)."""
    mx, my, Iz, xGm, m = mass_terms(model)
    du = (X + my * v * r + xGm * r * r) / mx
    A = Y - mx * u * r
    B = N - xGm * u * r
    det = my * Iz - xGm * xGm
    dv = (A * Iz - xGm * B) / det
    dr = (my * B - xGm * A) / det
    return du, dv, dr


def rigid_body_forces(model: MmgModel, u, v, r, du, dv, dr):
    """Forces that produce the accelerations ``(u̇, v̇, ṙ)`` (inverse of :func:`accelerations`)."""
    mx, my, Iz, xGm, m = mass_terms(model)
    X = mx * du - my * v * r - xGm * r * r
    Y = my * dv + xGm * dr + mx * u * r
    N = Iz * dr + xGm * dv + xGm * u * r
    return X, Y, N


def dynamics(t, x, u, model: MmgModel):
    """``f(t, x, u, θ)``: state derivative; ``x`` (..., 6), ``u`` (..., 4), batch-capable."""
    x = np.asarray(x, dtype=float)
    u_in = np.asarray(u, dtype=float)
    psi, uu, vv, rr = x[..., 2], x[..., 3], x[..., 4], x[..., 5]
    delta, n = u_in[..., 0], u_in[..., 1]
    if u_in.shape[-1] >= 4:
        UA, gA = apparent_wind(u_in[..., 2], u_in[..., 3], psi, uu, vv)
    else:
        UA, gA = np.zeros_like(uu), np.zeros_like(uu)
    X, Y, N = forces(model, uu, vv, rr, delta, n, UA, gA)
    du, dv, dr = accelerations(model, uu, vv, rr, X, Y, N)
    c, s = np.cos(psi), np.sin(psi)
    return np.stack([uu * c - vv * s, uu * s + vv * c, rr, du, dv, dr], axis=-1)


def simulate_batch(model: MmgModel, t: np.ndarray, x0: np.ndarray, U: np.ndarray, *,
                   substeps: int = 1, compiled: bool = True) -> np.ndarray:
    """RK4 simulation of many initial states at once with zero-order-hold inputs.

    Parameters
    ----------
    t : ndarray (n,)
        Time grid (uniform or not).
    x0 : ndarray (B, 6)
    U : ndarray (B, n, 4) or (n, 4)
        Inputs on the grid, held over each step (as :func:`shipid.numerics.integrate.simulate`).

    compiled : bool
        For the structures :func:`shipid.models.mmg_kernels.supported` names and inputs with the wind
        columns, the compiled copy of this integration (:func:`shipid.models.mmg_kernels.simulate_rows`;
        the same numbers to round-off, ``tests/models/test_mmg_kernels.py``); False: the loop below.

    Returns
    -------
    ndarray (B, n, 6)
        Non-finite states (a diverging model) stay NaN from the step they appear.
    """
    x = np.array(x0, dtype=float, ndmin=2)
    B, nt = x.shape[0], t.size
    U = np.asarray(U, dtype=float)
    if U.ndim == 2:
        U = np.broadcast_to(U, (B,) + U.shape)
    if compiled and mmg_kernels.supported(model.structure) and U.shape[-1] >= 4 and nt >= 1:
        t = np.asarray(t, dtype=float)
        h = np.broadcast_to((t[1:] - t[:-1]) / substeps, (B, nt - 1))
        Th = {m: model.theta(m)[None] for m in MODES}
        return mmg_kernels.simulate_rows(model.structure, model.particulars, mass_terms(model), Th, x, U[..., :4], h,
                                         substeps)
    out = np.empty((B, nt, x.shape[1]))
    out[:, 0] = x
    with np.errstate(all="ignore"):
        for k in range(nt - 1):
            uk = U[:, k]
            h = (t[k + 1] - t[k]) / substeps
            for _ in range(substeps):
                x = rk4_step(dynamics, 0.0, x, uk, model, h)      # autonomous: t does not enter
            # a state that blows up is reported as NaN, never silently clipped
            x = np.where(np.abs(x) < 1e6, x, np.nan)
            out[:, k + 1] = x
    return out


# ----------------------------------------------------------------------------- published sets
def _read_csv_table(path: Path, key: str, val: str) -> dict[str, float]:
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    out = {}
    for row in rows:
        row = {k.strip(): (v or "").strip() for k, v in row.items() if k is not None}
        out[row[key]] = float(row[val])
    return out


def _params_dir(root: Path | None) -> Path:
    root = data_root() if root is None else Path(root)
    if root is None or not (root / "params").is_dir():
        raise InputError("the shared data folder with params/ was not found (set SHIPID_DATA)")
    return root / "params"


#: Full-scale length between perpendiculars of the ESSO OSAKA, m (Crane 1979, Table 1: 1066 ft), the ship the
#: 3 m model represents; ``particulars["L_ship"]`` of the published set (``shipid imo``'s full-scale L/V).
ESSO_OSAKA_SHIP_LENGTH = 325.0
#: Full-scale length between perpendiculars of the KVLCC2, m (Yasukawa & Yoshimura 2015, Table 1).
KVLCC2_SHIP_LENGTH = 320.0


def load_esso_osaka_published(root: Path | None = None) -> MmgModel:
    """The published MMG set of the 3 m Esso Osaka (mmg-1p1r-simulator, commit c54ef807).

    Read from ``params/esso_osaka_3m_mmg_{principal_particulars,MMG_params,model_switch}.csv``
    under :func:`shipid.io.data_root` (or ``root``). Only the model switches of the
    published file (all 1: Hachii thrust, Ueno side force, rudder force when reversing,
    Fujii normal force, Yoshimura inflow, uniform true wind) are implemented; other
    switch values raise :class:`InputError`.
    """
    d = _params_dir(root)
    pp = _read_csv_table(d / "esso_osaka_3m_mmg_principal_particulars.csv", "parameter", "value")
    pr = _read_csv_table(d / "esso_osaka_3m_mmg_MMG_params.csv", "parameter", "params_init")
    sw = _read_csv_table(d / "esso_osaka_3m_mmg_model_switch.csv", "model", "value")
    want = {"switch_prop_x": 1, "switch_prop_y": 1, "switch_prop_n": 1, "switch_rudder": 1,
            "switch_fn": 1, "switch_ur": 1}
    for k, v in want.items():
        if int(sw.get(k, v)) != v:
            raise InputError(f"model switch {k} = {sw[k]:g} is not implemented (only {v})")
    L, d_, rho = pp["lpp"], pp["draft"], pp["rho_fresh"]
    qM, qI = 0.5 * rho * L * L * d_, 0.5 * rho * L ** 4 * d_
    part = {
        "L": L, "L_ship": ESSO_OSAKA_SHIP_LENGTH, "B": pp["breadth"], "d": d_, "rho": rho,
        "m": pp["mass_nd"] * qM, "x_G": pp["x_lcg"] * L,
        "m_x": pr["massx_nd"] * qM, "m_y": pr["massy_nd"] * qM, "J_z": pr["IzzJzz_nd"] * qI, "I_zG": 0.0,
        "D_p": pp["dia_prop"], "pitch_ratio": pp["pitchr"],
        "A_R": pp["area_rudder"], "lambda_R": pp["lambda_rudder"], "x_R": pp["x_location_rudder"],
        "C_rY": pr["cry_cross_flow"], "C_rN": pr["crn_cross_flow"],
        "t_P": pr["t_prop"], "w_P0": pr["w_prop_zero"], "tau_P": pr["tau_prop"], "C_P": pr["coeff_cp_prop"],
        "x_P": pr["xp_prop_nd"], "k_0": pr["kt_coeff0"], "k_1": pr["kt_coeff1"], "k_2": pr["kt_coeff2"],
        "c_0": pr["ci_coeff_prop0"], "c_1": pr["ci_coeff_prop1"], "c_2": pr["ci_coeff_prop2"],
        "XP_c3": pr["ci_coeff_prop3"],
        "l_R": pr["lr_rudder_nd"], "kx_R": pr["kx_rudder"], "kx_R_reverse": pr["kx_rudder_reverse"],
        "eps_R": pr["epsilon_rudder"], "C_PR": pr["cpr_rudder"],
        "gamma_R_minus": pr["gammaN_rudder"], "gamma_R_plus": pr["gammaP_rudder"],
        "t_R": pr["t_rudder"], "a_H": pr["ah_rudder"], "x_H": pr["xh_rudder_nd"] * L,
        "rho_air": pp["rho_air"], "A_T": pp["area_projected_trans"], "A_L": pp["area_projected_lateral"],
        "AOD": pp["AOD"], "LCW": pp["LCW"], "LCBR": pp["LCBR"], "HBR": pp["HBR"], "HC": pp["HC"], "SBW": pp["SBW"],
    }
    if int(sw.get("switch_wind", 1)) == 1:
        part.update(fujiwara_coefficients(part))
    else:
        for k in ("A_T",):
            part.pop(k)
    coef = {"X_0F": pr["xuu_nd"], "X_0A": pr["coeff_drag_aft"], "X_vr": pr["xvr_nd"],
            "XP_k0": (1 - pr["t_prop"]) * pr["kt_coeff0"], "XP_k1": (1 - pr["t_prop"]) * pr["kt_coeff1"],
            "XP_k2": (1 - pr["t_prop"]) * pr["kt_coeff2"],
            "XP_c0": pr["ci_coeff_prop0"], "XP_c1": pr["ci_coeff_prop1"], "XP_c2": pr["ci_coeff_prop2"],
            "XR_gain": 1 - pr["t_rudder"],
            "Y_v": pr["yv_nd"], "Y_r": pr["yr_nd"], "CD_Y": pr["coeff_drag_sway"],
            "N_v": pr["nv_nd"], "N_r": pr["nr_nd"], "CD_N": pr["coeff_drag_sway"],
            "YR_gain": 1 + pr["ah_rudder"],
            "NR_arm": pp["x_location_rudder"] + pr["ah_rudder"] * pr["xh_rudder_nd"] * L}
    for i in range(8):
        coef[f"YP_a{i}"] = pr[f"ai_coeff_prop{i}"]
        coef[f"NP_b{i}"] = pr[f"bi_coeff_prop{i}"]
    src = "NAOE-5thLab/mmg-1p1r-simulator python_module/input_csv @ c54ef807 (Miyauchi et al. 2022)"
    return MmgModel("esso-lowspeed", part, coef, name="esso-osaka-3m-published",
                    sources={"all": src, "equations": "mmg-1p1r-simulator subroutine/*.py; Yoshimura low-speed MMG"})


def _read_flat_yml(path: Path) -> dict[str, float]:
    """Numbers of a one-level YAML mapping (``key: value  # comment``) under one top key."""
    out: dict[str, float] = {}
    for line in path.read_text(encoding="utf-8").splitlines():
        line = line.split("#", 1)[0].rstrip()
        if not line.strip() or ":" not in line or not line.startswith((" ", "\t")):
            continue
        k, v = (s.strip() for s in line.split(":", 1))
        try:
            out[k] = float(v)
        except ValueError:
            continue
    return out


def load_kvlcc2_published(root: Path | None = None) -> MmgModel:
    """KVLCC2 L7 MMG set (Yasukawa & Yoshimura 2015, Table 3) from ``params/kvlcc2_L7_mmg_shipmmg.yml``.

    ``m = ρ ∇``, ``I_zG = m (0.25 L)²`` as the shipmmg tests set them; the wake change
    with β_P uses Yasukawa & Yoshimura's eq. 15 with ``C_1 = 2.0``, ``C_2 = 1.6`` (β_P > 0)
    and 1.1 (β_P < 0) (their Table 3, KVLCC2).
    """
    y = _read_flat_yml(_params_dir(root) / "kvlcc2_L7_mmg_shipmmg.yml")
    rho, L, d = y["ρ"], y["L_pp"], y["d"]
    m = rho * y["nabla"]
    qM, qI = 0.5 * rho * L * L * d, 0.5 * rho * L ** 4 * d
    part = {"L": L, "L_ship": KVLCC2_SHIP_LENGTH, "B": y["B"], "d": d, "rho": rho, "m": m, "x_G": y["x_G"],
            "m_x": y["m_x_dash"] * qM, "m_y": y["m_y_dash"] * qM, "J_z": y["J_z_dash"] * qI,
            "I_zG": m * (0.25 * L) ** 2, "D_p": y["D_p"], "H_R": y["H_R"], "A_R": y["A_R"],
            "w_P0": y["w_P0"], "t_P": y["t_P"], "x_P": y["x_P_dash"], "k_0": y["k_0"], "k_1": y["k_1"],
            "k_2": y["k_2"], "C_1": 2.0, "C_2_plus": 1.6, "C_2_minus": 1.1,
            "eps_R": y["ϵ"], "kappa_R": y["κ"], "f_alpha": y["f_α"], "l_R": y["l_r_dash"],
            "gamma_R_minus": y["γ_R_minus"], "gamma_R_plus": y["γ_R_plus"],
            "t_R": y["t_R"], "a_H": y["a_H"], "x_H": y["x_H_dash"] * L, "x_R": y["x_R_dash"] * L}
    coef = {"R_0": y["R_0_dash"], "X_vv": y["X_vv_dash"], "X_vr": y["X_vr_dash"], "X_rr": y["X_rr_dash"],
            "X_vvvv": y["X_vvvv_dash"], "XP_gain": 1 - y["t_P"], "XR_gain": 1 - y["t_R"],
            "YR_gain": 1 + y["a_H"], "NR_arm": part["x_R"] + y["a_H"] * part["x_H"]}
    for m_ in ("Y", "N"):
        for s in ("v", "r", "vvv", "vvr", "vrr", "rrr"):
            coef[f"{m_}_{s}"] = y[f"{m_}_{s}_dash"]
    return MmgModel("yasukawa2015", part, coef, name="kvlcc2-L7-published",
                    sources={"all": "params/kvlcc2_L7_mmg_shipmmg.yml (ShipMMG/shipmmg tests, MIT)",
                             "equations": "Yasukawa & Yoshimura 2015 eqs. 4-12, 15"})


def load_kvlcc2_hsva_prior(root: Path | None = None) -> MmgModel:
    """The KVLCC2 L7 coefficients on the particulars of the HSVA KVLCC2 model (SIMMAN 2008).

    Particulars from ``kvlcc2_hsva/ship_data_from_repo.yml`` (L 7.0 m, B 1.2688 m,
    T 0.455 m, m 3272 kg, x_G 0.2436 m, I_z 9908.6 kg m², ρ 1000, propeller D 0.204 m,
    A_R, H_R, w_P0, C_1, C_2); every coefficient and the other sub-model constants from
    :func:`load_kvlcc2_published`. Used as the prior/fixed part when identifying from the
    HSVA zig-zags, and as the "published coefficients" baseline on those runs.
    """
    base = load_kvlcc2_published(root)
    r = data_root() if root is None else Path(root)
    path = None if r is None else r / "kvlcc2_hsva" / "ship_data_from_repo.yml"
    if path is None or not path.is_file():
        raise InputError("kvlcc2_hsva/ship_data_from_repo.yml not found in the shared data folder")
    y = {}
    for line in path.read_text(encoding="utf-8").splitlines():
        line = line.split("#", 1)[0]
        if ":" in line:
            k, v = (s_.strip() for s_ in line.split(":", 1))
            try:
                y[k] = float(v)
            except ValueError:
                pass
    p = dict(base.particulars)
    L, d, rho = y["L"], y["T"], y["rho"]
    scale = (rho * L * L * d) / (base.particulars["rho"] * base.particulars["L"] ** 2 * base.particulars["d"])
    p.update(L=L, L_ship=L * y["scale_factor"] if "scale_factor" in y else KVLCC2_SHIP_LENGTH, B=y["B"], d=d,
             rho=rho, m=y["m"], x_G=y["x_G"], I_zG=y["I_z"], D_p=y["D"], A_R=y["A_R"],
             H_R=y["H_R"], w_P0=y["w_p0"], C_1=y["C_1"], C_2_plus=y["C_2_beta_p_pos"],
             C_2_minus=y["C_2_beta_p_neg"], t_P=y["tdf"],
             m_x=base.particulars["m_x"] * scale, m_y=base.particulars["m_y"] * scale,
             J_z=base.particulars["J_z"] * scale)
    coef = dict(base.coef)
    coef["XP_gain"] = 1 - y["tdf"]
    return MmgModel("yasukawa2015", p, coef, name="kvlcc2-L7-coefficients-on-HSVA-particulars",
                    sources={"coefficients": base.sources["all"],
                             "particulars": "kvlcc2_hsva/ship_data_from_repo.yml",
                             "equations": base.sources["equations"]})


PUBLISHED = {"esso_osaka_3m": load_esso_osaka_published, "kvlcc2_L7": load_kvlcc2_published,
             "kvlcc2_hsva": load_kvlcc2_hsva_prior}


def load_published(name: str, root: Path | None = None) -> MmgModel:
    """A published MMG set by name: ``esso_osaka_3m``, ``kvlcc2_L7`` or ``kvlcc2_hsva`` (``-`` or ``_``)."""
    key = name.replace("-", "_")
    for k, fn in PUBLISHED.items():
        if k.lower() == key.lower():
            return fn(root)
    raise InputError(f"unknown published MMG set '{name}' (choose from {', '.join(PUBLISHED)})")


def ship_model(model: MmgModel):
    """The :class:`shipid.models.ship_model.ShipModel` of an MMG model (for the generic simulator)."""

    def x0(speed: float) -> np.ndarray:
        return np.array([0.0, 0.0, 0.0, speed, 0.0, 0.0])

    def outputs(t, X, U):
        return {"x": X[:, 0], "y": X[:, 1], "psi": X[:, 2], "u": X[:, 3], "v": X[:, 4], "r": X[:, 5],
                "delta": U[:, 0], "n": U[:, 1]}

    esso = model.structure in ("esso-lowspeed", "esso-lowspeed-asym", "esso-lowspeed-ext")
    n0 = 10.0 if esso else 10.23
    U0 = 0.5 if esso else 1.179
    return ShipModel(name=model.name, f=dynamics, theta=model, state_names=STATE_NAMES,
                     input_names=INPUT_NAMES, x0=x0, outputs=outputs, service_speed=U0, heading_index=2,
                     u0=lambda speed: np.array([0.0, n0 * speed / U0, 0.0, 0.0]))


__all__ = ["MmgModel", "COEFS", "STATE_NAMES", "INPUT_NAMES", "STRUCTURES", "basis", "forces",
           "accelerations", "rigid_body_forces", "dynamics", "simulate_batch", "apparent_wind",
           "crossflow_integrals", "wind_forces", "fujiwara_coefficients", "load_published",
           "load_esso_osaka_published", "load_kvlcc2_published", "load_kvlcc2_hsva_prior", "ship_model", "mass_terms"]
