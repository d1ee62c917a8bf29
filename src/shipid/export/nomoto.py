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

Zig-zag K and T (``about="zigzag-10"``, or another ``zigzag-D[-P]``): the first-order model that describes
the ship in the manoeuvre an autopilot sees (Nomoto et al. 1957; ITTC Recommended Procedure 7.5-04-02-01,
Z-manoeuvre: K' and T' from the 10/10 zig-zag). The model's zig-zag is simulated at ``speed`` for
:data:`ZIGZAG_DURATION` ship lengths (L/U) with samples every :data:`ZIGZAG_DT` ship lengths, and
``T ṙ + r = K δ + c`` is fitted to its yaw rate by least squares (:func:`zigzag_fit`; ``c`` absorbs a
neutral rudder angle ``δ_n = −c/K``). T1, T2, T3 are not defined there (NaN). The fit's own standard
errors (from its Jacobian and residuals, which are the response the first-order model leaves out and are
correlated in time: the white-noise std is scaled by ``sqrt(n / n_eff)``, :func:`effective_samples`) and the
residual rms are in ``extra["fit"]``. :attr:`Nomoto.std` of a zig-zag K, T is the std from the
coefficients' covariance (as for the straight run) and the fit's own std in quadrature: the fit's alone
when the model has no covariance. Where the fitted T is not within the record (the zig-zag's yaw rate
grows, as for a course-unstable ship), K and T have an infinite std: only K/T is determined.

Standard errors: by the delta method (``J Σ Jᵀ`` with ``J`` the central-difference derivative of
``(K, T, T1, T2, T3, K/T)`` with respect to the coefficients, ``Σ`` their covariance,
:attr:`shipid.export.source.Source.cov`), or by Monte Carlo: ``samples`` draws of the coefficients
from ``N(θ̂, Σ)`` with an explicit ``seed``, the sample standard deviation of each quantity (draws
with no straight run, or whose zig-zag diverges, are counted and left out) and its 16, 50 and 84 % percentiles
(``extra["percentiles_16_50_84"]``: where some draws are course-unstable K and T are heavy-tailed).
Without a covariance every straight-run std is NaN and :attr:`Nomoto.note` says so. A quantity whose std exceeds its magnitude
(:data:`shipid.summary.REL_SE_UNDETERMINED`) has status ``not determined`` (:attr:`Nomoto.status`) and is
printed as such, not as an estimate.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from scipy.optimize import least_squares
from scipy.signal import lfilter

from shipid.errors import InputError, ShipidError
from shipid.export.params import load, simulate_source
from shipid.export.source import Source
from shipid.export.statespace import default_speed, jacobians, trim
from shipid.simulate.manoeuvres import parse_manoeuvre
from shipid.summary import NOT_DETERMINED, REL_SE_UNDETERMINED

#: Quantities with a standard error, in the order of :attr:`Nomoto.values`.
QUANTITIES = ("K", "T", "T1", "T2", "T3", "K_over_T", "K_nd", "T_nd")
UNITS = {"K": "1/s", "T": "s", "T1": "s", "T2": "s", "T3": "s", "K_over_T": "1/s^2", "K_nd": "-", "T_nd": "-"}
MEANING = {"K": "rudder gain K (first and second order)", "T": "first-order time constant T = T1 + T2 - T3",
           "T1": "second-order time constant T1", "T2": "second-order time constant T2",
           "T3": "second-order zero T3", "K_over_T": "yaw acceleration per rudder angle K/T",
           "K_nd": "K' = K L / U", "T_nd": "T' = T U / L"}
#: Meanings that differ for K and T fitted to a zig-zag.
MEANING_ZIGZAG = {"K": "first-order rudder gain K fitted to the zig-zag",
                  "T": "first-order time constant T fitted to the zig-zag"}
#: The straight-run linearisation (``about`` default).
STRAIGHT = "straight-run"
#: Simulated zig-zag length and sample interval, in ship lengths (times L/U).
ZIGZAG_DURATION, ZIGZAG_DT = 24.0, 0.02


