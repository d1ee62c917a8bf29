"""Standard manoeuvres of identified MMG models: test conditions and a batched simulator.

An identified model (MODEL.json of ``shipid identify mmg``) is run through the
definitive manoeuvres of ITTC 7.5-04-02-01 / IMO MSC.137(76) — turning circles,
zig-zags, the stopping test — in calm water and still air (no true wind; the air drag of
the ship's own motion stays, as in :func:`shipid.models.mmg.dynamics`), in the MMG rudder convention
(positive δ turns the ship to starboard; :func:`rudder_turn_sign` checks it on the model).

**Test conditions** (:func:`resolve_conditions`). The approach is steady straight
motion with the rudder amidships. Given a propeller rate ``n`` the approach speed is
the model's own straight-line equilibrium ``X(u, 0, 0; δ = 0, n) = 0``
(:func:`equilibrium_speed`, surge only, air drag included); given a speed the rate is solved the same
way (:func:`equilibrium_rps`); given both, both are used as given (the model then
accelerates during the approach). With neither, ``n`` is taken from the training
data recorded in the model (:func:`training_conditions`: the median propeller rate
over the ahead samples of all training runs), because the Esso Osaka runs start from
rest and execute the rudder within the first second, so their speed at execute is no
approach speed. The steering-gear rate is the median rate of the training runs' large rudder moves
(:func:`rudder_move_rates`), the rudder limit 35°; the
stopping test reverses to the most negative rate of the training runs at their
median propeller acceleration.

**Water depth** (:func:`depth_check`). The models have no shallow-water terms: a model holds at the
depth of its training runs. The depth is a recorded condition (``training_conditions["water_depth"]``,
from the runs' ``meta["water_depth"]``: the HSVA KVLCC2 profile reads 6.0 m from the test report, h/T =
13.2; ``identify mmg --water-depth``); ``simulate`` and ``imo`` take ``--water-depth`` and say out loud,
as one warning line, when the depth class of the prediction (:data:`DEPTH_CLASSES`, by h/T) is not that of
the training runs, or is not deep water where the training depth is unknown.

**Batched simulation** (:func:`simulate_rudder_batch`, :func:`simulate_stopping_batch`):
many rows at once — one per (parameter sample, manoeuvre) — each with its own
coefficient vector, by the same RK4 with zero-order-hold inputs and the same
rate-limited steering gear and Kempf reversal rule as
:func:`shipid.simulate.manoeuvres.run_manoeuvre` (for one row the two agree to
round-off; tested). The simulation stops when every row has what its criteria need.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from shipid.io.trial import Trial
from shipid.errors import InputError, ShipidError
from shipid.models import mmg
from shipid.io.files import read_trial
from shipid.numerics.integrate import rk4_propagate
from shipid.models.ship_model import ShipModel
from shipid.simulate.manoeuvres import ManoeuvreSpec, parse_manoeuvre, run_manoeuvre

#: Rudder limit (rad) of the manoeuvres (35° hard over, MSC.137(76) 4.2.1).
RUDDER_LIMIT = np.deg2rad(35.0)
#: Straight approach before execute (s), as :data:`shipid.simulate.manoeuvres.T_EXECUTE`.
T_APPROACH = 10.0


# ----------------------------------------------------------------------------- conditions
def rudder_move_rates(delta: np.ndarray, t: np.ndarray, min_swing: float = np.deg2rad(5.0)) -> np.ndarray:
    """Mean rates (rad/s) of the large rudder moves of a run.

    A move is a maximal stretch of samples over which the rudder moves in one
    direction (steps below 0.05° count as no motion and end it); its rate is its swing
    over its duration. Only moves of at least ``min_swing`` count, so the logger's
    quantisation steps (0.56° on the Esso Osaka logs) and slow drifts do not.
    A move done within one sample gives swing/dt, a lower bound of a faster gear.
    """
    dd = np.diff(np.asarray(delta, float))
    dt = np.diff(np.asarray(t, float))
    sgn = np.where(np.abs(dd) > np.deg2rad(0.05), np.sign(dd), 0.0)
    rates = []
    i = 0
    while i < sgn.size:
        if sgn[i] == 0 or not np.isfinite(dd[i]):
            i += 1
            continue
        j = i
        while j + 1 < sgn.size and sgn[j + 1] == sgn[i]:
            j += 1
        swing = abs(float(np.sum(dd[i:j + 1])))
        if swing >= min_swing:
            rates.append(swing / float(np.sum(dt[i:j + 1])))
        i = j + 1
    return np.asarray(rates)


def training_conditions(trials: Sequence[Trial]) -> dict[str, Any]:
    """What the training runs say about the test conditions (recorded in MODEL.json).

    ``rps_ahead``: median propeller rate over all samples with ``n > 0`` (rev/s);
    ``rps_astern``: the most negative rate (None if no run reversed); ``rps_rate``:
    median over runs of the 95th percentile of |dn/dt| where the rate changes by more
    than 0.1 rev/s² (None if constant); ``rudder_rate``: median over runs of
    :func:`rudder_rate` (rad/s); ``speed_p95``: median over runs of the 95th
    percentile of u (m/s, for reference); ``water_depth``: median of the runs' ``meta["water_depth"]``
    (m; None where no run records one) and ``water_depth_runs``, how many runs record it; rudder in the
    MMG convention.
    """
    n_all, rates, nrates, speeds = [], [], [], []
    nmin = np.inf
    for tr in trials:
        n = np.asarray(tr["n"], float)
        ok = np.isfinite(n)
        n_all.append(n[ok & (n > 0)])
        if ok.any():
            nmin = min(nmin, float(np.min(n[ok])))
        rates.extend(rudder_move_rates(np.asarray(tr["delta"], float), tr.t).tolist())
        dn = np.abs(np.diff(n)) / np.diff(tr.t)
        dn = dn[np.isfinite(dn) & (dn > 0.1)]
        if dn.size >= 5:
            nrates.append(float(np.percentile(dn, 95)))
        if "u" in tr:
            speeds.append(float(np.nanpercentile(tr["u"], 95)))
    pooled = np.concatenate(n_all) if n_all else np.array([])
    depths = [float(tr.meta["water_depth"]) for tr in trials if (tr.meta or {}).get("water_depth") is not None]
    return {"rps_ahead": float(np.median(pooled)) if pooled.size else None,
            "rps_astern": float(nmin) if np.isfinite(nmin) and nmin < 0 else None,
            "rps_rate": float(np.median(nrates)) if nrates else None,
            "rudder_rate": float(np.median(rates)) if rates else None,
            "speed_p95": float(np.median(speeds)) if speeds else None,
            "water_depth": float(np.median(depths)) if depths else None, "water_depth_runs": len(depths),
            "runs": len(trials)}


def straight_du(model: mmg.MmgModel, u: float, n: float) -> float:
    """Surge acceleration ``du/dt`` of ``model`` running straight (v = r = δ = 0) at speed ``u`` and propeller rate ``n``.

    Zero at the equilibrium that :func:`equilibrium_speed` and :func:`equilibrium_rps` solve for (still air).
    """
    UA, gA = mmg.apparent_wind(0.0, 0.0, 0.0, np.array([u]), np.array([0.0]))    # still air: the ship's own speed
    X, _, _ = mmg.forces(model, np.array([u]), np.array([0.0]), np.array([0.0]), np.array([0.0]), np.array([n]),
                         UA, gA)
    return float(X[0] / mmg.mass_terms(model)[0])


#: Propeller rates (rev/s) searched for a straight-line equilibrium (:func:`equilibrium_rps`, :func:`rows_equilibrium`).
RPS_BRACKET = (1e-3, 200.0)


def speed_bracket(model: mmg.MmgModel) -> tuple[float, float]:
    """Speeds (m/s) searched for a straight-line equilibrium: up to Froude number 3."""
    return 1e-3, 3.0 * np.sqrt(9.81 * model.particulars["L"])


def equilibrium_speed(model: mmg.MmgModel, rps: float) -> float:
    """Straight-line speed (m/s) at which the model's surge force vanishes at ``rps`` (δ = 0, v = r = 0)."""
    from scipy.optimize import brentq

    lo, hi = speed_bracket(model)
    flo, fhi = straight_du(model, lo, rps), straight_du(model, hi, rps)
    if not (flo > 0 > fhi):
        raise ShipidError(f"model {model.name!r} has no straight-line equilibrium speed at {rps:g} rev/s "
                          f"(surge acceleration {flo:.3g} at {lo:g} m/s, {fhi:.3g} at {hi:.3g} m/s); give --speed")
    return float(brentq(lambda u: straight_du(model, u, rps), lo, hi, xtol=1e-10))


