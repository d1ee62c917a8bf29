"""``shipid export ...``: identified models in the forms other tools take (:mod:`shipid.export`).

Also the parameter-file branch of ``shipid simulate FILE.toml MANOEUVRE`` (:func:`simulate_params_cmd`).
"""

from __future__ import annotations

import json
from pathlib import Path

import click
import numpy as np

from shipid.cli import CONTEXT, cli
from shipid.cli._common import emit, out_options, warn
from shipid.errors import InputError, OutputExistsError, ShipidError

MODEL_HELP = """\b
MODEL  a MODEL.json of `shipid identify dp | ebm | mmg`, published:NAME (an MMG set:
       esso_osaka_3m, kvlcc2_L7, kvlcc2_hsva), a parameter file of `shipid export params`,
       or a packaged vessel: supply (DP), esso-osaka (Abkowitz)"""


@cli.group("export", context_settings=CONTEXT)
def export() -> None:
    """Export a model: state space, Nomoto K and T, parameter file, shipmmg parameters."""


@export.command("state-space", context_settings=CONTEXT)
@click.argument("model")
@click.option("--speed", type=float, default=None,
              help="Manoeuvring models: straight-run speed to linearise about, m/s [default: the model's approach].")
@click.option("--units", type=click.Choice(["bis", "si"]), default="bis", show_default=True,
              help="DP model: bis system as eqs. 51-52 print it, or SI.")
@click.option("--alpha", "alpha_deg", type=float, default=90.0, show_default=True,
              help="DP model: azimuth angle of thruster 6, deg (eq. 29 is 90).")
@click.option("--kinematics", is_flag=True,
              help="Add the positions: heading and cross-track y (manoeuvring), x, y, psi (DP).")
@out_options(json_help="Print A, B, C, D with names and units as JSON on stdout.")
def state_space_cmd(model, speed, units, alpha_deg, kinematics, as_json, out, force):
    """Linear state space A, B, C, D of MODEL, with named states and inputs.

    DP: the control model of Fossen, Sagatun & Sorensen (1996) eqs. 50-52. MMG and
    EBM (Abkowitz) models: linearised about the trimmed straight run at --speed.

    """
    from shipid.export import state_space

    ss = state_space(model, speed=speed, units=units, alpha=float(np.deg2rad(alpha_deg)), kinematics=kinematics)
    emit(ss.to_dict(), as_json=as_json, out=out, force=force, text=lambda: click.echo(ss.summary()))


state_space_cmd.help += MODEL_HELP


@export.command("nomoto", context_settings=CONTEXT)
@click.argument("model")
@click.option("--speed", type=float, default=None, help="Approach speed, m/s [default: the model's approach].")
@click.option("--from", "about", default="straight-run", show_default=True,
              help="straight-run: K, T, T1, T2, T3 of the linearisation; or a zig-zag (zigzag-10, zigzag-20): "
                   "first-order K, T fitted to the model's simulated zig-zag (Nomoto 1957; ITTC 7.5-04-02-01).")
@click.option("--samples", type=int, default=0, show_default=True,
              help="Monte Carlo draws from the coefficients' covariance for the std (0: delta method).")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the Monte Carlo draws.")
@click.option("--no-form-term", "no_form_term", is_flag=True,
              help="MMG models of step 2's differential form: the estimation covariance alone, without the "
                   "model-form term (as shipid imo --no-form-term).")
@out_options(json_help="Print K, T, T1, T2, T3 with their std as JSON on stdout.")
def nomoto_cmd(model, speed, about, samples, seed, no_form_term, as_json, out, force):
    """Nomoto K, T (first order) and K, T1, T2, T3 (second order) of a manoeuvring MODEL, with std.

    From the sway-yaw rows of the linearisation about the straight run (Nomoto 1957;
    Fossen 1994 eqs. 6.37-6.38), or with --from zigzag-10 the first-order K, T of the
    model's simulated 10/10 zig-zag (what an autopilot sees; for a nearly course-unstable
    ship the straight-run K and T are far longer). Std by the delta method or Monte Carlo
    over the coefficients' covariance; a K or T whose std exceeds it is "not determined".

    """
    from shipid.export import load, nomoto

    if samples < 0 or seed < 0:
        raise InputError("--samples and --seed must be >= 0")
    src = load(model, form_term=not no_form_term)
    res = nomoto(src, speed=speed, samples=samples, seed=seed if samples else None, about=about)
    if res.method == "none" and src.method:
        warn(f"Nomoto of {src.name}: no standard errors ({src.cov_note})")
    nd = [k for k, st in res.status.items() if st == "not determined" and k in ("K", "T")]
    if nd:
        warn(f"Nomoto of {src.name} ({about}): {' and '.join(nd)} not determined (std above the value)")
    emit(res.to_dict(), as_json=as_json, out=out, force=force, text=lambda: click.echo(res.summary()))