def zigzag_fit(t: np.ndarray, r: np.ndarray, delta: np.ndarray) -> dict[str, Any]:
    """First-order ``T ṙ + r = K δ + c`` fitted to the yaw rate of a record with uniform steps (module
    docstring): the exact response with the rudder held over each step, by least squares from the
    equation-error (ARX) start; standard errors ``s² (JᵀJ)⁻¹`` from the residuals, the residual rms of
    ``r`` (rad/s) and the neutral rudder angle ``−c/K`` (rad)."""
    t, r, delta = (np.asarray(a, float) for a in (t, r, delta))
    h = float(t[1] - t[0])
    X = np.column_stack([r[:-1], delta[:-1], np.ones(r.size - 1)])
    a0, b0, e0 = np.linalg.lstsq(X, r[1:], rcond=None)[0]
    a0 = min(max(a0, 1e-6), 1 - 1e-9)
    q0 = np.array([b0 / (1 - a0), -h / np.log(a0), e0 / (1 - a0)])

    def response(q):
        K, T, c = q
        a = np.exp(-h / T)
        u = (1 - a) * (K * delta[:-1] + c)
        out, _ = lfilter([1.0], [1.0, -a], u, zi=[a * r[0]])
        return np.concatenate([[r[0]], out])

    scale = np.abs(q0) + np.array([1e-9, 1e-9, 1e-12])
    try:
        sol = least_squares(lambda q: response(q) - r, q0, x_scale=scale)
    except ValueError as err:                   # a non-finite start: no first-order model to fit
        raise ShipidError(f"no first-order fit to the zig-zag: {err}") from None
    dof = max(r.size - 3, 1)
    cov = float(sol.fun @ sol.fun) / dof * np.linalg.pinv(sol.jac.T @ sol.jac)
    inflation = r.size / effective_samples(sol.fun)
    sd = np.sqrt(np.clip(np.diag(cov), 0, None) * inflation)
    K, T, c = (float(v) for v in sol.x)
    return {"K": K, "T": T, "c": c, "K_std": float(sd[0]), "T_std": float(sd[1]), "inflation": float(inflation),
            "cov_KT": (cov[:2, :2] * inflation).tolist(),
            "rms_r": float(np.sqrt(np.mean(sol.fun ** 2))), "delta_n": -c / K if K else float("nan")}