def equilibrium_rps(model: mmg.MmgModel, speed: float) -> float:
    """Propeller rate (rev/s) that holds the straight-line speed ``speed`` (δ = 0, v = r = 0)."""
    from scipy.optimize import brentq

    lo, hi = RPS_BRACKET
    flo, fhi = straight_du(model, speed, lo), straight_du(model, speed, hi)
    if not (flo < 0 < fhi):
        raise ShipidError(f"model {model.name!r}: no propeller rate in (0, {hi:g}] rev/s holds {speed:g} m/s; "
                          "give --rps")
    return float(brentq(lambda n: straight_du(model, speed, n), lo, hi, xtol=1e-10))


@dataclass(frozen=True)
class Conditions:
    """Test conditions of the manoeuvres (SI: m/s, rev/s, rad, rad/s, rev/s²)."""

    speed: float
    rps: float
    rudder_rate: float
    rudder_limit: float = RUDDER_LIMIT
    rps_astern: float | None = None
    rps_rate: float | None = None
    notes: tuple[str, ...] = field(default_factory=tuple)
    water_depth: float | None = None
    warnings: tuple[str, ...] = field(default_factory=tuple)

    def to_dict(self) -> dict[str, Any]:
        return {"speed": self.speed, "rps": self.rps, "rudder_rate_deg_s": float(np.degrees(self.rudder_rate)),
                "rudder_limit_deg": float(np.degrees(self.rudder_limit)), "rps_astern": self.rps_astern,
                "rps_rate": self.rps_rate, "water_depth": self.water_depth, "notes": list(self.notes),
                "warnings": list(self.warnings)}