nomoto_cmd.help += MODEL_HELP


@export.command("params", context_settings=CONTEXT)
@click.argument("model")
@click.option("-o", "--out", "out", type=click.Path(dir_okay=False), default=None,
              help="Parameter file to write: .toml, or .yaml/.yml (needs PyYAML) [default: TOML on stdout].")
@click.option("--json", "as_json", is_flag=True, help="Print the parameter mapping as JSON on stdout.")
@click.option("--force", is_flag=True, help="Overwrite an existing --out file.")
def params_cmd(model, out, as_json, force):
    """Write MODEL's coefficients as a plain TOML/YAML parameter file with units and sources.

    `shipid simulate FILE MANOEUVRE` reads it back and simulates the same trajectory as
    the model it came from.

    """
    from shipid.export import load
    from shipid.export.params import document, to_toml, write_params

    if out is not None and Path(out).exists() and not force:
        raise OutputExistsError(out)
    src = load(model)
    if out is not None:
        path = write_params(src, out, force=force)
        if not as_json:
            click.echo(f"wrote {path}: {src.family} model {src.name}, {len(src.coef)} coefficients "
                       f"({src.cov_note})")
    if as_json:
        click.echo(json.dumps(document(src), indent=1, allow_nan=True))
    elif out is None:
        click.echo(to_toml(document(src)), nl=False)


params_cmd.help += MODEL_HELP


@export.command("shipmmg", context_settings=CONTEXT)
@click.argument("model")
@out_options(json_help="Print shipmmg's parameters and the differing terms as JSON on stdout.")
def shipmmg_cmd(model, as_json, out, force):
    """An MMG MODEL (structure yasukawa2015) as the parameters of shipmmg, naming the terms it lacks.

    MODEL: a MODEL.json of `shipid identify mmg`, published:kvlcc2_L7, or a parameter file.
    """
    from shipid.export import to_shipmmg

    ex = to_shipmmg(model)
    emit(ex.to_dict(), as_json=as_json, out=out, force=force, text=lambda: click.echo(ex.summary()))


def simulate_params_cmd(vessel: str, manoeuvre: str, out: str, *, duration, dt, seed, speed, rps, rudder_rate,
                        noise, force, water_depth) -> None:
    """``shipid simulate FILE.toml MANOEUVRE``: the model of a parameter file (:func:`shipid.export.simulate_params`)."""
    from shipid.export import simulate_params
    from shipid.io.files import write_trial

    path = Path(out)
    if path.suffix.lower() not in (".csv", ".parquet", ".pq"):
        raise ShipidError(f"{out}: output must end in .csv or .parquet")
    if path.exists() and not force:
        raise OutputExistsError(out)
    if seed < 0:
        raise ShipidError(f"--seed must be >= 0, got {seed}")
    trial, notes, warns = simulate_params(vessel, manoeuvre, duration=duration, dt=dt, seed=seed, speed=speed,
                                          rps=rps, rudder_rate=rudder_rate, water_depth=water_depth)
    if noise:
        from shipid.simulate.noise import default_measurement_model
        trial = default_measurement_model().apply(trial, np.random.default_rng([seed, 1]), missing_ok=True)
    write_trial(trial, path, force=force)
    click.echo(f"wrote {out}: {vessel} {manoeuvre}, {len(trial)} samples, {trial.duration:g} s at dt {dt:g} s, "
               f"seed {seed}{', with sensor noise' if noise else ''}")
    for n in notes:
        click.echo(f"  {n}")
    for w in warns:
        warn(w)
