"""Nomoto steering models of an identified manoeuvring model, with standard errors.

From the sway–yaw rows of the linearisation about the straight run
(:func:`shipid.export.statespace.manoeuvring_state_space`), ``[v̇, ṙ]ᵀ = a [v, r]ᵀ + b δ``, the yaw
rate follows the rudder by Nomoto's second-order model (Nomoto et al. 1957; Fossen 1994 eq. 6.37)::

    r/δ (s) = K (1 + T3 s) / ((1 + T1 s)(1 + T2 s))

    T1 T2 = 1/det a,   T1 + T2 = −tr a / det a,   K = (a21 b1 − a11 b2)/det a,   K T3 = b2/det a

and the first-order model ``T ṙ + r = K δ`` with ``T = T1 + T2 − T3`` (Fossen 1994 eq. 6.38: the
low-frequency approximation). ``K/T`` is the yaw acceleration per rudder angle at the start of a
rudder step. Non-dimensional ``K' = K L/U``, ``T' = T U/L``. Surge is left out: at the straight run
of a symmetric model it is decoupled from sway and yaw.

A ship close to course instability has a large T2 (a small ``det a``); the first-order T then
describes responses slower than ``T2``, and a first-order fit to a zig-zag (whose period is much
shorter) gives a smaller K and T with about the same ``K/T``. Where ``T1, T2`` are complex (an
oscillatory sway–yaw mode) they are NaN and T is ``−tr a/det a − T3``.

Standard errors: by the delta method (``J Σ Jᵀ`` with ``J`` the central-difference derivative of
``(K, T, T1, T2, T3, K/T)`` with respect to the coefficients, ``Σ`` their covariance,
:attr:`shipid.export.source.Source.cov`), or by Monte Carlo: ``samples`` draws of the coefficients
from ``N(θ̂, Σ)`` with an explicit ``seed``, the sample standard deviation of each quantity (draws
whose linearisation has no straight run are counted and left out). Without a covariance every std
is NaN and :attr:`Nomoto.note` says so.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from shipid.errors import InputError, ShipidError
from shipid.export.params import load
from shipid.export.source import Source
from shipid.export.statespace import jacobians, trim

#: Quantities with a standard error, in the order of :attr:`Nomoto.values`.
QUANTITIES = ("K", "T", "T1", "T2", "T3", "K_over_T", "K_nd", "T_nd")
UNITS = {"K": "1/s", "T": "s", "T1": "s", "T2": "s", "T3": "s", "K_over_T": "1/s^2", "K_nd": "-", "T_nd": "-"}
MEANING = {"K": "rudder gain K (first and second order)", "T": "first-order time constant T = T1 + T2 - T3",
           "T1": "second-order time constant T1", "T2": "second-order time constant T2",
           "T3": "second-order zero T3", "K_over_T": "yaw acceleration per rudder angle K/T",
           "K_nd": "K' = K L / U", "T_nd": "T' = T U / L"}


def nomoto_from_matrices(a: np.ndarray, b: np.ndarray, L: float, U: float) -> np.ndarray:
    """``(K, T, T1, T2, T3, K/T, K', T')`` from the sway–yaw matrices ``a`` (2×2) and ``b`` (2,) (module docstring)."""
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    det = a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]
    tr = a[0, 0] + a[1, 1]
    num0 = a[1, 0] * b[0] - a[0, 0] * b[1]
    if det == 0 or num0 == 0:
        return np.full(len(QUANTITIES), np.nan)
    K = num0 / det
    T3 = b[1] / num0
    S, P = -tr / det, 1.0 / det           # T1 + T2, T1 T2
    disc = S * S - 4 * P
    if disc >= 0:
        T1 = 0.5 * (S - np.sqrt(disc))
        T2 = 0.5 * (S + np.sqrt(disc))
        if abs(T1) > abs(T2):
            T1, T2 = T2, T1
    else:
        T1 = T2 = np.nan
    T = S - T3
    return np.array([K, T, T1, T2, T3, K / T, K * L / U, T * U / L])


@dataclass(frozen=True)
class Nomoto:
    """Nomoto K, T (and T1, T2, T3) of a model at a speed, with standard errors.

    Attributes
    ----------
    values, std : dict of str to float
        :data:`QUANTITIES` (units :data:`UNITS`).
    speed, rps, length : float
        The straight run (m/s, 1/s) and the ship length (m).
    model : str
    method : str
        ``"delta"``, ``"monte-carlo"`` or ``"none"``.
    note : str
        Where the std came from (the covariance used, draws left out).
    """

    values: dict
    std: dict
    speed: float
    rps: float
    length: float
    model: str = ""
    method: str = "none"
    note: str = ""
    samples: int = 0
    seed: int | None = None
    extra: dict = field(default_factory=dict)

    @property
    def K(self) -> float:
        return self.values["K"]

    @property
    def T(self) -> float:
        return self.values["T"]

    def __repr__(self) -> str:
        def pm(k):
            s = self.std[k]
            return f"{self.values[k]:.4g}" + ("" if not np.isfinite(s) else f" ± {s:.2g}")
        return (f"Nomoto({self.model!r} at {self.speed:.4g} m/s: K = {pm('K')} 1/s, T = {pm('T')} s; "
                f"T1 = {pm('T1')}, T2 = {pm('T2')}, T3 = {pm('T3')} s)")

    def to_frame(self) -> pd.DataFrame:
        """One row per quantity: value, std, unit, meaning."""
        return pd.DataFrame({"value": [self.values[k] for k in QUANTITIES],
                             "std": [self.std[k] for k in QUANTITIES],
                             "unit": [UNITS[k] for k in QUANTITIES],
                             "meaning": [MEANING[k] for k in QUANTITIES]}, index=list(QUANTITIES))

    def summary(self) -> str:
        """A table of the quantities with std, unit and meaning (what ``shipid export nomoto`` prints)."""
        lines = [f"{self.model}: Nomoto models at {self.speed:.4g} m/s, propeller {self.rps:.4g} rev/s, "
                 f"L {self.length:.4g} m",
                 f"{'':10s} {'value':>12s} {'std':>10s}  {'unit':6s} meaning"]
        for k in QUANTITIES:
            sd = self.std[k]
            lines.append(f"{k:10s} {self.values[k]:12.5g} {('-' if not np.isfinite(sd) else f'{sd:.3g}'):>10s}  "
                         f"{UNITS[k]:6s} {MEANING[k]}")
        lines.append(f"std: {self.note}")
        lines += [f"note: {n}" for n in self.extra.get("notes", [])]
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        return {"model": self.model, "speed": self.speed, "rps": self.rps, "length": self.length,
                "values": dict(self.values), "std": dict(self.std), "units": dict(UNITS), "method": self.method,
                "note": self.note, "samples": self.samples, "seed": self.seed, **self.extra}


def _notes(vals: np.ndarray) -> list[str]:
    v = dict(zip(QUANTITIES, vals))
    out = []
    if np.isfinite(v["T2"]) and v["T2"] < 0:
        out.append("course-unstable at this speed (T2 < 0): K and T describe an unstable yaw mode")
    elif np.isfinite(v["T2"]) and v["T2"] > 20 * max(abs(v["T1"]), abs(v["T3"])):
        out.append("T2 is much longer than T1 and T3 (nearly course-unstable): the first-order T holds for "
                   "responses slower than T2; a first-order fit to a zig-zag gives a smaller K and T with about "
                   "the same K/T")
    return out


def _evaluate(src: Source, speed: float) -> tuple[np.ndarray, Any]:
    tr = trim(src, speed)
    A, B = jacobians(src, tr)
    return nomoto_from_matrices(A[1:, 1:], B[1:, 0], src.length, tr.speed), tr


def nomoto(src: Any, *, speed: float | None = None, samples: int = 0, seed: int | None = None) -> Nomoto:
    """Nomoto K, T, T1, T2, T3 of an MMG or Abkowitz model at ``speed`` (module docstring).

    Parameters
    ----------
    src : Source
        Or anything :func:`shipid.export.params.load` takes.
    speed : float, optional
        Approach speed (m/s) [default: the model's recorded or packaged approach speed].
    samples : int
        0: std by the delta method; > 0: Monte Carlo with that many draws (``seed`` required).
    seed : int, optional
        Seed of the Monte Carlo draws.
    """
    src = load(src)
    if src.family not in ("mmg", "abkowitz"):
        raise InputError(f"Nomoto models are for manoeuvring models (MMG, EBM); {src.name!r} is a model of the {src.family} family")
    vals, tr = _evaluate(src, speed)
    U = tr.speed
    nan = {k: float("nan") for k in QUANTITIES}
    if src.cov is None or not src.cov_names:
        return Nomoto(dict(zip(QUANTITIES, map(float, vals))), nan, U, tr.rps, src.length, src.name, "none",
                      f"none ({src.cov_note})", extra={"notes": _notes(vals)})
    names = list(src.cov_names)
    theta = np.array([src.coef[k] for k in names])
    C = 0.5 * (src.cov + src.cov.T)
    if samples > 0:
        if seed is None:
            raise InputError("Monte Carlo standard errors need an explicit seed")
        rng = np.random.default_rng(seed)
        draws = rng.multivariate_normal(theta, C, size=int(samples), method="svd")
        out, failed = [], 0
        for d in draws:
            try:
                out.append(_evaluate(src.with_coefficients(dict(zip(names, d))), U)[0])
            except ShipidError:
                failed += 1
        if len(out) < 2:
            raise ShipidError(f"Monte Carlo: {failed} of {samples} draws have no straight run")
        sd = np.nanstd(np.array(out), axis=0, ddof=1)
        note = (f"Monte Carlo, {samples} draws from N(theta, Sigma), seed {seed}; Sigma: {src.cov_note}"
                + (f"; {failed} draws without a straight run left out" if failed else ""))
        return Nomoto(dict(zip(QUANTITIES, map(float, vals))), dict(zip(QUANTITIES, map(float, sd))), U, tr.rps,
                      src.length, src.name, "monte-carlo", note, int(samples), int(seed),
                      {"draws_left_out": failed, "notes": _notes(vals)})
    sd_theta = np.sqrt(np.clip(np.diag(C), 0, None))
    J = np.zeros((len(QUANTITIES), len(names)))
    for j, nm in enumerate(names):
        h = 1e-3 * sd_theta[j] if sd_theta[j] > 0 else 1e-6 * max(abs(theta[j]), 1e-12)
        if not h > 0:
            continue
        up = _evaluate(src.with_coefficients({nm: theta[j] + h}), U)[0]
        dn = _evaluate(src.with_coefficients({nm: theta[j] - h}), U)[0]
        J[:, j] = (up - dn) / (2 * h)
    V = J @ C @ J.T
    sd = np.sqrt(np.clip(np.diag(V), 0, None))
    return Nomoto(dict(zip(QUANTITIES, map(float, vals))), dict(zip(QUANTITIES, map(float, sd))), U, tr.rps,
                  src.length, src.name, "delta", f"delta method; Sigma: {src.cov_note}", extra={"notes": _notes(vals)})


__all__ = ["Nomoto", "nomoto", "nomoto_from_matrices", "QUANTITIES", "UNITS", "MEANING"]