#: Water-depth classes by depth over draught h/T, deepest first: (lowest h/T of the class, name). The
#: classification of PIANC (1992) that the ITTC Manoeuvring Committee uses: deep h/T > 3, medium deep
#: 1.5-3, shallow 1.2-1.5, very shallow below 1.2.
DEPTH_CLASSES = ((3.0, "deep"), (1.5, "medium deep"), (1.2, "shallow"), (0.0, "very shallow"))


def depth_class(h_over_T: float) -> str:
    """The :data:`DEPTH_CLASSES` name of a depth-to-draught ratio."""
    return next(name for lo, name in DEPTH_CLASSES if h_over_T > lo or lo == 0.0)


def depth_check(draught: float, trained: float | None, target: float | None) -> tuple[list[str], list[str]]:
    """Notes and warning lines on the water depth of a prediction (module docstring).

    ``draught`` T (m) of the model; ``trained``: the training runs' depth (m, None if not recorded);
    ``target``: the depth asked for (m, None: the training depth). A warning where the target's depth
    class differs from the training runs', or where the training depth is unknown and the target is not
    deep water; a note of the depth and class otherwise."""
    notes, warns = [], []
    if target is not None and not (np.isfinite(target) and target > draught):
        raise InputError(f"--water-depth must exceed the model's draught {draught:g} m, got {target:g}")
    h = trained if target is None else target
    if h is None:
        return notes, warns
    ct = depth_class(h / draught)
    if trained is not None:
        c0 = depth_class(trained / draught)
        if ct != c0:
            warns.append(f"water depth {h:g} m (h/T {h / draught:.3g}, {ct} water) is not the depth class of the "
                         f"training runs ({trained:g} m, h/T {trained / draught:.3g}, {c0}): the model has no "
                         "shallow-water terms and is not validated there")
        else:
            notes.append(f"water depth {h:g} m (h/T {h / draught:.3g}, {ct} water; training runs {trained:g} m)")
    elif ct != "deep":
        warns.append(f"water depth {h:g} m (h/T {h / draught:.3g}, {ct} water) and the training runs' depth is not "
                     "recorded: the model has no shallow-water terms and is not validated there")
    else:
        notes.append(f"water depth {h:g} m (h/T {h / draught:.3g}, deep water; the training runs' depth is not "
                     "recorded)")
    return notes, warns


