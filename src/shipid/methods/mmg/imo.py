"""IMO MSC.137(76) Standards for ship manoeuvrability, assessed on an identified MMG model with bands.

Criteria (Resolution MSC.137(76), 4 December 2002, §5.3–5.4; definitions §4.2 and
ITTC 7.5-04-02-01, :mod:`shipid.simulate.metrics`):

* **Turning ability** (§5.3.1): 35° turning circle to either side, advance ≤ 4.5 L
  and tactical diameter ≤ 5 L.
* **Initial turning ability** (§5.3.2): 10° rudder to either side; the ship should
  not have travelled more than 2.5 L (along its track) by the time the heading has
  changed 10° from the original heading (measured in the 10°/10° zig-zag).
* **Yaw-checking and course-keeping** (§5.3.3): first overshoot of the 10°/10°
  zig-zag ≤ 10° if L/V < 10 s, ≤ 20° if L/V ≥ 30 s, ≤ (5 + ½ L/V)° in between;
  second overshoot of the 10°/10° zig-zag ≤ 25°, 40°, (17.5 + 0.75 L/V)° (the first
  limit + 15° at the ends); first overshoot of the 20°/20° zig-zag ≤ 25°.
* **Stopping ability** (§5.4): track reach of the full-astern stopping test ≤ 15 L
  (an Administration may accept up to 20 L for large, low-powered ships); only where
  the model has an astern propeller model (the ``esso-*`` structures, Hachii's
  thrust for n < 0); otherwise "not available".

Scale: the criteria in ship lengths hold at any Froude-similar scale; the overshoot
limits depend on the *full-scale* L/V in seconds, ``(L/V)_ship = (L/U)_model √λ``
with ``λ = L_ship / L_model``. The full-scale length is the one given (``ship_length``) or the
model's ``particulars["L_ship"]``, which the published priors carry (ESSO OSAKA 325 m, KVLCC2
320 m) and an identified model inherits; a model without one needs ``ship_length``: there is no
silent default. The steering gear is the slowest SOLAS allows (2.32°/s: 35° to 30° the other side
in 28 s, II-1 reg. 29.3.2) at model scale, ``2.32 √λ`` °/s, unless a rate is given. Both values
and where they came from are in the report's header and JSON. The stopping test uses
the training runs' propeller reversal, so its track reach is the model's.

Uncertainty: ``samples`` coefficient vectors are drawn (seeded) from N(θ̂, Σ) of the
identified model's free coefficients (``covariance``, ``covariance_names`` of
MODEL.json; fixed coefficients stay fixed) and every manoeuvre is simulated for each
(one batch, :mod:`shipid.methods.mmg.manoeuvres`), each draw from its own straight-line
equilibrium at the approach (:func:`approach_rows`: the speed at the propeller rate, or the rate
at a given speed, whichever was not given). Each criterion reports the
nominal value (the point estimate), the Monte Carlo standard deviation and the
2.275 %–97.725 % quantile band (the ±2-std band of a normal; quantiles rather than
nominal ± 2 std so that a skewed response shows), and P(pass) over the draws (against
the strictest limit where the limit is a range). The covariance is the one MODEL.json
carries: ``identify mmg`` stores a run-bootstrap covariance (five or more training
runs) or a HAC sandwich (:mod:`shipid.methods.mmg.covariance`, where the split-half
check shows why the ridge standard errors, which assume independent residuals, are
5–9 times too small); its description is ``diagnostics["covariance"]["kind"]``
and is printed with the bands. A MODEL.json without it is taken to carry ridge errors.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from shipid.errors import InputError
from shipid.methods.mmg import manoeuvres as MM
from shipid.methods.mmg.pipeline import FORM_CHECK_SE
from shipid.simulate.metrics import turning_metrics, zigzag_metrics
from shipid.methods.mmg.validate import model_from_result

#: Quantiles of the band (the ±2-std probabilities of a normal).
BAND = (2.275, 97.725)
#: What :func:`assess` adds where the model's standard errors are flagged by
#: :func:`shipid.methods.mmg.pipeline.form_check` (figures: ``docs/validation/mmg.md``).
FORM_BANDS = ("the bands are too narrow for such a model: in the simulated seven-zig-zag KVLCC2 coverage study "
              "(docs/validation/mmg.md) the differential form's bands held the truth 0.31-0.33 of the time for "
              "the initial turning, 0.53-0.70 for the first overshoots and 0.88-0.89 for the advance; identified "
              "with --equation integral, 0.93-0.96 for the turning criteria")
#: What :func:`assess` adds for such a model when its bands include the model-form term (the default).
FORM_TERM_BANDS = ("the bands include the two forms' difference as one standard deviation of model-form error: "
                   "in the simulated seven-zig-zag KVLCC2 coverage study (docs/validation/mmg.md) they held the "
                   "truth 0.99-1.00 of the time for every criterion, conservative "
                   "(tactical diameter: mean std 0.032 L, error RMS 0.013 L); the same draws without the term "
                   "(--no-form-term) 0.30-0.31 for the initial turning, 0.52-0.63 for the first overshoots")
#: What the bands do not hold, as the simulated coverage study measured it (``docs/validation/mmg.md``).
BAND_CAVEAT = ("the bands carry the coefficients' estimation uncertainty, not a bias of the fit: in the simulated "
               "coverage studies (docs/validation/mmg.md), on four-run campaigns of the Esso Osaka 3 m "
               "they held the truth 0.98-1.00 of the time for every criterion, a little wide for the turning "
               "ones (advance: mean std 0.022 L, error RMS 0.018 L, bias +0.007 L); on seven-zig-zag KVLCC2 "
               "campaigns in the integral form (identified with --equation integral) 0.93-0.96 for the "
               "turning criteria and 0.81-0.89 for the overshoots, whose errors (RMS 0.01-0.03 deg) are at the "
               "resolution of the simulation; in the differential form much less (a warning says so)")
#: Maximum stopping track reach (ship lengths).
STOPPING_LIMIT = 15.0
#: Slowest steering gear SOLAS II-1 reg. 29.3.2 allows (deg/s): 35° one side to 30° the other in 28 s.
SOLAS_RUDDER_RATE = 65.0 / 28.0


def overshoot_limits(l_over_v: float | None) -> tuple[tuple[float, float], tuple[float, float]]:
    """(min, max) limits (deg) of the 10°/10° first and second overshoots for full-scale L/V (s);
    ``None``: the range over all L/V."""
    if l_over_v is None:
        return (10.0, 20.0), (25.0, 40.0)
    if l_over_v < 10.0:
        a, b = 10.0, 25.0
    elif l_over_v >= 30.0:
        a, b = 20.0, 40.0
    else:
        a, b = 5.0 + 0.5 * l_over_v, 17.5 + 0.75 * l_over_v
    return (a, a), (b, b)


def form_delta(result: Mapping[str, Any], names: list[str]) -> np.ndarray | None:
    """The model-form term ``δ = θ̂ − θ_integral`` over ``names`` from the MODEL.json's
    ``diagnostics.form_check`` (:func:`shipid.methods.mmg.pipeline.form_check`); None where the model has
    no such check (integral form, refined, or published).

    Every coefficient the integral fit has enters, the "not determined" ones too, so that ``θ̂ − δ`` is the
    integral form's whole model: a draw that moved only the well-determined coefficients would combine
    one form's cubic terms with the other's linear ones (on one simulated KVLCC2 truth that gave a 35°
    tactical diameter 0.21 L from both forms' and the truth's, which agree within 0.015 L)."""
    check = (result.get("diagnostics") or {}).get("form_check") or {}
    other = check.get("integral") or {}
    if not other:
        return None
    coef = result["model"]["coefficients"]
    return np.array([float(coef[n]) - float(other[n]) if n in other else 0.0 for n in names])


def sample_coefficients(result: Mapping[str, Any], samples: int, seed: int,
                        form_term: bool = True) -> tuple[list[str], np.ndarray]:
    """Names and ``(samples + 1, p)`` values: row 0 the estimate, then draws from N(θ̂, Σ) (seeded).

    ``form_term``: where the model carries a differential-form check (:func:`form_delta`), the draws'
    covariance is ``Σ + δδᵀ``: the integral form's estimate counts as one standard deviation of model-form
    error (:func:`shipid.methods.mmg.pipeline.form_check`)."""
    names = list(result.get("covariance_names") or [])
    cov = result.get("covariance")
    coef = result["model"]["coefficients"]
    theta = np.array([float(coef[n]) for n in names])
    if not names or cov is None:
        if samples:
            raise InputError("the model has no parameter covariance: use --samples 0")
        return names, theta[None]
    S = np.asarray(cov, float)
    if S.shape != (len(names), len(names)) or not np.all(np.isfinite(S)):
        raise InputError("the model's covariance is malformed or not finite")
    S = 0.5 * (S + S.T)
    d = form_delta(result, names) if form_term else None
    if d is not None:
        S = S + np.outer(d, d)
    w, V = np.linalg.eigh(S)
    if w.min() < -1e-9 * max(w.max(), 1e-300):
        raise InputError(f"the model's covariance is not positive semi-definite (eigenvalue {w.min():.3g})")
    A = V * np.sqrt(np.clip(w, 0.0, None))
    z = np.random.default_rng(seed).standard_normal((samples, len(names)))
    return names, np.vstack([theta, theta + z @ A.T])


def approach_rows(model, Th: Mapping[str, np.ndarray], cond: MM.Conditions, *, speed_given: bool,
                  rps_given: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Approach speed and propeller rate of each row of ``Th`` (row 0 the estimate) and where a draw has none.

    What the user fixed stays fixed; what :func:`shipid.methods.mmg.manoeuvres.resolve_conditions` derived
    from the model's straight-line equilibrium is derived again for each draw
    (:func:`~shipid.methods.mmg.manoeuvres.rows_equilibrium`): with a propeller rate (given or the training
    runs'), each draw's own equilibrium speed; with a speed only, each draw's own rate. Holding the nominal
    model's speed for every draw instead starts each draw off its equilibrium and leaves the surge
    coefficients' share of the turning criteria out of the band: on one simulated coverage-study
    truth (30 noise realisations, ``docs/validation/mmg.md``) the advance's band std was then 0.012 L
    against an error RMS of 0.019 L. Row 0 keeps ``cond``'s values exactly. Returns ``(speed, rps, no_eq)``,
    ``no_eq`` True where a draw has no equilibrium."""
    R = next(iter(Th.values())).shape[0]
    u0, n0 = np.full(R, cond.speed), np.full(R, cond.rps)
    draws = {m: T[1:] for m, T in Th.items()}
    if R > 1 and not speed_given:
        u0[1:] = MM.rows_equilibrium(model, draws, rps=cond.rps)
    elif R > 1 and not rps_given:
        n0[1:] = MM.rows_equilibrium(model, draws, speed=cond.speed)
    return u0, n0, ~(np.isfinite(u0) & np.isfinite(n0))