def effective_samples(e: np.ndarray) -> float:
    """``n / (1 + 2 Σ ρ_k)`` of residuals ``e``, the sum of their autocorrelation up to its first
    non-positive lag (Bartlett 1946; Box, Jenkins & Reinsel 2008 eq. 2.1.13): the residuals of a
    first-order fit to a zig-zag are the response it leaves out, correlated over a yaw period."""
    e = np.asarray(e, float) - np.mean(e)
    n = e.size
    f = np.fft.rfft(e, 2 * n)
    acf = np.fft.irfft(f * np.conj(f))[:n]
    if not acf[0] > 0:
        return float(n)
    rho = acf / acf[0]
    stop = np.flatnonzero(rho[1:] <= 0)
    m = int(stop[0]) + 1 if stop.size else n
    return float(n / max(1.0, 1.0 + 2.0 * np.sum(rho[1:m])))


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
        ``"delta"``, ``"monte-carlo"``, ``"none"``, or ``"zigzag-fit"`` (a zig-zag fit's own std alone).
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
    about: str = STRAIGHT

    @property
    def status(self) -> dict:
        """Per quantity: ``estimated``, ``not determined`` (std above its magnitude) or ``no std``."""
        out = {}
        for k in QUANTITIES:
            v, sd = self.values[k], self.std[k]
            if np.isfinite(v) and sd == np.inf:
                out[k] = NOT_DETERMINED
            elif not (np.isfinite(v) and np.isfinite(sd)):
                out[k] = "no std"
            elif sd > REL_SE_UNDETERMINED * abs(v):
                out[k] = NOT_DETERMINED
            else:
                out[k] = "estimated"
        return out

    @property
    def K(self) -> float:
        return self.values["K"]

    @property
    def T(self) -> float:
        return self.values["T"]

    def __repr__(self) -> str:
        st = self.status

        def pm(k):
            s = self.std[k]
            if st[k] == NOT_DETERMINED:
                return f"not determined (std {s:.2g})"
            return f"{self.values[k]:.4g}" + ("" if not np.isfinite(s) else f" ± {s:.2g}")
        about = "" if self.about == STRAIGHT else f" from {self.about}"
        return (f"Nomoto({self.model!r}{about} at {self.speed:.4g} m/s: K = {pm('K')} 1/s, T = {pm('T')} s; "
                f"T1 = {pm('T1')}, T2 = {pm('T2')}, T3 = {pm('T3')} s)")

    def meaning(self, k: str) -> str:
        """What quantity ``k`` is (:data:`MEANING`, or :data:`MEANING_ZIGZAG` for a zig-zag fit)."""
        return MEANING_ZIGZAG.get(k, MEANING[k]) if self.about != STRAIGHT else MEANING[k]

    def to_frame(self) -> pd.DataFrame:
        """One row per quantity: value, std, status, unit, meaning."""
        st = self.status
        return pd.DataFrame({"value": [self.values[k] for k in QUANTITIES],
                             "std": [self.std[k] for k in QUANTITIES],
                             "status": [st[k] for k in QUANTITIES],
                             "unit": [UNITS[k] for k in QUANTITIES],
                             "meaning": [self.meaning(k) for k in QUANTITIES]}, index=list(QUANTITIES))

    def summary(self) -> str:
        """A table of the quantities with std, unit and meaning (what ``shipid export nomoto`` prints)."""
        about = ("linearised about the straight run" if self.about == STRAIGHT
                 else f"first order fitted to its {self.about} yaw rate")
        lines = [f"{self.model}: Nomoto models at {self.speed:.4g} m/s, propeller {self.rps:.4g} rev/s, "
                 f"L {self.length:.4g} m, {about}",
                 f"{'':10s} {'value':>14s} {'std':>10s}  {'unit':6s} meaning"]
        st = self.status
        for k in QUANTITIES:
            sd, v = self.std[k], self.values[k]
            if self.about != STRAIGHT and k in ("T1", "T2", "T3"):
                continue
            val = "not determined" if st[k] == NOT_DETERMINED else f"{v:.5g}"
            lines.append(f"{k:10s} {val:>14s} {('-' if np.isnan(sd) else f'{sd:.3g}'):>10s}  "
                         f"{UNITS[k]:6s} {self.meaning(k)}")
        lines.append(f"std: {self.note}")
        nd = [k for k in QUANTITIES if st[k] == NOT_DETERMINED]
        if nd:
            lines.append(f"not determined (std above the magnitude): {', '.join(nd)}")
        band = self.extra.get("percentiles_16_50_84", {})
        if band:
            lines.append("Monte Carlo 16/50/84 %: " + "; ".join(
                f"{k} {band[k][0]:.3g} / {band[k][1]:.3g} / {band[k][2]:.3g}" for k in ("K", "T", "K_over_T") if k in band))
        fit = self.extra.get("fit")
        if fit:
            lines.append(f"zig-zag fit: {fit['duration']:.4g} s at {fit['dt']:.3g} s, r residual rms "
                         f"{np.rad2deg(fit['rms_r']):.2g} deg/s, fit std K {fit['K_std']:.2g} 1/s, T {fit['T_std']:.2g} s "
                         f"(correlated residuals: x{np.sqrt(fit['inflation']):.2g}), neutral rudder {np.rad2deg(fit['delta_n']):.3g} deg")
        lines += [f"note: {n}" for n in self.extra.get("notes", [])]
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        return {"model": self.model, "about": self.about, "speed": self.speed, "rps": self.rps,
                "length": self.length, "values": dict(self.values), "std": dict(self.std), "status": self.status,
                "units": dict(UNITS), "method": self.method,
                "note": self.note, "samples": self.samples, "seed": self.seed, **self.extra}


def _notes(vals: np.ndarray) -> list[str]:
    v = dict(zip(QUANTITIES, vals))
    out = []
    if np.isfinite(v["T2"]) and v["T2"] < 0:
        out.append("course-unstable at this speed (T2 < 0): K and T describe an unstable yaw mode")
    elif np.isfinite(v["T2"]) and v["T2"] > 20 * max(abs(v["T1"]), abs(v["T3"])):
        out.append("T2 >> T1, T3 (nearly course-unstable): this T holds for responses slower than T2; the K, T of a "
                   "zig-zag (about='zigzag-10') are smaller, with about the same K/T")
    return out


def _evaluate(src: Source, speed: float | None, about: str = STRAIGHT) -> tuple[np.ndarray, float, float, dict]:
    """``(values, U, rps, fit)`` of the straight-run linearisation or of the zig-zag fit (module docstring)."""
    if about == STRAIGHT:
        tr = trim(src, speed)
        A, B = jacobians(src, tr)
        return nomoto_from_matrices(A[1:, 1:], B[1:, 0], src.length, tr.speed), tr.speed, tr.rps, {}
    U = default_speed(src) if speed is None else float(speed)
    L = src.length
    dur, dt = ZIGZAG_DURATION * L / U, ZIGZAG_DT * L / U
    with np.errstate(all="ignore"):              # a draw that diverges is refused below, not warned about
        trial = simulate_source(src, about, duration=dur, dt=dt, speed=U)[0]
        if not np.all(np.isfinite(trial["r"])):
            raise ShipidError(f"model {src.name!r}: the simulated {about} diverges")
        fit = zigzag_fit(trial.t, trial["r"], trial["delta"])
    K, T = fit["K"], fit["T"]
    nan = float("nan")
    vals = np.array([K, T, nan, nan, nan, K / T, K * L / U, T * U / L])
    rps = float(trial.meta.get("rps", trial["n"][0] if "n" in trial.channels else nan))
    return vals, U, rps, {**fit, "duration": dur, "dt": dt}


def _check_about(about: str) -> str:
    about = str(about)
    if about != STRAIGHT:
        try:
            kind = parse_manoeuvre(about).kind
        except ShipidError as err:
            raise InputError(f"Nomoto models come from {STRAIGHT!r} or a zig-zag such as 'zigzag-10': {err}") from None
        if kind != "zigzag":
            raise InputError(f"Nomoto models come from {STRAIGHT!r} or a zig-zag such as 'zigzag-10', not {about!r}")
    return about


def nomoto(src: Any, *, speed: float | None = None, samples: int = 0, seed: int | None = None,
           about: str = STRAIGHT) -> Nomoto:
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
    about : str
        ``"straight-run"``: K, T, T1, T2, T3 of the linearisation about the straight run (Fossen 1994
        eqs. 6.37-6.38); a zig-zag name such as ``"zigzag-10"``: first-order K, T fitted to the model's
        simulated zig-zag by Nomoto's analysis (Nomoto et al. 1957).
    """
    src = load(src)
    about = _check_about(about)
    if src.family not in ("mmg", "abkowitz"):
        raise InputError(f"Nomoto models are for manoeuvring models (MMG, EBM); {src.name!r} is a model of the {src.family} family")
    vals, U, rps, fit = _evaluate(src, speed, about)
    notes = _notes(vals)
    if fit and not 0 < fit["T"] < fit["duration"]:
        notes.append(f"the zig-zag fit's T ({fit['T']:.3g} s) is not within the record ({fit['duration']:.4g} s): "
                     "the yaw rate grows as if course-unstable, and only K/T is determined by this zig-zag")
    extra = {"notes": notes} | ({"fit": fit} if fit else {})
    common = dict(speed=U, rps=rps, length=src.length, model=src.name, about=about)
    values = dict(zip(QUANTITIES, map(float, vals)))
    if src.cov is None or not src.cov_names:
        sd, method, note, mc = np.full(len(QUANTITIES), np.nan), "none", f"none ({src.cov_note})", {}
    elif samples > 0:
        if seed is None:
            raise InputError("Monte Carlo standard errors need an explicit seed")
        sd, note, mc = _monte_carlo(src, U, about, int(samples), int(seed))
        method = "monte-carlo"
    else:
        sd, method, note, mc = _delta(src, U, about), "delta", f"delta method; Sigma: {src.cov_note}", {}
    if fit and method == "none":
        sd, method = np.sqrt(_fit_variance(fit, src.length, U)), "zigzag-fit"
        note = f"the zig-zag fit's own std alone (the coefficients have {note[6:-1]})"
    elif fit:
        sd = np.sqrt(np.where(np.isfinite(sd), sd, 0.0) ** 2 + _fit_variance(fit, src.length, U))
        note += "; the zig-zag fit's own std added in quadrature"
    return Nomoto(values, dict(zip(QUANTITIES, map(float, sd))), method=method, note=note,
                  samples=int(samples) if mc else 0, seed=int(seed) if mc else None, extra={**mc, **extra}, **common)


def _fit_variance(fit: dict, L: float, U: float) -> np.ndarray:
    """Variance of :data:`QUANTITIES` from the zig-zag fit's covariance of ``(K, T)`` (NaN for T1, T2, T3;
    infinite for K and T where the fitted T is not within the record)."""
    C = np.asarray(fit["cov_KT"], float)
    K, T = fit["K"], fit["T"]
    g = np.array([1.0 / T, -K / T ** 2])
    nan = float("nan")
    if not 0 < T < fit["duration"]:             # T runs off: the record determines K/T alone
        return np.array([np.inf, np.inf, nan, nan, nan, g @ C @ g, np.inf, np.inf])
    return np.array([C[0, 0], C[1, 1], nan, nan, nan, g @ C @ g, C[0, 0] * (L / U) ** 2, C[1, 1] * (U / L) ** 2])


def _monte_carlo(src: Source, U: float, about: str, samples: int, seed: int) -> tuple[np.ndarray, str, dict]:
    """Sample std of :data:`QUANTITIES` over ``samples`` draws from ``N(θ̂, Σ)`` (module docstring)."""
    names = list(src.cov_names)
    theta = np.array([src.coef[k] for k in names])
    C = 0.5 * (src.cov + src.cov.T)
    rng = np.random.default_rng(seed)
    draws = rng.multivariate_normal(theta, C, size=samples, method="svd")
    out, failed = [], 0
    for d in draws:
        try:
            out.append(_evaluate(src.with_coefficients(dict(zip(names, d))), U, about)[0])
        except ShipidError:
            failed += 1
    if len(out) < 2:
        raise ShipidError(f"Monte Carlo: {failed} of {samples} draws have no straight run or a diverging zig-zag")
    arr = np.array(out)
    ok = np.isfinite(arr).sum(axis=0) >= 2
    sd = np.full(arr.shape[1], np.nan)
    sd[ok] = np.nanstd(arr[:, ok], axis=0, ddof=1)
    band = {k: [float(x) for x in np.nanpercentile(arr[:, j], [16, 50, 84])]
            for j, k in enumerate(QUANTITIES) if ok[j]}
    note = (f"Monte Carlo, {samples} draws from N(theta, Sigma), seed {seed}; Sigma: {src.cov_note}"
            + (f"; {failed} draws left out ({'no straight run' if about == STRAIGHT else 'no straight run or a diverging zig-zag'})"
               if failed else ""))
    return sd, note, {"draws_left_out": failed, "percentiles_16_50_84": band}


def _delta(src: Source, U: float, about: str) -> np.ndarray:
    """Delta-method std of :data:`QUANTITIES`: ``J Σ Jᵀ`` with central differences (module docstring)."""
    names = list(src.cov_names)
    theta = np.array([src.coef[k] for k in names])
    C = 0.5 * (src.cov + src.cov.T)
    var = np.clip(np.diag(C), 0, None)
    J = np.zeros((len(QUANTITIES), len(names)))
    for j, nm in enumerate(names):
        if var[j] == 0:                   # no uncertainty: no column of J needed
            continue
        h = 1e-3 * np.sqrt(var[j])
        up = _evaluate(src.with_coefficients({nm: theta[j] + h}), U, about)[0]
        dn = _evaluate(src.with_coefficients({nm: theta[j] - h}), U, about)[0]
        J[:, j] = (up - dn) / (2 * h)
    return np.sqrt(np.clip(np.diag(J @ C @ J.T), 0, None))

__all__ = ["Nomoto", "nomoto", "nomoto_from_matrices", "zigzag_fit", "STRAIGHT", "QUANTITIES", "UNITS", "MEANING"]