def recorded_conditions(d: Mapping[str, Any]) -> dict[str, Any] | None:
    """The training conditions of a MODEL.json dict: recorded ones, else from its training run files if readable."""
    tc = (d.get("model") or {}).get("training_conditions")
    if tc:
        return dict(tc)
    runs = (d.get("provenance") or {}).get("training_runs") or []
    from pathlib import Path

    trials = []
    for r in runs:
        f = r.get("file") if isinstance(r, Mapping) else None
        if not f or not Path(f).is_file():
            return None
        try:
            tr = read_trial(f, trim_empty_rows=True, interpolate_gaps=1.0)
        except ShipidError:
            return None
        if int((d.get("provenance") or {}).get("rudder_sign", 1)) == -1:
            tr = tr.with_channels(delta=-tr["delta"])
        trials.append(tr)
    return training_conditions(trials) if trials else None


def resolve_conditions(model: mmg.MmgModel, result: Mapping[str, Any] | None = None, *,
                       speed: float | None = None, rps: float | None = None,
                       rudder_rate_deg_s: float | None = None, water_depth: float | None = None) -> Conditions:
    """The test conditions from the options and the model's training data (module docstring)."""
    tc = recorded_conditions(result) if result is not None else None
    dnotes, dwarns = depth_check(float(model.particulars["d"]), (tc or {}).get("water_depth"), water_depth)
    notes = []
    for name, v in (("--speed", speed), ("--rps", rps), ("--rudder-rate", rudder_rate_deg_s)):
        if v is not None and not (np.isfinite(v) and v > 0):
            raise InputError(f"{name} must be positive, got {v:g}")
    if speed is None and rps is None:
        if not tc or tc.get("rps_ahead") is None:
            raise InputError("the model records no training conditions: give --speed or --rps")
        rps = float(tc["rps_ahead"])
        notes.append(f"propeller rate {rps:.4g} rev/s: median ahead rate of the {tc.get('runs')} training runs")
    if speed is None:
        speed = equilibrium_speed(model, rps)
        notes.append(f"approach speed {speed:.4g} m/s: the model's straight-line equilibrium at {rps:.4g} rev/s")
    elif rps is None:
        rps = equilibrium_rps(model, speed)
        notes.append(f"propeller rate {rps:.4g} rev/s: the model's straight-line equilibrium at {speed:.4g} m/s")
    else:
        du = straight_du(model, speed, rps)
        notes.append(f"speed and rate as given; the model's surge acceleration at the approach is {du:.3g} m/s^2")
    if rudder_rate_deg_s is not None:
        rate = float(np.deg2rad(rudder_rate_deg_s))
    elif tc and tc.get("rudder_rate"):
        rate = float(tc["rudder_rate"])
        notes.append(f"rudder rate {np.degrees(rate):.3g} deg/s: median of the training runs")
    else:
        raise InputError("the model records no rudder rate: give --rudder-rate (deg/s)")
    return Conditions(speed=float(speed), rps=float(rps), rudder_rate=rate,
                      rps_astern=(tc or {}).get("rps_astern"), rps_rate=(tc or {}).get("rps_rate"),
                      notes=tuple(notes + dnotes), warnings=tuple(dwarns),
                      water_depth=water_depth if water_depth is not None else (tc or {}).get("water_depth"))


def rudder_turn_sign(model: mmg.MmgModel, cond: Conditions) -> float:
    """+1 if positive δ turns the model to starboard at the approach (``∂ṙ/∂δ > 0``), else −1."""
    def rdot(d):
        UA, gA = mmg.apparent_wind(0.0, 0.0, 0.0, np.array([cond.speed]), np.array([0.0]))
        X, Y, N = mmg.forces(model, *(np.array([a]) for a in (cond.speed, 0.0, 0.0, d, cond.rps)), UA, gA)
        return mmg.accelerations(model, cond.speed, 0.0, 0.0, X, Y, N)[2][0]
    s = rdot(np.deg2rad(5.0)) - rdot(-np.deg2rad(5.0))
    if not np.isfinite(s) or s == 0:
        raise ShipidError(f"model {model.name!r}: the yaw rate does not respond to the rudder")
    return float(np.sign(s))


