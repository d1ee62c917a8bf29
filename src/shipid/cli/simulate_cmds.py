"""Generic commands: ``shipid simulate``, ``shipid vessels``, ``shipid demo``."""

from __future__ import annotations

import datetime as _dt
import time
from pathlib import Path

import click

from shipid.cli import CONTEXT, cli
from shipid.errors import OutputExistsError, ShipidError

_SUFFIXES = (".csv", ".parquet", ".pq")


@cli.command("simulate", context_settings=CONTEXT)
@click.argument("vessel")
@click.argument("manoeuvre")
@click.option("--out", "-o", "out", required=True, type=click.Path(dir_okay=False),
              help="Output trial file; .csv or .parquet (by extension).")
@click.option("--duration", type=float, default=None,
              help="Seconds [default: by manoeuvre, e.g. 900 for zig-zags].")
@click.option("--dt", type=float, default=None,
              help="Sample interval (s) [default: the vessel's trial sampling, [trials].dt of its file (esso-osaka: "
                   "1 s), else 0.1].")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Seed of every random draw (PRBS, --noise).")
@click.option("--speed", type=float, default=None, help="Approach speed in m/s [default: service speed].")
@click.option("--noise", is_flag=True,
              help="Add sensor noise: the vessel's trial sensors where its file states them (esso-osaka: Yoon & Rhee "
                   "eq. 19), else shipid.simulate.noise.DEFAULT_NOISE.")
@click.option("--rps", type=float, default=None,
              help="Identified MMG models only: propeller rate, rev/s [default: from the training data].")
@click.option("--rudder-rate", type=float, default=None,
              help="Identified MMG models only: steering-gear rate, deg/s [default: from the training data].")
@click.option("--water-depth", type=float, default=None,
              help="Identified MMG models only: water depth, m [default: the training runs']; a depth class "
                   "(h/T) other than the training runs' is a warning (no shallow-water terms).")
@click.option("--force", is_flag=True, help="Overwrite an existing output file.")
@click.option("--change-at", type=float, default=None,
              help="mass-cm-stream: time of the load change (s) [default: no change].")
@click.option("--to", "to", type=str, default=None,
              help="mass-cm-stream: the load after the change, 'M,ZM' (kg, m) [default: 0.7,-0.14].")
def simulate_cmd(vessel: str, manoeuvre: str, out: str, duration: float | None, dt: float,
                 seed: int, speed: float | None, rps: float | None, rudder_rate: float | None,
                 noise: bool, force: bool, change_at: float | None = None, to: str | None = None,
                 water_depth: float | None = None) -> None:
    """Simulate VESSEL through MANOEUVRE and write the trial.

    \b
    VESSEL     a packaged vessel (see `shipid vessels`), `nomoto`, an identified
               MMG model: MODEL.json of `shipid identify mmg` (or published:NAME),
               or a parameter file of `shipid export params` (.toml, .yaml)
    MANOEUVRE  straight | turning-35[-port] | zigzag-20 | zigzag-10-5 | prbs-10[-T]
               | dp-surge | dp-sway-yaw | dp-azimuth
               | mass-cm-stream (fishing-vessel: a 50-Hz loaded IMU + rudder stream with a load
               change, its nominal / calibration datasets, known.toml and truth beside it)
    Example: shipid simulate esso-osaka zigzag-20 --out z.csv
    """
    if manoeuvre == "mass-cm-stream":
        from shipid.simulate.masscm_stream import simulate_stream_cmd
        simulate_stream_cmd(vessel, out, duration=duration, seed=seed, change_at=change_at, to=to, force=force)
        return
    if Path(vessel).suffix.lower() in (".toml", ".yaml", ".yml"):     # a parameter file of `shipid export params`
        from shipid.cli.export_cmds import simulate_params_cmd
        return simulate_params_cmd(vessel, manoeuvre, out, duration=duration, dt=0.1 if dt is None else dt, seed=seed, speed=speed, rps=rps,
                                   rudder_rate=rudder_rate, noise=noise, force=force, water_depth=water_depth)
    from shipid.methods.mmg.cli_imo import is_model_spec, simulate_identified

    if is_model_spec(vessel):
        if seed < 0:
            raise ShipidError(f"--seed must be >= 0, got {seed}")
        return simulate_identified(vessel, manoeuvre, out, duration=duration, dt=0.1 if dt is None else dt,
                                   seed=seed, speed=speed,
                                   rps=rps, rudder_rate=rudder_rate, noise=noise, force=force,
                                   water_depth=water_depth)
    if rps is not None or rudder_rate is not None or water_depth is not None:
        raise ShipidError("--rps, --rudder-rate and --water-depth apply to identified MMG models (MODEL.json) only")
    from shipid.simulate.manoeuvres import parse_manoeuvre
    from shipid.simulate.registry import get_ship_model
    from shipid.simulate.run import default_dt, simulate_vessel

    path = Path(out)
    if path.suffix.lower() not in _SUFFIXES:
        raise ShipidError(f"{out}: output must end in .csv or .parquet")
    if path.exists() and not force:
        raise OutputExistsError(out)
    spec = parse_manoeuvre(manoeuvre)
    if seed < 0:
        raise ShipidError(f"--seed must be >= 0, got {seed}")
    model = get_ship_model(vessel)
    from shipid.io.files import sensor_meta_lost, write_trial
    from shipid.progress import progress_bar

    dt = default_dt(vessel) if dt is None else dt
    dur = spec.default_duration if duration is None else duration
    steps = max(1, int(round(dur / dt))) if dt > 0 else 1
    with progress_bar(steps, f"{model.name} {spec.name}") as advance:
        last = [0]

        def tick(k: int) -> None:
            k = min(k, steps)
            if k - last[0] >= 100 or k == steps:
                advance(k - last[0])
                last[0] = k

        trial = simulate_vessel(vessel, manoeuvre, duration=duration, dt=dt, seed=seed, speed=speed, noise=noise,
                                progress=tick)
    write_trial(trial, path, force=force)
    click.echo(f"wrote {out}: {model.name} {spec.name}, {len(trial)} samples, "
               f"{trial.duration:g} s at dt {dt:g} s, seed {seed}{', with sensor noise' if noise else ''}")
    lost = sensor_meta_lost(trial, path)
    if lost:
        click.echo(f"note: a CSV file cannot state the trial's sensor positions; give them to identify and validate "
                   f"as --antenna {lost.get('x_D', 0):g},{lost.get('y_D', 0):g} --log-offset {lost.get('y_S', 0):g} "
                   f"(or write .parquet, which keeps them)")


