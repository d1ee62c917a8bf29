"""Linear state-space forms ``ẋ = A x + B u``, ``y = C x + D u`` of shipid's models.

* **DP low-frequency model** (Fossen, Sagatun & Sørensen 1996, eqs. 50–52): with ``C_h(h) = 0`` the
  momentum equation (35) becomes ``ν̇'' = A'' ν'' + B'' u`` with ``A'' = M''⁻¹ A_h M''`` and
  ``B'' = M''⁻¹ T'' K''`` (ERRATA 001: eq. 50 prints ``B'' = M''⁻¹``; eq. 52 is 3 × 6 and matches
  this reading). The inputs are the control vector of eq. 5, ``u_i = |p_i − p_i0| (p_i − p_i0)``,
  with the azimuth thruster at a fixed angle α (eq. 29: α = 90°). The matrices are exact
  (:func:`shipid.models.dp.derived_A`, :func:`shipid.models.dp.derived_B`), in the bis system of the
  paper (eqs. 26–28, time unit ``sqrt(L/g)``) or in SI (``A = −M⁻¹ D``, ``B = M⁻¹ T K`` of eq. 8).
* **Manoeuvring models** (MMG, Yasukawa & Yoshimura 2015 eq. 4; modified Abkowitz, Yoon & Rhee
  2003 eq. 1) linearised about a straight run at speed ``U``: the trim ``(n, δ₀, v₀)`` that holds
  ``u̇ = v̇ = ṙ = 0`` at ``u = U, r = 0`` (δ₀ and v₀ are zero for a port–starboard symmetric model),
  then the Jacobians of ``(u̇, v̇, ṙ)`` with respect to ``(u, v, r)`` and the inputs ``(δ, n)`` by
  central differences. Where a force has a kink at the straight run (the flow-straightening
  coefficient γ_R switching sides at β_R = 0, ``|v|`` terms) a central difference is the mean of
  the two one-sided slopes. The Abkowitz states are the velocities through the water (the current
  enters only the kinematics). With ``kinematics=True`` the heading and the cross-track position
  are added: ``ψ̇ = r``, ``ẏ = U ψ + v`` (the linearised ``ẏ = u sin ψ + v cos ψ`` at ψ = 0).

:class:`StateSpace` holds the matrices with named states, inputs and outputs and their units,
``to_frame()`` gives the system matrix ``[[A, B], [C, D]]`` as a labelled DataFrame and
``to_control()`` a python-control ``StateSpace`` (optional extra ``shipid[control]``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from scipy.optimize import least_squares

from shipid.errors import InputError, ShipidError
from shipid.export.params import load
from shipid.export.source import Source
from shipid.methods.mmg import manoeuvres as MM
from shipid.models import abkowitz as ab
from shipid.models import dp
from shipid.models import mmg
from shipid.models.thrusters import configuration_matrix

#: Relative step of the central differences (of U, U/L, 1 rad, n).
STEP = 1e-5

_UNITS = {"u": "m/s", "v": "m/s", "r": "rad/s", "psi": "rad", "x": "m", "y": "m", "delta": "rad", "n": "1/s"}


@dataclass(frozen=True)
class StateSpace:
    """``ẋ = A x + B u``, ``y = C x + D u`` with named states, inputs and outputs.

    Attributes
    ----------
    A, B, C, D : ndarray
    states, inputs, outputs : tuple of str
    units : dict of str to str
        Unit of every state, input and output (``"- (bis)"`` in the bis system).
    operating_point : dict
        The point linearised about (speed, propeller rate, trim rudder and sway; the azimuth angle).
    model : str
        Name of the model exported.
    form : str
        The equations the matrices stand for, with their source.
    notes : tuple of str
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    states: tuple
    inputs: tuple
    outputs: tuple
    units: dict = field(default_factory=dict)
    operating_point: dict = field(default_factory=dict)
    model: str = ""
    form: str = ""
    notes: tuple = ()

    def __repr__(self) -> str:
        return (f"StateSpace({self.model!r}: {len(self.states)} states {', '.join(self.states)}; "
                f"inputs {', '.join(self.inputs)}; {self.form})")

    def to_frame(self) -> pd.DataFrame:
        """The system matrix ``[[A, B], [C, D]]``: rows ``d<state>/dt`` and outputs, columns states and
        inputs, each label with its unit."""
        def lab(n):
            return f"{n} [{self.units.get(n, '-')}]"
        M = np.block([[self.A, self.B], [self.C, self.D]])
        rows = [f"d{s}/dt" for s in self.states] + [f"out {o}" for o in self.outputs]
        return pd.DataFrame(M, index=rows, columns=[lab(s) for s in self.states] + [lab(i) for i in self.inputs])

    def summary(self) -> str:
        """The matrices as a table with the operating point and notes (what ``shipid export state-space`` prints)."""
        lines = [f"{self.model}: {self.form}"]
        op = ", ".join(f"{k} {v:.6g}" if isinstance(v, float) else f"{k} {v}" for k, v in self.operating_point.items())
        lines.append(f"operating point: {op}")
        lines += [f"note: {n}" for n in self.notes]
        ev = self.eigenvalues()
        lines.append("eigenvalues of A: " + ", ".join(f"{z.real:.4g}" + (f"{z.imag:+.4g}j" if z.imag else "")
                                                      for z in ev))
        with pd.option_context("display.width", 200, "display.max_columns", 50):
            lines.append(self.to_frame().to_string(float_format=lambda v: f"{v:.5g}"))
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form (matrices as nested lists)."""
        return {"model": self.model, "form": self.form, "states": list(self.states), "inputs": list(self.inputs),
                "outputs": list(self.outputs), "units": dict(self.units),
                "operating_point": dict(self.operating_point), "A": self.A.tolist(), "B": self.B.tolist(),
                "C": self.C.tolist(), "D": self.D.tolist(), "notes": list(self.notes)}

    def eigenvalues(self) -> np.ndarray:
        """Eigenvalues of ``A`` (1/s, or per bis time unit)."""
        return np.linalg.eigvals(self.A)

    def to_control(self):
        """The python-control ``StateSpace`` with the same names (needs ``pip install shipid[control]``)."""
        try:
            import control
        except ImportError:
            raise ShipidError("python-control is not installed: pip install 'shipid[control]' "
                              "(or pip install control)") from None
        return control.ss(self.A, self.B, self.C, self.D, states=list(self.states), inputs=list(self.inputs),
                          outputs=list(self.outputs), name=self.model or None)


# ----------------------------------------------------------------------------- DP, eqs. 50-52
def dp_state_space(vessel: dp.DPVessel, *, units: str = "bis", alpha: float = np.pi / 2,
                   kinematics: bool = False) -> StateSpace:
    """The DP control model of eqs. 50–52 (module docstring).

    Parameters
    ----------
    vessel : DPVessel
        M'' (eq. 30), A_h (eq. 48 or identified), K'' (eq. 49 or identified), the arms of eq. 29.
    units : {"bis", "si"}
        ``"bis"``: ``A'' = M''⁻¹ A_h M''``, ``B'' = M''⁻¹ T'' K''`` as eqs. 51–52 print them;
        ``"si"``: ``A = −M⁻¹ D``, ``B = M⁻¹ T K`` of eq. 8 (s, m, N; inputs still the ``u_i`` of eq. 5).
    alpha : float
        Azimuth angle of thruster 6 (rad) in the configuration matrix (eq. 7; eq. 29 is π/2).
    kinematics : bool
        Add ``η = [x, y, ψ]`` with ``η̇ = ν`` (eq. 13 at ψ = 0).
    """
    if units not in ("bis", "si"):
        raise InputError(f"units must be 'bis' or 'si', got {units!r}")
    if not np.all(np.isfinite(vessel.A_h)) or not np.all(np.isfinite(vessel.K)):
        raise InputError(f"DP vessel {vessel.name!r} has no identified A_h and K (eqs. 48-49)")
    if units == "bis":
        A = dp.derived_A(vessel.M, vessel.A_h)
        B = dp.derived_B(vessel.M, vessel.T(alpha), vessel.K)
        unit = {"u": "- (bis)", "v": "- (bis)", "r": "- (bis)", "x": "- (bis)", "y": "- (bis)", "psi": "rad"}
        form = ("nu'' dot = A'' nu'' + B'' u, A'' = M''^-1 A_h M'', B'' = M''^-1 T'' K'' "
                "(Fossen, Sagatun & Sorensen 1996 eqs. 50-52; ERRATA 001 reading of B'')")
    else:
        par = dp.lf_params(vessel)
        T = configuration_matrix(par.arms, alpha)
        A = -np.linalg.solve(par.M, par.D)
        B = np.linalg.solve(par.M, T * par.K[None, :])
        unit = {"u": "m/s", "v": "m/s", "r": "rad/s", "x": "m", "y": "m", "psi": "rad"}
        form = "nu dot = -M^-1 D nu + M^-1 T K u (eq. 8 with C(nu) = 0 and no current; SI)"
    states = ("u", "v", "r")
    if kinematics:
        states = ("x", "y", "psi") + states
        A = np.block([[np.zeros((3, 3)), np.eye(3)], [np.zeros((3, 3)), A]])
        B = np.vstack([np.zeros((3, B.shape[1])), B])
    inputs = tuple(f"u{i}" for i in range(1, 7))
    units_all = {s: unit[s] for s in states}
    units_all.update({i: "-" for i in inputs})
    n = len(states)
    return StateSpace(A, B, np.eye(n), np.zeros((n, len(inputs))), states, inputs, states, units_all,
                      {"alpha6_deg": float(np.degrees(alpha)), "nu": [0.0, 0.0, 0.0]}, vessel.name, form,
                      ("C_h(h) = 0: the Coriolis term is left out, as eq. 50 does",
                       "inputs u_i = |p_i - p_i0| (p_i - p_i0), the control vector of eq. 5"))


# ----------------------------------------------------------------------------- manoeuvring models
def accelerations(src: Source, nu: np.ndarray, delta: float, n: float) -> np.ndarray:
    """``(u̇, v̇, ṙ)`` of an MMG or Abkowitz model in calm water at velocities ``nu = (u, v, r)``."""
    u, v, r = (float(a) for a in nu)
    if src.family == "mmg":
        x = np.array([0.0, 0.0, 0.0, u, v, r])
        return np.asarray(mmg.dynamics(0.0, x, np.array([delta, n, 0.0, 0.0]), src.model)[3:], float)
    if src.family == "abkowitz":
        p = src.model
        X, Y, N = ab.forces(u, v, r, delta, n, p)
        return np.linalg.solve(p.mass_matrix, ab.rigid_body_rhs(u, v, r, X[0], Y[0], N[0], p))
    raise InputError(f"a {src.family} model is not a manoeuvring model")


def default_speed(src: Source) -> float:
    """The approach speed of the model's recorded conditions, else of its packaged simulator."""
    c = src.conditions
    if c.get("speed"):
        return float(c["speed"])
    if src.family == "mmg":
        if c.get("rps_ahead"):
            return float(MM.equilibrium_speed(src.model, float(c["rps_ahead"])))
        return float(mmg.ship_model(src.model).service_speed)
    return float(src.model.U0)