def ship_model(model: mmg.MmgModel, cond: Conditions):
    """:class:`shipid.models.ship_model.ShipModel` of an identified MMG model in calm water at ``cond``."""

    def outputs(t, X, U):
        return {"x": X[:, 0], "y": X[:, 1], "psi": X[:, 2], "u": X[:, 3], "v": X[:, 4], "r": X[:, 5],
                "delta": U[:, 0], "n": U[:, 1]}

    return ShipModel(name=model.name, f=mmg.dynamics, theta=model, state_names=mmg.STATE_NAMES,
                     input_names=mmg.INPUT_NAMES, x0=lambda s: np.array([0.0, 0.0, 0.0, s, 0.0, 0.0]),
                     outputs=outputs, service_speed=cond.speed, heading_index=2,
                     rudder_limit=cond.rudder_limit, rudder_rate_limit=cond.rudder_rate,
                     u0=lambda s: np.array([0.0, cond.rps, 0.0, 0.0]))


def default_duration(model: mmg.MmgModel, cond: Conditions) -> float:
    """Record length for ``shipid simulate``: the approach plus 60 L/U."""
    return T_APPROACH + 60.0 * model.particulars["L"] / cond.speed


def check_manoeuvre(manoeuvre: str) -> ManoeuvreSpec:
    """The parsed ``manoeuvre``; one :class:`ShipidError` for one an MMG model cannot run (unknown, or a DP
    trial)."""
    spec = parse_manoeuvre(manoeuvre)
    if spec.kind == "dp":
        raise ShipidError(f"manoeuvre {manoeuvre!r} is a DP trial; an MMG model has rudder and propeller only")
    return spec


def simulate_model(model: mmg.MmgModel, result: Mapping[str, Any] | None, manoeuvre: str, *,
                   duration: float | None = None, dt: float = 0.1, seed: int = 0, speed: float | None = None,
                   rps: float | None = None, rudder_rate: float | None = None,
                   water_depth: float | None = None) -> tuple[Trial, Conditions]:
    """``model`` through ``manoeuvre`` under the conditions :func:`resolve_conditions` sets (those recorded in
    ``result``, overridden by the arguments); ``duration`` defaults to :func:`default_duration`.

    Returns the record (``meta``: ``rps``, ``conditions``, ``model``, ``rudder_convention``) and the conditions,
    whose ``notes`` and ``warnings`` the caller says.
    """
    check_manoeuvre(manoeuvre)
    cond = resolve_conditions(model, result, speed=speed, rps=rps, rudder_rate_deg_s=rudder_rate,
                              water_depth=water_depth)
    dur = default_duration(model, cond) if duration is None else duration
    trial = run_manoeuvre(ship_model(model, cond), manoeuvre, duration=dur, dt=dt, seed=seed, speed=cond.speed)
    trial.meta.update(rps=cond.rps, conditions=cond.to_dict(), model=model.name,
                      rudder_convention="MMG: positive delta turns the ship to starboard")
    return trial, cond


# ----------------------------------------------------------------------------- batched simulation
def theta_rows(model: mmg.MmgModel, names: Sequence[str] = (), values: np.ndarray | None = None) -> dict:
    """Per-mode coefficient arrays ``{mode: (B, p)}``: the model's coefficients with ``names`` set per row."""
    values = np.zeros((1, 0)) if values is None else np.atleast_2d(np.asarray(values, float))
    B = values.shape[0]
    out = {}
    for m in mmg.MODES:
        cols = mmg.COEFS[model.structure][m]
        T = np.tile(model.theta(m), (B, 1))
        for j, c in enumerate(cols):
            if c in names:
                T[:, j] = values[:, list(names).index(c)]
        out[m] = T
    return out


