"""A loaded-condition IMU + rudder stream with a load change, for the online mass / CM monitor.

The ship is the linear model (11) of :mod:`shipid.models.roll` (Linder et al. 2015), simulated
exactly on the sample grid (:func:`shipid.models.roll.simulate_zoh`). Up to ``change_at`` the load is
``(m0, zm0)``; from there on ``(m1, zm1)``: the state (roll, heading, sway, roll and yaw rate) carries over
and the system matrices switch, as for a load shifted in one sample. The rudder is the rate-limited PRBS of
:func:`shipid.models.roll_sim.rudder_prbs`; the wave roll moment is the narrow-band moment of
:func:`shipid.models.roll_sim.wave_moment`, scaled once (to the requested roll std in the first condition)
and then kept as a physical moment; the gyro / accelerometer noise and constant biases are those of
:class:`shipid.models.roll_sim.NoiseSpec` (eq. 9). The nominal and calibration datasets are simulated by
:func:`shipid.models.roll_sim.simulate_condition` with their own seeds.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from shipid.io.files import write_trial
from shipid.io.trial import Trial
from shipid.errors import OutputExistsError, ShipidError
from shipid.models.roll import imu_outputs, params_from_vessel, simulate_zoh
from shipid.models.roll_reduced import CALIBRATION, NOMINAL, KnownParams
from shipid.models.roll_sim import NoiseSpec, rudder_prbs, simulate_condition, wave_moment
from shipid.vessels import load_vessel


@dataclass(frozen=True)
class StreamSpec:
    """What to simulate: durations (s), sampling (Hz), the load before / after the change, the noise."""

    duration: float = 1800.0
    fs: float = 50.0
    change_at: float | None = 900.0
    m0: float = 0.4
    zm0: float = -0.182
    m1: float = 0.7
    zm1: float = -0.14
    reference_duration: float = 300.0      # nominal and calibration datasets
    delta_amp: float = float(np.deg2rad(5.0))
    delta_clock: float = 0.5
    noise: NoiseSpec = NoiseSpec.combined()


def simulate_stream(spec: StreamSpec = StreamSpec(), *, vessel: str = "fishing-vessel",
                    seed: int | np.random.SeedSequence = 0) -> dict:
    """Nominal, calibration datasets and the loaded stream (with the change), and the truth.

    Returns ``{"nominal": Trial, "calibration": Trial, "stream": Trial, "truth": dict}``; every random draw
    comes from children of ``SeedSequence(seed)`` (nominal, calibration, stream rudder, waves, sensors).
    """
    v = load_vessel(vessel)
    ss = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(int(seed))
    c_nom, c_cal, c_rud, c_wave, c_sens = ss.spawn(5)
    kw = dict(duration=spec.reference_duration, fs=spec.fs, delta_amp=spec.delta_amp, delta_clock=spec.delta_clock,
              noise=spec.noise)
    nominal = simulate_condition(params_from_vessel(v, NOMINAL), seed=c_nom, condition=NOMINAL, **kw)
    calibration = simulate_condition(params_from_vessel(v, CALIBRATION), seed=c_cal, condition=CALIBRATION, **kw)
    dt = 1.0 / spec.fs
    n = int(round(spec.duration * spec.fs))
    delta = rudder_prbs(n, dt, spec.delta_amp, spec.delta_clock, np.random.default_rng(c_rud))
    th0 = params_from_vessel(v, "loaded").loaded(spec.m0, spec.zm0)
    th1 = th0.loaded(spec.m1, spec.zm1)
    k = n if spec.change_at is None else min(n, max(0, int(round(spec.change_at * spec.fs))))
    tau = np.zeros(n)
    if spec.noise.wave_roll_deg > 0:
        w = wave_moment(n, dt, spec.noise, np.random.default_rng(c_wave))
        Xw, _ = simulate_zoh(th0, np.zeros(n), dt, tau=w)
        tau = w * (np.deg2rad(spec.noise.wave_roll_deg) / np.std(Xw[:, 0]))
    parts = []
    x0 = None
    for th, a, b in ((th0, 0, k), (th1, k, n)):
        if b <= a:
            continue
        e = min(b + 1, n)                  # one sample more: the state at the switch, under this condition
        X, Xdot = simulate_zoh(th, delta[a:e], dt, tau=tau[a:e], x0=x0)
        x0 = X[-1]
        parts.append(imu_outputs(th, X[:b - a], Xdot[:b - a]))
    out = {key: np.concatenate([p[key] for p in parts]) for key in ("p", "a_s", "r", "phi")}
    rs = np.random.default_rng(c_sens)
    nz = spec.noise
    p = out["p"] + nz.gyro_bias + nz.gyro_std * rs.standard_normal(n)
    a_s = out["a_s"] + nz.acc_bias + nz.acc_std * rs.standard_normal(n)
    r = out["r"] + nz.gyro_bias + nz.gyro_std * rs.standard_normal(n)
    t = np.arange(n) * dt
    stream = Trial(t, {"p": p, "a_s": a_s, "r": r, "delta": delta},
                   meta={"vessel": vessel, "condition": "loaded", "simulated": True})
    g = v.values("general")
    truth = {"vessel": vessel, "seed": (int(seed) if not isinstance(seed, np.random.SeedSequence)
                                        else [int(x) for x in np.atleast_1d(seed.entropy)] + list(seed.spawn_key)), "change_at": spec.change_at if k < n else None,
             "before": {"m": spec.m0, "zm_bar": spec.zm0}, "after": {"m": spec.m1, "zm_bar": spec.zm1},
             "z_f": float(g["z_f"]), "spec": {**asdict(spec), "noise": asdict(spec.noise)}}
    return {NOMINAL: nominal, CALIBRATION: calibration, "stream": stream, "truth": truth}


def truth_at(truth: dict, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """True ``(m, zm_bar)`` at stream times ``t`` from the sidecar ``truth``."""
    t = np.asarray(t, dtype=float)
    ca = truth.get("change_at")
    after = np.zeros(t.shape, dtype=bool) if ca is None else t >= ca
    m = np.where(after, truth["after"]["m"], truth["before"]["m"])
    z = np.where(after, truth["after"]["zm_bar"], truth["before"]["zm_bar"])
    return m, z


def known_toml(vessel: str = "fishing-vessel", z_f: bool = True) -> str:
    """``known.toml`` text of :func:`shipid.methods.masscm.known.read_known` for a packaged vessel."""
    kn = KnownParams.from_vessel(vessel)
    lines = [f"{k} = {getattr(kn, k)!r}" for k in ("U", "M", "zg_bar", "m_c", "zc_bar", "zs_bar", "g")]
    if z_f:
        lines.append(f"z_f = {float(load_vessel(vessel).values('general')['z_f'])!r}")
    return "# known parameters (SI) of " + vessel + "\n" + "\n".join(lines) + "\n"


def write_stream_files(sim: dict, out: str | Path, *, force: bool = False) -> dict[str, Path]:
    """Write the stream to ``out`` and, beside it, ``<stem>.nominal.csv``, ``<stem>.calibration.csv``,
    ``<stem>.known.toml`` and the truth ``<stem>.truth.json``. Nothing is written if any exists (no force)."""

    out = Path(out)
    stem = out.with_suffix("")
    paths = {"stream": out, NOMINAL: Path(f"{stem}.nominal{out.suffix}"),
             CALIBRATION: Path(f"{stem}.calibration{out.suffix}"), "known": Path(f"{stem}.known.toml"),
             "truth": Path(f"{stem}.truth.json")}
    if not force:
        for p in paths.values():
            if p.exists():
                raise OutputExistsError(str(p))
    for key in ("stream", NOMINAL, CALIBRATION):
        write_trial(sim[key], paths[key], force=force)
    paths["known"].write_text(known_toml(sim["truth"]["vessel"]), encoding="utf-8")
    paths["truth"].write_text(json.dumps(sim["truth"], indent=1), encoding="utf-8")
    return paths


def simulate_stream_cmd(vessel: str, out: str, *, duration: float | None, seed: int, change_at: float | None,
                        to: str | None, force: bool) -> None:
    """``shipid simulate VESSEL mass-cm-stream``: simulate and write the files, one line on stdout."""
    import click

    if vessel not in ("fishing-vessel", "fishing_vessel", "linder2015"):
        raise ShipidError(f"mass-cm-stream is defined for the fishing-vessel (Linder et al. 2015), not {vessel!r}")
    if not str(out).lower().endswith(".csv"):
        raise ShipidError(f"{out}: the stream must be a .csv file")
    spec = StreamSpec() if duration is None else StreamSpec(duration=float(duration))
    m1, z1 = spec.m1, spec.zm1
    if to is not None:
        try:
            m1, z1 = (float(x) for x in to.split(","))
        except ValueError:
            raise ShipidError(f"--to must be 'M,ZM' (kg, m), got {to!r}") from None
        if not m1 > 0:
            raise ShipidError(f"--to: the mass must be positive, got {m1:g}")
    if change_at is not None and not 0 < change_at < spec.duration:
        raise ShipidError(f"--change-at must lie inside the stream (0, {spec.duration:g}) s, got {change_at:g}")
    spec = StreamSpec(**{**asdict(spec), "noise": spec.noise, "change_at": change_at, "m1": m1, "zm1": z1})
    if seed < 0:
        raise ShipidError(f"--seed must be >= 0, got {seed}")
    paths = write_stream_files(simulate_stream(spec, vessel="fishing-vessel", seed=seed), out, force=force)
    ch = "no load change" if change_at is None else (f"load {spec.m0:g} kg at {spec.zm0:g} m -> {m1:g} kg at "
                                                     f"{z1:g} m at {change_at:g} s")
    click.echo(f"wrote {paths['stream']} ({spec.duration:g} s at {spec.fs:g} Hz, {ch}, seed {seed}), "
               f"{paths['nominal']}, {paths['calibration']}, {paths['known']}, {paths['truth']}")


__all__ = ["simulate_stream_cmd", "StreamSpec", "simulate_stream", "truth_at", "known_toml", "write_stream_files"]
