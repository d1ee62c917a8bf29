"""Standard manoeuvres as closed-loop input laws, and :func:`run_manoeuvre` to record them as a Trial.

Every manoeuvre is an input law ``u(t, x)`` for :func:`shipid.numerics.integrate.simulate`:
a *command* (a sampled schedule, or a rule that looks at the state, such as the
zig-zag) passed through rate- and angle-limited actuators
(:mod:`shipid.simulate.actuators`). The law is stateful and is called once per
sample, in order, as ``simulate`` does; commands and actual actuator positions
are both recorded (``delta_cmd`` and ``delta`` ...).

Manoeuvre names (parsed by :func:`parse_manoeuvre`):

``straight``
    All inputs held at their nominal values.
``turning-D`` / ``turning-D-port``
    Turning circle: after a straight approach the rudder is ordered to D degrees
    (the side that turns the ship to starboard, or to port) and held (ITTC 7.5-04-02-01).
``zigzag-D`` / ``zigzag-D-P`` / ``...-port``
    Zig-zag D/P (P = D when omitted): rudder to D degrees (first to starboard unless
    ``-port``); the rudder is reversed at the first sample where the heading
    change from the heading at execution reaches P degrees in the direction of the
    turn (Kempf's zig-zag, ITTC 7.5-04-02-01).
``prbs-A`` / ``prbs-A-T``
    Pseudo-random binary rudder ±A degrees from a maximum-length shift-register
    sequence with clock (minimum) period T seconds (default 30 s), seeded.
``dp-surge`` / ``dp-sway-yaw`` / ``dp-azimuth`` (optionally ``-A``)
    The decoupled DP sea trials of Fossen, Sagatun & Sørensen (1996) §4.2:
    (1) uncoupled surge with the main propellers p1 = p2, (2) coupled sway and yaw
    with the tunnel thrusters p3, p4, p5, (3) the azimuth thruster p6 alone at
    several azimuth angles alpha6. Steps of pitch ratio A (default 0.5) added to
    the nominal (zero-thrust) pitch p_i0. The paper shows these trials only as
    figures (Figs. 5–7); the step times chosen here are ours (fractions of the
    duration, listed in :data:`DP_SEQUENCES`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Callable, Mapping

import numpy as np

import shipid
from shipid.io.trial import CHANNELS, Trial
from shipid.errors import ShipidError
from shipid.simulate.actuators import RateLimitedActuator, steering_gear
from shipid.numerics.integrate import rk4_step, simulate
from shipid.models.ship_model import ShipModel

#: Default durations (s) by manoeuvre kind, when none is given.
DEFAULT_DURATION: dict[str, float] = {"straight": 120.0, "turning": 900.0, "zigzag": 900.0,
                                      "prbs": 900.0, "dp": 600.0}
#: Straight approach before the rudder is ordered (s), for turning circles and zig-zags.
T_EXECUTE = 10.0
#: Largest record run_manoeuvre will make (samples), to refuse typos such as --duration 1e9.
MAX_SAMPLES = 10_000_000
#: Default PRBS clock (minimum) period (s).
PRBS_MIN_PERIOD = 30.0
#: Default actuator limits where the model gives none: pitch-ratio rate (1/s; 0 → 1 in 10 s),
#: pitch-ratio magnitude (-), azimuth rate (rad/s; 10 °/s, a typical azimuth slewing rate).
PITCH_RATE = 0.1
PITCH_LIMIT = 1.0
AZIMUTH_RATE = np.deg2rad(10.0)

#: DP trial sequences: per trial, a list of (fraction of the duration, {input: value}); pitch
#: values are multiples of the amplitude A added to the nominal pitch, ``alpha6`` is in degrees
#: (absolute). Between steps the values are held.
DP_SEQUENCES: dict[str, list[tuple[float, dict[str, float]]]] = {
    # (1) uncoupled surge: both main propellers together (no yaw moment since l1 = l2, eq. 7)
    "dp-surge": [(0.0, {"p1": 0.0, "p2": 0.0}), (0.03, {"p1": 1.0, "p2": 1.0}),
                 (0.20, {"p1": 0.0, "p2": 0.0}), (0.37, {"p1": -1.0, "p2": -1.0}),
                 (0.53, {"p1": 0.0, "p2": 0.0}), (0.70, {"p1": 0.5, "p2": 0.5}),
                 (0.87, {"p1": 0.0, "p2": 0.0})],
    # (2) coupled sway and yaw: tunnel thrusters; same sign = sway, opposite = yaw (eq. 29 arms)
    "dp-sway-yaw": [(0.0, {"p3": 0.0, "p4": 0.0, "p5": 0.0}),
                    (0.03, {"p3": 1.0, "p4": 1.0, "p5": 1.0}),
                    (0.20, {"p3": 0.0, "p4": 0.0, "p5": 0.0}),
                    (0.33, {"p3": -1.0, "p4": -1.0, "p5": 1.0}),
                    (0.50, {"p3": 0.0, "p4": 0.0, "p5": 0.0}),
                    (0.63, {"p3": -1.0, "p4": -1.0, "p5": -1.0}),
                    (0.80, {"p3": 1.0, "p4": 1.0, "p5": -1.0}),
                    (0.93, {"p3": 0.0, "p4": 0.0, "p5": 0.0})],
    # (3) azimuth test: thruster 6 alone at three azimuth angles
    "dp-azimuth": [(0.0, {"p6": 0.0, "alpha6": 90.0}), (0.03, {"p6": 1.0}),
                   (0.20, {"p6": 0.0}), (0.30, {"alpha6": 45.0}), (0.37, {"p6": 1.0}),
                   (0.53, {"p6": 0.0}), (0.63, {"alpha6": 135.0}), (0.70, {"p6": 1.0}),
                   (0.87, {"p6": 0.0})],
}


@dataclass(frozen=True)
class ManoeuvreSpec:
    """A parsed manoeuvre name.

    Attributes
    ----------
    name : str
        The name as given (canonical lower case).
    kind : str
        ``straight``, ``turning``, ``zigzag``, ``prbs`` or ``dp``.
    params : mapping
        ``delta``, ``psi`` (rad), ``side`` (+1 starboard, -1 port), ``amplitude``,
        ``min_period`` (s), ``sequence`` (DP) as the kind needs.
    """

    name: str
    kind: str
    params: Mapping[str, object] = field(default_factory=dict)

    @property
    def default_duration(self) -> float:
        return DEFAULT_DURATION[self.kind]

    @property
    def driven_inputs(self) -> tuple[str, ...]:
        """Input names the manoeuvre commands."""
        if self.kind == "dp":
            names: list[str] = []
            for _, step in DP_SEQUENCES[str(self.params["sequence"])]:
                names += [n for n in step if n not in names]
            return tuple(names)
        return () if self.kind == "straight" else ("delta",)


_NUM = r"(\d+(?:\.\d+)?)"
_FORMS = ("straight, turning-D[-port], zigzag-D[-P][-port], prbs-A[-T], "
          "dp-surge[-A], dp-sway-yaw[-A], dp-azimuth[-A]  (D, P, A in degrees; T in s; DP A a pitch ratio)")


def parse_manoeuvre(text: str) -> ManoeuvreSpec:
    """Parse a manoeuvre name such as ``zigzag-20``, ``turning-35-port``, ``prbs-10-20``, ``dp-surge``.

    Raises
    ------
    ShipidError
        For a name that is not one of the forms above, or an angle out of range.
    """
    s = text.strip().lower()
    if s == "straight":
        return ManoeuvreSpec(s, "straight")
    m = re.fullmatch(rf"turning-{_NUM}(-port|-starboard|-stbd)?", s)
    if m:
        d = _angle(m.group(1), text)
        return ManoeuvreSpec(s, "turning", {"delta": d, "side": -1 if m.group(2) == "-port" else 1})
    m = re.fullmatch(rf"zig-?zag-{_NUM}(?:-{_NUM})?(-port|-starboard|-stbd)?", s)
    if m:
        d = _angle(m.group(1), text)
        p = _angle(m.group(2) or m.group(1), text)
        return ManoeuvreSpec(s, "zigzag", {"delta": d, "psi": p,
                                           "side": -1 if m.group(3) == "-port" else 1})
    m = re.fullmatch(rf"prbs-{_NUM}(?:-{_NUM})?", s)
    if m:
        a = _angle(m.group(1), text)
        tmin = float(m.group(2)) if m.group(2) else PRBS_MIN_PERIOD
        if tmin <= 0:
            raise ShipidError(f"manoeuvre {text!r}: PRBS minimum period must be positive")
        return ManoeuvreSpec(s, "prbs", {"amplitude": a, "min_period": tmin})
    m = re.fullmatch(rf"(dp-surge|dp-sway-yaw|dp-azimuth)(?:-{_NUM})?", s)
    if m:
        a = float(m.group(2)) if m.group(2) else 0.5
        if not 0 < a <= PITCH_LIMIT:
            raise ShipidError(f"manoeuvre {text!r}: pitch step must be in (0, {PITCH_LIMIT}]")
        return ManoeuvreSpec(s, "dp", {"sequence": m.group(1), "amplitude": a})
    raise ShipidError(f"unknown manoeuvre {text!r} (known forms: {_FORMS})")


def _angle(deg: str, text: str) -> float:
    v = float(deg)
    if not 0 < v <= 90:
        raise ShipidError(f"manoeuvre {text!r}: angle {v:g} deg must be in (0, 90]")
    return float(np.deg2rad(v))


# -- sampled command signals ---------------------------------------------------------------

#: Feedback taps of maximum-length Fibonacci LFSRs (bit numbers, 1-based; Xilinx XAPP052 table).
_LFSR_TAPS = {5: (5, 3), 6: (6, 5), 7: (7, 6), 8: (8, 6, 5, 4), 9: (9, 5), 10: (10, 7),
              11: (11, 9), 12: (12, 6, 4, 1), 13: (13, 4, 3, 1), 14: (14, 5, 3, 1),
              15: (15, 14), 16: (16, 15, 13, 4)}


def mls_bits(n: int, rng: np.random.Generator, order: int | None = None) -> np.ndarray:
    """``n`` bits (0/1) of a maximum-length shift-register sequence with a seeded start.

    The register length is the smallest (≥ 5) whose period ``2**m - 1`` covers ``n``
    bits; the initial register is drawn from ``rng`` (never all zeros), so the
    sequence is a seeded segment of an m-sequence. ``order`` forces the register length.
    """
    m = order if order is not None else next((k for k in sorted(_LFSR_TAPS) if 2 ** k - 1 >= n),
                                             max(_LFSR_TAPS))
    taps = _LFSR_TAPS[m]
    reg = rng.integers(0, 2, size=m)
    if not reg.any():
        reg[rng.integers(0, m)] = 1
    out = np.empty(n, dtype=int)
    for i in range(n):
        out[i] = reg[-1]
        fb = 0
        for tap in taps:
            fb ^= int(reg[tap - 1])
        reg = np.roll(reg, 1)
        reg[0] = fb
    return out


def prbs_signal(t: np.ndarray, amplitude: float, min_period: float, rng: np.random.Generator,
                t_start: float = 0.0) -> np.ndarray:
    """A PRBS command ``±amplitude`` on the grid ``t`` (zero before ``t_start``).

    The level may change only every ``c`` samples, ``c = ceil(min_period / dt)``
    counted from the first sample at or after ``t_start``, so every hold lasts at
    least ``min_period`` (up to the end of the record).
    """
    t = np.asarray(t, dtype=float)
    dt = float(np.median(np.diff(t)))
    c = max(1, int(np.ceil(min_period / dt - 1e-9)))
    k0 = int(np.searchsorted(t, t_start - 1e-9 * dt))
    n_bits = max(1, int(np.ceil((t.size - k0) / c)))
    bits = mls_bits(n_bits, rng)
    out = np.zeros(t.size)
    out[k0:] = amplitude * (2.0 * np.repeat(bits, c)[: t.size - k0] - 1.0)
    return out


def rate_limit_signal(command: np.ndarray, dt: float, limit: float, rate_limit: float,
                      initial: float = 0.0) -> np.ndarray:
    """Pass a sampled command through a :class:`RateLimitedActuator` (open loop)."""
    act = RateLimitedActuator(dt=dt, rate_limit=rate_limit, lo=-limit, hi=limit, value=initial)
    return np.array([act.step(c) for c in command])


# -- closed-loop laws ------------------------------------------------------------------------

class ManoeuvreLaw:
    """Input law ``u(t, x)``: commands → actuators → the full input vector.

    Subclasses implement :meth:`commands` (the commanded value of every driven input
    at sample ``k``). The law counts its calls: call ``k`` is sample ``k`` of the
    uniform grid ``t0 + k dt`` (as :func:`simulate` calls it).
    """

    def __init__(self, model: ShipModel, dt: float, speed: float, driven: tuple[str, ...],
                 actuators: dict[str, RateLimitedActuator]):
        self.model = model
        self.dt = dt
        self.u_nom = model.nominal_input(speed)
        self.index = {n: model.input_names.index(n) for n in driven}
        self.actuators = actuators
        self.k = 0
        self.cmd_log: dict[str, list[float]] = {n: [] for n in driven}

    def commands(self, k: int, t: float, x: np.ndarray) -> dict[str, float]:
        raise NotImplementedError

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        cmds = self.commands(self.k, t, x)
        u = self.u_nom.copy()
        for name, i in self.index.items():
            self.cmd_log[name].append(cmds[name])
            u[i] = self.actuators[name].step(cmds[name])
        self.k += 1
        return u

    def command_history(self) -> dict[str, np.ndarray]:
        return {n: np.asarray(v) for n, v in self.cmd_log.items()}


class ScheduleLaw(ManoeuvreLaw):
    """Commands from sampled signals (open loop), one array per driven input."""

    def __init__(self, model, dt, speed, schedule: dict[str, np.ndarray], actuators):
        super().__init__(model, dt, speed, tuple(schedule), actuators)
        self.schedule = schedule

    def commands(self, k, t, x):
        return {n: float(s[min(k, s.size - 1)]) for n, s in self.schedule.items()}


class ZigZagLaw(ManoeuvreLaw):
    """Kempf zig-zag δ/ψ as a closed-loop rule on the heading.

    Before ``t_exec`` the rudder command is the nominal one. At the first sample
    at or after ``t_exec`` the heading ψ_0 is stored and the rudder ordered to the
    side that turns the ship in direction ``d`` (+1 starboard). Thereafter, at
    every sample ``k``: if ``d (ψ_k − ψ_0) ≥ ψ_switch`` then ``d ← −d`` and the
    command reverses at that very sample.
    """

    def __init__(self, model, dt, speed, delta: float, psi_switch: float, side: int,
                 rudder_sign: float, t_exec: float, actuator: RateLimitedActuator):
        super().__init__(model, dt, speed, ("delta",), {"delta": actuator})
        if model.heading_index is None:
            raise ShipidError(f"vessel {model.name!r} has no heading state: cannot run a zig-zag")
        self.delta, self.psi_switch, self.d = delta, psi_switch, int(side)
        self.rudder_sign, self.t_exec = rudder_sign, t_exec
        self.psi0: float | None = None
        self.delta_nom = float(self.u_nom[self.index["delta"]])
        self.switch_samples: list[int] = []

    def commands(self, k, t, x):
        psi = float(x[self.model.heading_index])
        if t < self.t_exec - 1e-9 * self.dt:
            return {"delta": self.delta_nom}
        if self.psi0 is None:
            self.psi0 = psi
        elif self.d * _wrap(psi - self.psi0) >= self.psi_switch:
            self.d = -self.d
            self.switch_samples.append(k)
        return {"delta": self.delta_nom + self.rudder_sign * self.d * self.delta}


def _wrap(a: float) -> float:
    """Angle to (-π, π] (unchanged, bit for bit, when already there): models may wrap ψ."""
    return a if -np.pi < a <= np.pi else float(np.pi - (np.pi - a) % (2 * np.pi))


def rudder_turn_sign(model: ShipModel, speed: float) -> float:
    """+1 if positive δ turns the ship to starboard (r > 0), −1 otherwise.

    Conventions differ between models (Abkowitz-type models have N_δ < 0, so
    positive δ turns to port), so the manoeuvres ask the model: the sign of the
    yaw-rate response to a small rudder step, from ``∂ṙ/∂δ`` when the state has an
    ``r`` entry, else from the heading after 10 s of a 5° step.
    """
    x0 = model.x0(speed)
    u0 = model.nominal_input(speed)
    if "delta" not in model.input_names:
        raise ShipidError(f"vessel {model.name!r} has no rudder input (inputs: "
                          f"{', '.join(model.input_names)})")
    i = model.input_names.index("delta")
    du = np.zeros_like(u0)
    du[i] = np.deg2rad(5.0)
    if "r" in model.state_names:
        j = model.state_names.index("r")
        d = model.f(0.0, x0, u0 + du, model.theta)[j] - model.f(0.0, x0, u0, model.theta)[j]
        if d != 0 and np.isfinite(d):
            return float(np.sign(d))
    if model.heading_index is None:
        raise ShipidError(f"vessel {model.name!r} has neither r nor a heading state")
    h = 0.05
    xa, xb = x0.copy(), x0.copy()
    for k in range(200):
        xa = rk4_step(model.f, k * h, xa, u0 + du, model.theta, h)
        xb = rk4_step(model.f, k * h, xb, u0, model.theta, h)
    d = xa[model.heading_index] - xb[model.heading_index]
    if d == 0 or not np.isfinite(d):
        raise ShipidError(f"vessel {model.name!r}: heading does not respond to the rudder")
    return float(np.sign(d))


def manoeuvre_law(spec: ManoeuvreSpec, model: ShipModel, t: np.ndarray, speed: float,
                  rng: np.random.Generator) -> ManoeuvreLaw:
    """The closed-loop input law of ``spec`` for ``model`` on the uniform grid ``t``."""
    dt = float(t[1] - t[0])
    missing = [n for n in spec.driven_inputs if n not in model.input_names]
    if missing:
        raise ShipidError(f"manoeuvre {spec.name!r} drives {', '.join(missing)} but vessel "
                          f"{model.name!r} has inputs {', '.join(model.input_names) or 'none'}")
    t_exec = t[0] + min(T_EXECUTE, 0.1 * (t[-1] - t[0]))
    if spec.kind == "straight":
        return ScheduleLaw(model, dt, speed, {}, {})
    if spec.kind in ("turning", "zigzag", "prbs"):
        u_nom = model.nominal_input(speed)
        d_nom = float(u_nom[model.input_names.index("delta")])
        gear = steering_gear(dt, model.rudder_limit, model.rudder_rate_limit, initial=d_nom)
        if spec.kind == "prbs":
            cmd = d_nom + prbs_signal(t, float(spec.params["amplitude"]),
                                      float(spec.params["min_period"]), rng, t_start=t_exec)
            return ScheduleLaw(model, dt, speed, {"delta": cmd}, {"delta": gear})
        sign = rudder_turn_sign(model, speed)
        delta, side = float(spec.params["delta"]), int(spec.params["side"])
        if spec.kind == "turning":
            cmd = np.where(t >= t_exec - 1e-9 * dt, d_nom + sign * side * delta, d_nom)
            return ScheduleLaw(model, dt, speed, {"delta": cmd}, {"delta": gear})
        return ZigZagLaw(model, dt, speed, delta, float(spec.params["psi"]), side, sign, t_exec, gear)
    # DP sea trials
    seq = DP_SEQUENCES[str(spec.params["sequence"])]
    amp = float(spec.params["amplitude"])
    u_nom = model.nominal_input(speed)
    duration = t[-1] - t[0]
    schedule: dict[str, np.ndarray] = {}
    actuators: dict[str, RateLimitedActuator] = {}
    for name in spec.driven_inputs:
        nom = float(u_nom[model.input_names.index(name)])
        cmd = np.full(t.size, nom)
        for frac, step in seq:
            if name in step:
                value = np.deg2rad(step[name]) if name.startswith("alpha") else nom + amp * step[name]
                cmd[t >= t[0] + frac * duration - 1e-9 * dt] = value
        schedule[name] = cmd
        if name.startswith("alpha"):
            rate = model.input_rate_limits.get(name, AZIMUTH_RATE)
            lim = model.input_limits.get(name, np.inf)
        else:
            rate = model.input_rate_limits.get(name, PITCH_RATE)
            lim = model.input_limits.get(name, PITCH_LIMIT)
        actuators[name] = RateLimitedActuator(dt=dt, rate_limit=rate, lo=-lim, hi=lim, value=cmd[0])
    return ScheduleLaw(model, dt, speed, schedule, actuators)


def run_manoeuvre(model: ShipModel, name: str, duration: float | None = None, dt: float = 0.1,
                  seed: int = 0, *, speed: float | None = None, method: str = "rk4",
                  substeps: int = 1, progress: Callable[[int], None] | None = None) -> Trial:
    """Simulate ``model`` through the manoeuvre ``name`` and return the record as a Trial.

    Parameters
    ----------
    model : ShipModel
    name : str
        Manoeuvre name (see the module docstring and :func:`parse_manoeuvre`).
    duration : float, optional
        Seconds; default by kind (:data:`DEFAULT_DURATION`).
    dt : float
        Sample interval of the record and of the input hold (s).
    seed : int
        Seed of every random draw (the PRBS register).
    speed : float, optional
        Approach speed (m/s); default ``model.service_speed``.
    method, substeps : passed to :func:`simulate`.
    progress : callable, optional
        Called with the number of steps done.

    Returns
    -------
    Trial
        Channels ``model.outputs(...)`` plus every input (actual values, SI) and, for
        driven inputs, the command as ``<name>_cmd``; meta ``vessel``, ``manoeuvre``,
        ``seed``, ``dt``, ``speed``, ``source``.
    """
    spec = parse_manoeuvre(name)
    duration = spec.default_duration if duration is None else float(duration)
    if not (dt > 0 and np.isfinite(dt)):
        raise ShipidError(f"time step must be positive, got {dt}")
    if not (duration > dt and np.isfinite(duration)):
        raise ShipidError(f"duration must exceed the time step, got {duration} s")
    n = int(round(duration / dt)) + 1
    if n > MAX_SAMPLES:
        raise ShipidError(f"{n} samples requested (duration {duration:g} s at dt {dt:g} s); "
                          f"the limit is {MAX_SAMPLES}")
    t = np.arange(n) * dt
    speed = model.service_speed if speed is None else float(speed)
    rng = np.random.default_rng(seed)
    law = manoeuvre_law(spec, model, t, speed, rng)
    sim = simulate(model.f, t, model.x0(speed), law, model.theta, method=method,
                   substeps=substeps, progress=progress)
    if not np.all(np.isfinite(sim.x)):
        raise ShipidError(f"simulation of {model.name!r} {spec.name!r} diverged (non-finite state)")
    channels = dict(model.outputs(sim.t, sim.x, sim.u))
    units = {k: model.output_units.get(k, CHANNELS.get(k, "-")) for k in channels}
    for i, nm in enumerate(model.input_names):
        channels.setdefault(nm, sim.u[:, i])
        units.setdefault(nm, CHANNELS.get(nm, "-"))
    for nm, c in law.command_history().items():
        channels[f"{nm}_cmd"] = c
        units[f"{nm}_cmd"] = CHANNELS.get(nm, "-")
    meta = {"vessel": model.name, "manoeuvre": spec.name, "seed": int(seed), "dt": dt,
            "speed": speed, "source": f"simulated by shipid {shipid.__version__}"}
    return Trial(t, channels, units, meta)