def rows_deriv(model: mmg.MmgModel, Th: Mapping[str, np.ndarray], x: np.ndarray, delta, n, wind=None):
    """:func:`shipid.models.mmg.dynamics` for rows with their own coefficients ``Th[mode]`` (B, p).

    ``x`` (B, 6); ``delta``, ``n`` (B,); ``wind``: the true wind ``(U_T, γ_T)`` (B,) each, None for still
    air (the ship still meets the apparent wind of its own motion, as :func:`shipid.models.mmg.dynamics`
    with zero true wind).
    """
    w0, w1 = (0.0, 0.0) if wind is None else wind
    UA, gA = mmg.apparent_wind(w0, w1, x[:, 2], x[:, 3], x[:, 4])
    b = mmg.basis(model, x[:, 3], x[:, 4], x[:, 5], delta, n, UA, gA)
    F = [np.einsum("bp,bp->b", b[m][0], Th[m]) + b[m][1] for m in mmg.MODES]
    du, dv, dr = mmg.accelerations(model, x[:, 3], x[:, 4], x[:, 5], *F)
    c, s = np.cos(x[:, 2]), np.sin(x[:, 2])
    return np.stack([x[:, 3] * c - x[:, 4] * s, x[:, 3] * s + x[:, 4] * c, x[:, 5], du, dv, dr], axis=-1)


def rows_dynamics(t: float, x: np.ndarray, u: tuple, theta: tuple) -> np.ndarray:
    """:func:`rows_deriv` as ``f(t, x, u, θ)``: ``u = (δ, n, wind)``, ``θ = (model, Th)``; autonomous."""
    model, Th = theta
    delta, n, wind = u
    return rows_deriv(model, Th, x, delta, n, wind)


def rows_rk4(model: mmg.MmgModel, Th: Mapping[str, np.ndarray], x: np.ndarray, delta, n, h, wind=None):
    """One RK4 step of every row (inputs held), as :func:`shipid.models.mmg.simulate_batch`; ``h`` scalar or (B, 1).

    The package's one RK4 (:func:`shipid.numerics.integrate.rk4_propagate`) on :func:`rows_dynamics`.
    A state beyond 1e6 becomes NaN (a diverging row)."""
    x = rk4_propagate(rows_dynamics, 0.0, x, h, 1, ((delta, n, wind), (model, Th)))
    return np.where(np.abs(x) < 1e6, x, np.nan)


def rows_equilibrium(model: mmg.MmgModel, Th: Mapping[str, np.ndarray], *, rps: float | None = None,
                     speed: float | None = None, iterations: int = 200) -> np.ndarray:
    """Per row of ``Th`` the straight-line equilibrium: the speed (m/s) at propeller rate ``rps``, as
    :func:`equilibrium_speed`, or the rate (rev/s) that holds ``speed``, as :func:`equilibrium_rps`;
    NaN where a row has none in the same bracket.

    Vectorised bisection on the surge acceleration of :func:`rows_deriv` (δ = v = r = 0, still air) to
    float resolution. The Monte Carlo bands of :func:`shipid.methods.mmg.imo.assess` start each draw from
    its own equilibrium, as the nominal model starts from its own: the approach speed at a given
    propeller rate is as uncertain as the surge coefficients that set it."""
    if (rps is None) == (speed is None):
        raise ValueError("give exactly one of rps, speed")
    B = next(iter(Th.values())).shape[0]
    lo, hi = (np.full(B, b) for b in (speed_bracket(model) if rps is not None else RPS_BRACKET))
    sgn = 1.0 if rps is not None else -1.0          # du/dt falls with speed, rises with the rate

    def du(a):
        x = np.zeros((B, 6))
        x[:, 3] = a if rps is not None else speed
        return rows_deriv(model, Th, x, np.zeros(B), np.full(B, float(rps)) if rps is not None else a)[:, 3]

    with np.errstate(all="ignore"):
        ok = (sgn * du(lo) > 0) & (sgn * du(hi) < 0)
        for _ in range(iterations):
            mid = 0.5 * (lo + hi)
            pos = sgn * du(mid) > 0
            lo, hi = np.where(pos, mid, lo), np.where(pos, hi, mid)
            if np.all(hi - lo <= 4.0 * np.finfo(float).eps * np.abs(hi)):
                break
    return np.where(ok, 0.5 * (lo + hi), np.nan)