def approach_note(speed_given: bool, rps_given: bool) -> str:
    """How each Monte Carlo draw approaches (:func:`approach_rows`), for the report's notes."""
    if not speed_given:
        return "each draw approaches at its own straight-line speed at the propeller rate (as the estimate does)"
    if not rps_given:
        return "each draw approaches at the given speed with its own equilibrium propeller rate"
    return "every draw approaches at the given speed and propeller rate (not each draw's equilibrium)"


@dataclass(frozen=True)
class Criterion:
    """One criterion: nominal value, MC std and band, limit(s) and verdict."""

    name: str
    unit: str
    value: float
    std: float
    band: tuple[float, float]
    limit: tuple[float, float] | None
    verdict: str
    p_pass: float
    n_valid: int
    note: str = ""
    n_open: int = 0

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "unit": self.unit, "value": self.value, "std": self.std,
                "band": list(self.band), "limit": None if self.limit is None else list(self.limit),
                "verdict": self.verdict, "p_pass": self.p_pass, "samples_valid": self.n_valid,
                "samples_not_reached": self.n_open, "note": self.note}


def _band(d: np.ndarray) -> tuple[float, float]:
    """The :data:`BAND` quantiles of draws ``d`` where NaN means "not reached within the simulated time"
    (a track, turn or stop longer than any simulated one): such draws lie beyond every finite value, so a
    quantile that falls among them is +inf (the band is open at its upper end)."""
    fin = d[np.isfinite(d)]           # at least two (_criterion)
    if fin.size == d.size:
        return tuple(float(q) for q in np.percentile(fin, BAND))
    top = float(fin.max())
    q = np.percentile(np.where(np.isfinite(d), d, top + 1.0), BAND)
    return tuple(float(x) if x <= top else float("inf") for x in q)