def straight_rps(src: Source, speed: float) -> float:
    """Propeller rate holding ``speed`` with δ = v = r = 0 (the start of the trim)."""
    if src.family == "mmg":
        return float(MM.equilibrium_rps(src.model, speed))
    p = src.model
    try:
        return float(ab.service_rpm(speed, p.theta_X, p.L))
    except ValueError as err:      # the surge coefficients balance no propeller rate
        raise ShipidError(f"model {src.name!r}: {err} at {speed:g} m/s") from None


@dataclass(frozen=True)
class Trim:
    """A straight run: speed U (m/s), propeller rate n (1/s), rudder δ₀ (rad), sway v₀ (m/s)."""

    speed: float
    rps: float
    delta: float
    v: float
    residual: float


def trim(src: Source, speed: float | None = None) -> Trim:
    """The straight run at ``speed`` (module docstring): solves ``u̇ = v̇ = ṙ = 0`` at ``r = 0`` for ``(n, δ₀, v₀)``.

    Raises
    ------
    ShipidError
        When no trim is found (the residual stays above 1e-9 of the scales ``U²/L``, ``U²/L²``).
    """
    U = default_speed(src) if speed is None else float(speed)
    if not (np.isfinite(U) and U > 0):
        raise InputError(f"speed must be positive, got {U:g}")
    L = src.length
    scale = np.array([U * U / L, U * U / L, U * U / L ** 2])
    n0 = straight_rps(src, U)

    def res(z):
        return accelerations(src, (U, z[2] * U, 0.0), z[1], z[0] * n0) / scale

    z0 = np.array([1.0, 0.0, 0.0])
    r0 = res(z0)
    if np.max(np.abs(r0)) < 1e-12:
        return Trim(U, n0, 0.0, 0.0, float(np.max(np.abs(r0))))
    sol = least_squares(res, z0, xtol=1e-15, ftol=1e-15, gtol=1e-15, method="lm")
    worst = float(np.max(np.abs(sol.fun)))
    if not worst < 1e-9:
        raise ShipidError(f"model {src.name!r}: no straight run at {U:g} m/s (trim residual {worst:.2g})")
    return Trim(U, float(sol.x[0] * n0), float(sol.x[1]), float(sol.x[2] * U), worst)