@dataclass(frozen=True)
class BatchRecord:
    """Histories of a batch: ``t`` (n,), ``x`` (B, n, 6), ``delta``, ``delta_cmd``, ``n`` (B, n)."""

    t: np.ndarray
    x: np.ndarray
    delta: np.ndarray
    delta_cmd: np.ndarray
    n: np.ndarray

    def trial(self, i: int, meta: Mapping | None = None) -> Trial:
        """Row ``i`` as a Trial (channels of :func:`shipid.simulate.manoeuvres.run_manoeuvre`)."""
        ch = {c: self.x[i, :, j] for j, c in enumerate(mmg.STATE_NAMES)}
        ch.update(delta=self.delta[i], n=self.n[i], delta_cmd=self.delta_cmd[i])
        return Trial(self.t, ch, {}, dict(meta or {}))


def _start(B: int, cond: Conditions, speed, rps) -> tuple[np.ndarray, np.ndarray]:
    """Initial states (B, 6) and propeller rates (B,) of a batch: ``cond``'s, or the per-row ``speed`` / ``rps``."""
    x = np.tile([0.0, 0.0, 0.0, cond.speed, 0.0, 0.0], (B, 1))
    if speed is not None:
        x[:, 3] = np.broadcast_to(np.asarray(speed, float), (B,))
    n = np.full(B, cond.rps) if rps is None else np.array(np.broadcast_to(np.asarray(rps, float), (B,)))
    return x, n


def simulate_rudder_batch(model: mmg.MmgModel, Th: Mapping[str, np.ndarray], order: np.ndarray,
                          psi_switch: np.ndarray, side: np.ndarray, cond: Conditions, *, dt: float = 0.1,
                          t_max: float | None = None, t_approach: float = T_APPROACH,
                          until_heading: float = np.deg2rad(200.0), until_reversals: int = 3,
                          exact_reversal: bool = False, speed: np.ndarray | None = None,
                          rps: np.ndarray | None = None) -> BatchRecord:
    """Turning circles (``psi_switch = inf``) and zig-zags of many rows at once.

    Row ``i``: coefficients ``Th[mode][i]``, rudder order ``order[i]`` (rad, > 0) first to
    ``side[i]`` (+1 starboard), reversed (Kempf) when the heading change from the heading
    at execute reaches ``psi_switch[i]`` in the direction of the turn. The steering gear
    moves at ``cond.rudder_rate`` within ``±cond.rudder_limit``; the propeller is held at
    ``cond.rps``. Stops when every row has turned ``until_heading`` (turning rows) or
    reversed ``until_reversals`` times (zig-zag rows), or at ``t_max`` (default the
    approach plus 100 L/U).

    ``exact_reversal``: the heading reaches the switching angle between two samples, at
    ``t* = t_{k-1} + f dt`` (linear interpolation); the sampled rule reverses at ``t_k``,
    up to one step late, which makes an overshoot jump by up to ``r dt`` when a
    coefficient changes a little (a noise floor of the Monte Carlo bands). With this
    option the gear's travel at the reversal sample is ``rate dt (2 − f)`` instead of
    ``rate dt``, i.e. it has moved as if reversed at ``t*`` (with the usual one-step lead
    of the sampled gear), so the overshoots vary smoothly with the coefficients.

    ``speed``, ``rps``: per-row approach speed and propeller rate (B,), instead of ``cond``'s for all rows
    (e.g. each row's own :func:`rows_equilibrium`).
    """
    order, psi_switch, side = (np.asarray(a, float) for a in (order, psi_switch, side))
    B = order.size
    L = model.particulars["L"]
    t_max = t_approach + 100.0 * L / cond.speed if t_max is None else float(t_max)
    nmax = int(round(t_max / dt)) + 1
    sign = rudder_turn_sign(model, cond)
    k_exec = int(np.searchsorted(np.arange(nmax) * dt, min(t_approach, 0.1 * t_max) - 1e-9 * dt))
    step = cond.rudder_rate * dt
    x, nn = _start(B, cond, speed, rps)
    X = np.full((B, nmax, 6), np.nan)
    D = np.zeros((B, nmax))
    C = np.zeros((B, nmax))
    d = side.copy()
    delta = np.zeros(B)
    psi0 = np.zeros(B)
    nrev = np.zeros(B, int)
    turning = ~np.isfinite(psi_switch)
    a_prev = np.zeros(B)
    k = 0
    with np.errstate(all="ignore"):
        while True:
            X[:, k] = x
            stp = step
            if k >= k_exec:
                if k == k_exec:
                    psi0 = x[:, 2].copy()
                    a_prev = np.zeros(B)
                else:
                    a = x[:, 2] - psi0
                    a = np.where((a > -np.pi) & (a <= np.pi), a, np.pi - np.mod(np.pi - a, 2 * np.pi))
                    flip = ~turning & (d * a >= psi_switch)
                    if exact_reversal and flip.any():
                        f = np.clip((psi_switch - d * a_prev) / (d * a - d * a_prev), 0.0, 1.0)
                        stp = np.where(flip, step * (2.0 - np.nan_to_num(f, nan=1.0)), step)
                    d = np.where(flip, -d, d)
                    nrev += flip
                    a_prev = a
                cmd = sign * d * order
            else:
                cmd = np.zeros(B)
            delta = np.clip(delta + np.clip(cmd - delta, -stp, stp), -cond.rudder_limit, cond.rudder_limit)
            C[:, k], D[:, k] = cmd, delta
            head = np.abs(x[:, 2] - psi0)
            done = np.where(turning, head >= until_heading, nrev >= until_reversals) | ~np.isfinite(x).all(axis=1)
            if k == nmax - 1 or (k > k_exec and done.all()):
                break
            x = rows_rk4(model, Th, x, delta, nn, dt)
            k += 1
    n_used = k + 1
    t = np.arange(n_used) * dt
    return BatchRecord(t, X[:, :n_used], D[:, :n_used], C[:, :n_used], np.tile(nn[:, None], (1, n_used)))