def _criterion(name, unit, vals, limit, note="", excluded=None) -> Criterion:
    """One criterion from ``vals`` (the nominal model first, then the draws; NaN: not reached).

    ``excluded`` (same length, optional): rows with no value for another reason (no straight-line
    equilibrium at the approach, a diverged simulation), left out of the band and counted by their own
    warnings; every other NaN draw is "not reached" and enters the band as beyond every value (:func:`_band`).
    """
    vals = np.asarray(vals, float)
    nominal = float(vals[0])
    keep = np.ones(vals.size - 1, bool) if excluded is None else ~np.asarray(excluded, bool)[1:]
    d = vals[1:][keep]
    mc = d[np.isfinite(d)]
    # draws beyond every simulated value have no finite spread: the std is then infinite, the band (quantiles) not
    std = float("nan") if mc.size <= 1 else float("inf") if mc.size < d.size else float(np.std(mc, ddof=1))
    band = _band(d) if mc.size > 1 else (float("nan"), float("nan"))
    if limit is None:
        verdict, p = "not available", float("nan")
    elif not np.isfinite(nominal):
        verdict, p = "fail (not reached)", float(np.mean(vals[1:] <= limit[0])) if vals.size > 1 else float("nan")
    else:
        lo, hi = limit
        verdict = "pass" if nominal <= lo else "fail" if nominal > hi else "depends on L/V (give --ship-length)"
        p = float(np.mean(vals[1:] <= lo)) if vals.size > 1 else float("nan")   # strictest limit if a range
    return Criterion(name, unit, nominal, std, band, None if limit is None else tuple(limit), verdict, p,
                     int(mc.size), note, int(d.size - mc.size))


