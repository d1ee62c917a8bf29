"""Real-data commands (issue 6): validate a model on a run, identify MMG models, held-out studies.

* ``shipid validate MODEL.json --trial RUN.csv [--json] [--plot out.png]``
  (``MODEL`` may also be ``published:esso_osaka_3m`` or ``published:kvlcc2_L7``)
* ``shipid identify mmg --trial RUN.csv [--trial ...] [--channels MAP | --format esso]``
  and ``shipid identify realdata --train RUN.csv ...`` (the same pipeline)
* ``shipid study esso-osaka-heldout [--split miyauchi2022|wakita2022] [--json]``
* ``shipid study kvlcc2-zigzag [--json]``
"""

from __future__ import annotations

import json

import click

from shipid.cli import CONTEXT, cli, identify, study
from shipid.errors import ShipidError


def _read_run(path, fmt=None, channels=None):
    from shipid.data.io import read_trial

    return read_trial(path, fmt=fmt, channel_map=channels, trim_empty_rows=True,
                      interpolate_gaps=1.0, method="shipid validate/identify")


@cli.command("validate", context_settings=CONTEXT)
@click.argument("model")
@click.option("--trial", "trial_path", required=True, type=click.Path(dir_okay=False),
              help="Measured run (CSV/Parquet/Esso CSV/KVLCC2 .dat).")
@click.option("--format", "fmt", default=None, help="Trial format (csv, parquet, esso, kvlcc2).")
@click.option("--channels", default=None, help="Column map 'x=COL,u=COL,...' for own column names.")
@click.option("--horizon", default=60.0, show_default=True, help="Length of restarted horizons, s.")
@click.option("--json", "as_json", is_flag=True, help="Print the error table as JSON.")
@click.option("--plot", "plot_path", default=None, type=click.Path(dir_okay=False),
              help="Write a figure of measured vs predicted motion (PNG/PDF/SVG).")
@click.option("--force", is_flag=True, help="Overwrite the plot file.")
def validate_cmd(model, trial_path, fmt, channels, horizon, as_json, plot_path, force):
    """Simulate MODEL open loop on a measured run and report RMS/max errors.

    MODEL is a JSON file written by 'shipid identify mmg --json' (or 'identify
    realdata'), or 'published:esso_osaka_3m' / 'published:kvlcc2_L7' for the published
    MMG sets read from the shared data folder. The model starts from the measured
    initial state and is driven by the measured rudder, propeller revolutions and
    true wind; errors of heading (deg), yaw rate (deg/s), u, v (m/s) and position (m)
    over the first 30 s, 60 s, the whole run and 60-s horizons restarted from the
    measured state.
    """
    from shipid.methods import validate as V

    if horizon <= 0:
        raise ShipidError("--horizon must be positive")
    m = V.load_model(model)
    tr = _read_run(trial_path, fmt, channels)
    v = V.validate(m, tr, horizon=horizon)
    if plot_path:
        V.plot(v, plot_path, force=force)
    if as_json:
        click.echo(json.dumps(v.to_dict(), indent=2))
    else:
        click.echo(V.format_table(v))
        if plot_path:
            click.echo(f"plot written to {plot_path}")