def simulate_stopping_batch(model: mmg.MmgModel, Th: Mapping[str, np.ndarray], cond: Conditions, *,
                            dt: float = 0.1, t_max: float | None = None,
                            t_approach: float = T_APPROACH, speed: np.ndarray | None = None,
                            rps: np.ndarray | None = None) -> BatchRecord:
    """Full-astern stopping test of many rows: rudder amidships, the propeller ordered to
    ``cond.rps_astern`` at execute and moving at ``cond.rps_rate`` (instantly if None);
    stops when every row has lost its ahead speed (u ≤ 0) or at ``t_max`` (approach + 200 L/U).
    ``speed``, ``rps``: per-row approach (B,), as in :func:`simulate_rudder_batch`."""
    if cond.rps_astern is None:
        raise ShipidError("no astern propeller rate (the training runs never reversed)")
    B = next(iter(Th.values())).shape[0]
    L = model.particulars["L"]
    t_max = t_approach + 200.0 * L / cond.speed if t_max is None else float(t_max)
    nmax = int(round(t_max / dt)) + 1
    k_exec = int(round(min(t_approach, 0.1 * t_max) / dt))
    nstep = np.inf if cond.rps_rate is None else cond.rps_rate * dt
    x, n = _start(B, cond, speed, rps)
    X = np.full((B, nmax, 6), np.nan)
    Nn = np.zeros((B, nmax))
    zero = np.zeros(B)
    k = 0
    with np.errstate(all="ignore"):
        while True:
            X[:, k] = x
            if k >= k_exec:
                n = n + np.clip(cond.rps_astern - n, -nstep, nstep)
            Nn[:, k] = n
            done = (x[:, 3] <= 0) | ~np.isfinite(x).all(axis=1)
            if k == nmax - 1 or (k > k_exec and done.all()):
                break
            x = rows_rk4(model, Th, x, zero, n, dt)
            k += 1
    m = k + 1
    cmd = np.zeros((B, m))
    cmd[:, k_exec:] = 1.0                    # marks the execute for the metrics
    return BatchRecord(np.arange(m) * dt, X[:, :m], np.zeros((B, m)), cmd, Nn[:, :m])


__all__ = ["check_manoeuvre", "simulate_model", "Conditions", "DEPTH_CLASSES", "depth_class", "depth_check", "training_conditions", "recorded_conditions",
           "resolve_conditions", "equilibrium_speed",
           "equilibrium_rps", "rudder_turn_sign", "ship_model", "default_duration", "theta_rows", "BatchRecord",
           "simulate_rudder_batch", "simulate_stopping_batch", "rudder_move_rates", "rows_deriv", "rows_equilibrium", "rows_dynamics", "rows_rk4", "RUDDER_LIMIT", "T_APPROACH", "straight_du"]