def _arc(x, y):
    return np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])


def initial_turning(rec: MM.BatchRecord, i: int, angle: float = np.deg2rad(10.0)) -> float:
    """Track distance (m) from execute until the heading has changed ``angle``; NaN if never."""
    ev = np.flatnonzero(np.diff(rec.delta_cmd[i]) != 0) + 1
    if ev.size == 0:
        return float("nan")
    k0 = int(ev[0])
    psi = np.abs(rec.x[i, k0:, 2] - rec.x[i, k0, 2])
    s = _arc(rec.x[i, k0:, 0], rec.x[i, k0:, 1])
    j = np.flatnonzero(psi >= angle)
    if j.size == 0 or j[0] == 0:
        return float("nan")
    j = int(j[0])
    return float(s[j - 1] + (angle - psi[j - 1]) / (psi[j] - psi[j - 1]) * (s[j] - s[j - 1]))


def stopping_reach(rec: MM.BatchRecord, i: int) -> float:
    """Track reach (m) from the astern order until the ahead speed is lost (u = 0); NaN if never."""
    k0 = int(np.flatnonzero(rec.delta_cmd[i] > 0)[0])
    u = rec.x[i, k0:, 3]
    s = _arc(rec.x[i, k0:, 0], rec.x[i, k0:, 1])
    j = np.flatnonzero(u <= 0)
    if j.size == 0 or j[0] == 0:
        return float("nan")
    j = int(j[0])
    return float(s[j - 1] + u[j - 1] / (u[j - 1] - u[j]) * (s[j] - s[j - 1]))


def _safe(f, *a):
    try:
        return f(*a)
    except InputError:
        return None


def full_scale_length(model, ship_length: float | None = None) -> tuple[float, str]:
    """The full-scale ship length (m) of the overshoot limits and of the steering-gear rate, and where it
    came from: ``ship_length`` as given, else the model's ``particulars["L_ship"]`` (its prior's), else
    :class:`~shipid.errors.InputError`: there is no silent default."""
    if ship_length is not None:
        if not ship_length > 0:
            raise InputError(f"--ship-length must be positive, got {ship_length:g}")
        return float(ship_length), "given"
    ls = model.particulars.get("L_ship")
    if ls is not None and float(ls) > 0:
        return float(ls), f"L_ship of the model's particulars, from its prior ({model.name})"
    raise InputError(f"the model {model.name} records no full-scale ship length (particulars L_ship): give "
                     "--ship-length (m); the overshoot limits and the steering-gear rate depend on it")