def jacobians(src: Source, tr: Trim) -> tuple[np.ndarray, np.ndarray]:
    """``(∂ν̇/∂ν (3×3), ∂ν̇/∂(δ, n) (3×2))`` at the trim, by central differences of step :data:`STEP`."""
    U, L = tr.speed, src.length
    x0 = np.array([U, tr.v, 0.0])
    u0 = np.array([tr.delta, tr.rps])
    hx = STEP * np.array([U, U, U / L])
    hu = STEP * np.array([1.0, max(abs(tr.rps), 1e-3)])

    def f(x, u):
        return accelerations(src, x, u[0], u[1])

    A = np.column_stack([(f(x0 + e, u0) - f(x0 - e, u0)) / (2 * h) for e, h in zip(np.diag(hx), hx)])
    B = np.column_stack([(f(x0, u0 + e) - f(x0, u0 - e)) / (2 * h) for e, h in zip(np.diag(hu), hu)])
    return A, B


def manoeuvring_state_space(src: Source, *, speed: float | None = None, kinematics: bool = False) -> StateSpace:
    """An MMG or Abkowitz model linearised about the straight run at ``speed`` (module docstring)."""
    tr = trim(src, speed)
    A, B = jacobians(src, tr)
    states = ("u", "v", "r")
    if kinematics:
        A = np.block([[A, np.zeros((3, 2))], [np.zeros((2, 5))]])
        A[3, 2] = 1.0                      # psi dot = r
        A[4, 1], A[4, 3] = 1.0, tr.speed   # y dot = v + U psi
        B = np.vstack([B, np.zeros((2, 2))])
        states = states + ("psi", "y")
    n = len(states)
    inputs = ("delta", "n")
    units = {k: _UNITS[k] for k in states + inputs}
    if src.family == "mmg":
        form = (f"MMG ({src.model.structure}; Yasukawa & Yoshimura 2015 eq. 4) linearised about the straight run "
                "by central differences")
    else:
        form = "modified Abkowitz model (Yoon & Rhee 2003 eq. 1) linearised about the straight run by central differences"
    notes = []
    if abs(tr.delta) > 0 or abs(tr.v) > 0:
        notes.append(f"asymmetric model: the straight run needs rudder {np.degrees(tr.delta):.4g} deg and sway "
                     f"{tr.v:.3g} m/s; the states and inputs are deviations from them")
    if src.family == "abkowitz":
        notes.append("u, v are velocities through the water (the current enters only the kinematics)")
    op = {"speed": tr.speed, "rps": tr.rps, "delta_deg": float(np.degrees(tr.delta)), "v": tr.v,
          "trim_residual": tr.residual}
    return StateSpace(A, B, np.eye(n), np.zeros((n, 2)), states, inputs, states, units, op, src.name, form,
                      tuple(notes))


def state_space(src: Any, *, speed: float | None = None, units: str = "bis", alpha: float = np.pi / 2,
                kinematics: bool = False) -> StateSpace:
    """The state-space form of any exportable model: :func:`dp_state_space` for the DP family
    (``units``, ``alpha``), :func:`manoeuvring_state_space` for MMG and Abkowitz (``speed``).

    ``src``: a :class:`Source` or anything :func:`shipid.export.params.load` takes.
    """
    src = load(src)
    if src.family == "dp":
        if speed is not None:
            raise InputError("the DP model is linearised at rest (eq. 50); --speed applies to manoeuvring models")
        return dp_state_space(src.model, units=units, alpha=alpha, kinematics=kinematics)
    return manoeuvring_state_space(src, speed=speed, kinematics=kinematics)


__all__ = ["StateSpace", "Trim", "dp_state_space", "manoeuvring_state_space", "state_space", "trim", "jacobians",
           "accelerations", "default_speed", "STEP"]