@cli.command("vessels", context_settings=CONTEXT)
def vessels_cmd() -> None:
    """List the packaged vessels with their model family and sources."""
    from shipid.simulate.registry import list_vessels
    for e in list_vessels():
        alias = f" (aliases: {', '.join(e.aliases)})" if e.aliases else ""
        click.echo(f"{e.name}{alias}")
        click.echo(f"    {e.title}")
        click.echo(f"    model: {e.family}")
        for s in e.sources:
            click.echo(f"    source {s}")


@cli.command("demo", context_settings=CONTEXT)
@click.option("--out-dir", type=click.Path(file_okay=False), default=None,
              help="Where to write [default: a fresh folder ./shipid-demo/run-YYYYmmdd-HHMMSS].")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Seed of every simulated record of the demo (the same seed gives the same numbers).")
@click.option("--force", is_flag=True, help="Overwrite existing files in --out-dir.")
def demo_cmd(out_dir: str | None, seed: int, force: bool) -> None:
    """Run shipid on its bundled vessels and print what it did.

    Simulates every packaged vessel on a representative manoeuvre, then runs the
    demo step of each method; every part it leaves out (real data missing, an
    optional package absent) is listed at the end with the reason.

    Its measured run time is in docs/validation/index.md.
    """
    from shipid.demo import SKIPPED, DemoContext, closing_line, demo_steps, format_table

    if out_dir is None:
        base = Path("shipid-demo")
        stamp = _dt.datetime.now().strftime("run-%Y%m%d-%H%M%S")
        target = base / stamp
        i = 1
        while target.exists():
            target = base / f"{stamp}-{i}"
            i += 1
    else:
        target = Path(out_dir)
    target.mkdir(parents=True, exist_ok=True)
    ctx = DemoContext(out_dir=target, force=force, seed=seed, echo=click.echo)
    t0 = time.perf_counter()
    rows = []
    steps = demo_steps()
    for mod, why in SKIPPED.items():
        ctx.skip(f"demo step of {mod}", why)
        click.echo(f"[skipped] {mod}: {why}")
    for step in steps:
        click.echo(f"[{step.name}] {step.description}")
        ts = time.perf_counter()
        got = step.fn(ctx) or []
        for line in format_table(got) if got else []:
            click.echo("    " + line)
        click.echo(f"    ({time.perf_counter() - ts:.1f} s)")
        rows += got
    for what, why in ctx.skipped:
        click.echo(f"[skipped] {what}: {why}")
    if ctx.findings:
        click.echo("[findings] what the results did not determine, and their warnings")
        for line in ctx.findings:
            click.echo("    " + line)
    click.echo(closing_line(ctx, time.perf_counter() - t0, target))