def assess(result: Mapping[str, Any], *, samples: int = 100, seed: int = 0, ship_length: float | None = None,
           speed: float | None = None, rps: float | None = None, rudder_rate_deg_s: float | None = None,
           dt: float = 0.1, form_term: bool = True, water_depth: float | None = None) -> dict[str, Any]:
    """All criteria of the module docstring for the MODEL.json dict ``result``.

    ``form_term``: draw from the covariance with the model-form term where the model has one
    (:func:`sample_coefficients`); False: the estimation uncertainty alone. ``water_depth`` (m): the depth
    the criteria are asked for (default: the training runs'); the model has no shallow-water terms, so
    a depth class other than the training runs' is a warning
    (:func:`shipid.methods.mmg.manoeuvres.depth_check`)."""

    if samples < 0:
        raise InputError(f"--samples must be >= 0, got {samples}")
    model = model_from_result(result)
    L = float(model.particulars["L"])
    ship_length, length_from = full_scale_length(model, ship_length)
    gear_note, rate_from = None, "given"
    if rudder_rate_deg_s is None:
        rudder_rate_deg_s = SOLAS_RUDDER_RATE * np.sqrt(ship_length / L)
        rate_from = f"the SOLAS minimum {SOLAS_RUDDER_RATE:.3g} deg/s at scale {ship_length / L:.4g} (Froude)"
        gear_note = (f"rudder rate {rudder_rate_deg_s:.3g} deg/s: the SOLAS minimum {SOLAS_RUDDER_RATE:.3g} deg/s "
                     f"(35 deg to 30 deg the other side in 28 s) at scale {ship_length / L:.4g} (Froude)")
    cond = MM.resolve_conditions(model, result, speed=speed, rps=rps, rudder_rate_deg_s=rudder_rate_deg_s,
                                 water_depth=water_depth)
    if gear_note:
        from dataclasses import replace
        cond = replace(cond, notes=cond.notes + (gear_note,))
    lu = L / cond.speed
    lv = lu * np.sqrt(ship_length / L)
    names, vals = sample_coefficients(result, samples, seed, form_term)
    with_form = bool(samples) and form_term and form_delta(result, names) is not None
    Th = MM.theta_rows(model, names, vals)
    R = vals.shape[0]
    u0, n0, no_eq = approach_rows(model, Th, cond, speed_given=speed is not None, rps_given=rps is not None)
    kinds = [("turning-35", np.deg2rad(35.0), np.inf, 1), ("turning-35-port", np.deg2rad(35.0), np.inf, -1),
             ("zigzag-10", np.deg2rad(10.0), np.deg2rad(10.0), 1), ("zigzag-10-port", np.deg2rad(10.0),
                                                                  np.deg2rad(10.0), -1),
             ("zigzag-20", np.deg2rad(20.0), np.deg2rad(20.0), 1), ("zigzag-20-port", np.deg2rad(20.0),
                                                                  np.deg2rad(20.0), -1)]
    K = len(kinds)
    ThB = {m: np.repeat(T, K, axis=0) for m, T in Th.items()}            # row = sample * K + kind
    order = np.tile([k[1] for k in kinds], R)
    psw = np.tile([k[2] for k in kinds], R)
    side = np.tile([k[3] for k in kinds], R)
    rec = MM.simulate_rudder_batch(model, ThB, order, psw, side, cond, dt=dt, exact_reversal=True,
                                   speed=np.repeat(u0, K), rps=np.repeat(n0, K))
    diverged = ~np.isfinite(rec.x).all(axis=(1, 2)) & ~np.repeat(no_eq, K)
    # per manoeuvre kind, the rows with no value for a reason other than "not reached" (_criterion)
    bad = diverged.reshape(R, K) | no_eq[:, None]
    excl = {k[0]: bad[:, j] for j, k in enumerate(kinds)}
    vals_of: dict[str, np.ndarray] = {}

    def put(key, i, v):
        vals_of.setdefault(key, np.full(R, np.nan))[i] = v

    for r in range(R):
        for j, (kname, _, ps, sd) in enumerate(kinds):
            row = r * K + j
            if diverged[row] or no_eq[r]:
                continue
            tr = rec.trial(row)
            if kname.startswith("turning"):
                tm = _safe(turning_metrics, tr)
                if tm is not None:
                    put(f"{kname} advance", r, tm.advance / L)
                    put(f"{kname} tactical diameter", r, tm.tactical_diameter / L)
            else:
                zm = _safe(zigzag_metrics, tr, ps)
                ov = list(zm.overshoots) if zm is not None else []
                put(f"{kname} first overshoot", r, np.degrees(ov[0]) if len(ov) > 0 else np.nan)
                if kname.startswith("zigzag-10"):
                    put(f"{kname} second overshoot", r, np.degrees(ov[1]) if len(ov) > 1 else np.nan)
                    put(f"initial turning{' port' if sd < 0 else ''}", r, initial_turning(rec, row) / L)
    (f1lo, f1hi), (f2lo, f2hi) = overshoot_limits(lv)
    crit = []
    for side_name in ("turning-35", "turning-35-port"):
        crit.append(_criterion(f"{side_name} advance", "L", vals_of.get(f"{side_name} advance", np.full(R, np.nan)),
                               (4.5, 4.5), excluded=excl[side_name]))
        crit.append(_criterion(f"{side_name} tactical diameter", "L",
                               vals_of.get(f"{side_name} tactical diameter", np.full(R, np.nan)), (5.0, 5.0),
                               excluded=excl[side_name]))
    for nm, z in (("initial turning", "zigzag-10"), ("initial turning port", "zigzag-10-port")):
        crit.append(_criterion(nm + " (track to 10 deg heading)", "L",
                               vals_of.get(nm, np.full(R, np.nan)), (2.5, 2.5), excluded=excl[z]))
    for z in ("zigzag-10", "zigzag-10-port"):
        crit.append(_criterion(f"{z} first overshoot", "deg", vals_of[f"{z} first overshoot"], (f1lo, f1hi),
                               excluded=excl[z]))
        crit.append(_criterion(f"{z} second overshoot", "deg", vals_of[f"{z} second overshoot"], (f2lo, f2hi),
                               excluded=excl[z]))
    for z in ("zigzag-20", "zigzag-20-port"):
        crit.append(_criterion(f"{z} first overshoot", "deg", vals_of[f"{z} first overshoot"], (25.0, 25.0),
                               excluded=excl[z]))
    stop_note = ""
    if model.structure.startswith("esso") and cond.rps_astern is not None:
        srec = MM.simulate_stopping_batch(model, Th, cond, dt=dt, speed=u0, rps=n0)
        sdiv = np.array([not np.isfinite(srec.x[r]).all() for r in range(R)])
        reach = np.array([np.nan if sdiv[r] else stopping_reach(srec, r) / L for r in range(R)])
        note = (f"full astern {cond.rps_astern:g} rev/s (the training runs' most negative rate), reversed at "
                + (f"{cond.rps_rate:.3g} rev/s^2" if cond.rps_rate else "once") + " as in the training runs; a "
                "full-scale engine reverses far more slowly, so this is the model's, not the ship's, track reach")
        crit.append(_criterion("stopping track reach", "L", reach, (STOPPING_LIMIT, STOPPING_LIMIT), note,
                               excluded=sdiv | no_eq))
    else:
        stop_note = ("not available: model has no astern propeller" if not model.structure.startswith("esso")
                     else "not available: the training runs never reversed the propeller")
        crit.append(Criterion("stopping track reach", "L", float("nan"), float("nan"), (float("nan"),) * 2,
                              None, stop_note, float("nan"), 0, stop_note))
    warnings = list(cond.warnings)
    for c in crit:
        if c.limit is None:
            continue
        if not np.isfinite(c.value):
            warnings.append(f"{c.name}: not reached by the nominal model within the simulated time")
        if samples and c.n_open:
            warnings.append(f"{c.name}: {c.n_open} of {samples} draws do not reach it within the simulated time "
                            "(in the band as beyond every value" + (": its upper end is open)"
                                                                   if not np.isfinite(c.band[1]) else ")"))
    if no_eq.any():
        warnings.append(f"{int(no_eq.sum())} of {samples} draws have no straight-line equilibrium at the approach "
                        "(left out of the bands)")
    if diverged.any():
        warnings.append(f"{int(diverged.sum())} of {diverged.size} simulated manoeuvres diverged "
                        "(left out of the bands)")
    over = (((result.get("diagnostics") or {}).get("form_check") or {}).get("over") or [])
    if samples and over:
        warnings.append(f"the model's standard errors are flagged (step 2's differential and integral forms disagree "
                        f"by more than {FORM_CHECK_SE:g} SE on {len(over)} coefficients, diagnostics.form_check): "
                        + (FORM_TERM_BANDS if with_form else FORM_BANDS))
    cov_kind = ((result.get("diagnostics") or {}).get("covariance") or {}).get(
        "kind", "ridge SE (independent residuals assumed: optimistic)")
    if with_form:
        cov_kind += " + model-form term (differential minus integral form of step 2 as one std)"
    return {"model": model.name, "structure": model.structure, "L": L, "L_over_U_model_s": lu,
            "ship_length": ship_length, "ship_length_from": length_from,
            "rudder_rate_deg_s": float(rudder_rate_deg_s), "rudder_rate_from": rate_from, "L_over_V_full_scale_s": lv, "conditions": cond.to_dict(),
            "samples": int(samples), "seed": int(seed), "dt": dt, "form_term": with_form,
            "covariance_names": names, "covariance_kind": cov_kind,
            "criteria": [c.to_dict() for c in crit], "warnings": warnings,
            "notes": ["criteria of IMO MSC.137(76) 5.3-5.4 in ship lengths (model scale); overshoot limits "
                      "from the full-scale L/V", "band: 2.275-97.725 % quantiles of the Monte Carlo over the "
                      "parameter covariance (covariance_kind)", approach_note(speed is not None, rps is not None),
                      BAND_CAVEAT]}


