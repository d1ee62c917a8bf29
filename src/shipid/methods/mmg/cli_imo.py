"""Standard manoeuvres of identified MMG models.

* ``shipid imo MODEL.json [--json] [-o R.json] [--samples N] [--seed S] [--ship-length L]``: the IMO
  MSC.137(76) criteria with Monte Carlo bands (:mod:`shipid.methods.mmg.imo`).
* ``shipid simulate MODEL.json MANOEUVRE --out FILE [--speed U] [--rps N]``: handled by
  :func:`simulate_identified` (called from the generic ``simulate`` command when its
  first argument is a MODEL.json file or ``published:NAME``).
"""

from __future__ import annotations

import json
from pathlib import Path

import click

from shipid.cli import CONTEXT, cli
from shipid.cli._common import emit, loud_lines, out_options, warn
from shipid.errors import InputError, OutputExistsError, ShipidError


def _load(spec: str) -> tuple[dict, object]:
    """The MODEL.json dict (empty for published sets) and its MMG model."""
    from shipid.methods.mmg import validate as V

    model = V.load_model(spec)
    if spec.startswith("published:"):
        return {"model": model.to_dict()}, model
    return json.loads(Path(spec).read_text(encoding="utf-8")), model


def is_model_spec(vessel: str) -> bool:
    """True when ``shipid simulate``'s first argument names an MMG model rather than a packaged vessel."""
    return vessel.lower().endswith(".json") or vessel.startswith("published:")


def simulate_identified(spec: str, manoeuvre: str, out: str, *, duration: float | None, dt: float, seed: int,
                        speed: float | None, rps: float | None, rudder_rate: float | None, noise: bool,
                        force: bool, water_depth: float | None = None) -> None:
    """``shipid simulate MODEL.json MANOEUVRE``: the model in calm water at the resolved test conditions."""
    from shipid.io.files import write_trial
    from shipid.methods.mmg import manoeuvres as MM

    path = Path(out)
    if path.suffix.lower() not in (".csv", ".parquet", ".pq"):
        raise ShipidError(f"{out}: output must end in .csv or .parquet")
    if path.exists() and not force:
        raise OutputExistsError(out)
    spec_m = MM.check_manoeuvre(manoeuvre)      # refused before the model is read
    d, model = _load(spec)
    trial, cond = MM.simulate_model(model, d, manoeuvre, duration=duration, dt=dt, seed=seed, speed=speed, rps=rps,
                                    rudder_rate=rudder_rate, water_depth=water_depth)
    if noise:
        import numpy as np

        from shipid.simulate.noise import default_measurement_model
        trial = default_measurement_model().apply(trial, np.random.default_rng([seed, 1]), missing_ok=True)
    write_trial(trial, path, force=force)
    click.echo(f"wrote {out}: {model.name} {spec_m.name}, {len(trial)} samples, {trial.duration:g} s at dt {dt:g} s; "
               f"approach {cond.speed:.4g} m/s at {cond.rps:.4g} rev/s, rudder rate "
               f"{cond.to_dict()['rudder_rate_deg_s']:.3g} deg/s")
    for n in cond.notes:
        click.echo(f"  {n}")
    for w in cond.warnings:
        warn(w)


@cli.command("imo", context_settings=CONTEXT)
@click.argument("model")
@out_options(json_help="Print the assessment as JSON on stdout.")
@click.option("--samples", default=100, show_default=True, type=int,
              help="Monte Carlo draws from the parameter covariance (0: nominal only).")
@click.option("--seed", default=0, show_default=True, type=int, help="Seed of the draws.")
@click.option("--ship-length", type=float, default=None,
              help="Full-scale length (m) of the overshoot limits' L/V and the steering-gear scale "
                   "[default: the model's L_ship, from its prior; required where it has none].")
@click.option("--speed", type=float, default=None, help="Approach speed, m/s [default: from the training data].")
@click.option("--rps", type=float, default=None, help="Propeller rate, rev/s [default: from the training data].")
@click.option("--rudder-rate", type=float, default=None,
              help="Steering-gear rate, deg/s [default: the SOLAS minimum 2.32 deg/s at the model's scale (Froude)].")
@click.option("--dt", type=float, default=0.1, show_default=True, help="Simulation step, s.")
@click.option("--water-depth", type=float, default=None,
              help="Water depth, m [default: the training runs']; a depth class (h/T) other than the training "
                   "runs' is a warning: the model has no shallow-water terms.")
@click.option("--no-form-term", "no_form_term", is_flag=True,
              help="Draw from the estimation covariance alone, without the model-form term of a "
                   "differential-form model (diagnostics.form_check).")
def imo_cmd(model, as_json, out, force, samples, seed, ship_length, speed, rps, rudder_rate, dt, water_depth,
            no_form_term):
    """IMO MSC.137(76) manoeuvres and criteria of an identified MMG model, with Monte Carlo bands.

    Turning ability (35 deg, both sides: advance <= 4.5 L, tactical diameter <= 5 L),
    initial turning (10 deg rudder: <= 2.5 L travelled by 10 deg heading change),
    10/10 first and second and 20/20 first overshoots, stopping (full astern, track
    reach <= 15 L) where the model has an astern propeller. Each value with the band
    of --samples draws from the identified coefficients' covariance and P(pass). For a model
    identified with step 2's differential form the draws' covariance includes the difference
    from the integral form as one standard deviation of model-form error.
    """
    from shipid.methods.mmg import imo as I

    if not dt > 0:
        raise InputError(f"--dt must be positive, got {dt:g}")
    d, _ = _load(model)
    rep = I.assess(d, samples=samples, seed=seed, ship_length=ship_length, speed=speed, rps=rps,
                   rudder_rate_deg_s=rudder_rate, dt=dt, form_term=not no_form_term, water_depth=water_depth)
    # one line each on stderr, counted for shipid --strict, and in the JSON
    rep["warnings"] = loud_lines(rep["warnings"])
    emit(rep, as_json=as_json, out=out, force=force, indent=1, text=lambda: click.echo(I.format_report(rep)))