def format_report(rep: Mapping[str, Any]) -> str:
    """Plain-text table of :func:`assess`."""
    c = rep["conditions"]
    lv = rep["L_over_V_full_scale_s"]
    lines = [f"IMO MSC.137(76) manoeuvres of {rep['model']} ({rep['structure']}), L = {rep['L']:g} m",
             f"ship length {rep['ship_length']:g} m ({rep['ship_length_from']}); rudder rate "
             f"{rep['rudder_rate_deg_s']:.3g} deg/s ({rep['rudder_rate_from']})",
             f"approach {c['speed']:.4g} m/s, {c['rps']:.4g} rev/s, rudder {c['rudder_rate_deg_s']:.3g} deg/s; "
             f"L/U = {rep['L_over_U_model_s']:.3g} s (model); full-scale L/V = "
             + f"{lv:.3g} s",
             f"bands: {rep['samples']} draws from the parameter covariance, seed {rep['seed']}; covariance: "
             + rep.get("covariance_kind", "ridge SE (independent residuals assumed: optimistic)"),
             f"{'criterion':<52} {'value':>8} {'std':>7} {'band (+-2 std)':>19} {'limit':>11} {'P(pass)':>8}  verdict"]
    for k in rep["criteria"]:
        lim = k["limit"]
        ls = "-" if lim is None else (f"{lim[0]:g}" if lim[0] == lim[1] else f"{lim[0]:g}-{lim[1]:g}")
        b = k["band"]
        lines.append(f"{k['name'] + ' [' + k['unit'] + ']':<52} {k['value']:8.3g} {k['std']:7.2g} "
                     f"[{b[0]:7.3g}, {b[1]:7.3g}] {ls:>11} {k['p_pass']:8.2f}  {k['verdict']}")
    for n in [*c["notes"], *rep.get("notes", [])]:
        lines.append(f"note: {n}")
    return "\n".join(lines)


__all__ = ["assess", "full_scale_length", "format_report", "overshoot_limits", "sample_coefficients", "form_delta", "initial_turning",
           "stopping_reach", "Criterion", "BAND", "STOPPING_LIMIT"]
