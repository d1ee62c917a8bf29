"""``shipid check`` and ``shipid convert``: the trial-data front door on the command line.

Both read a trial with :func:`shipid.io.read_trial`, so every problem in the file
is answered with one line naming file, channel and row, and exit status 2.
"""

from __future__ import annotations

import click
import numpy as np

from shipid.cli import cli
from shipid.cli._common import channels_option, emit, out_options
from shipid.io.files import FORMATS, parse_channel_map, read_trial, write_trial


def _read_options(f):
    f = click.option("--skip-bad-sentences", "skip_bad", is_flag=True,
                     help="NMEA logs: skip corrupt sentences (counted; still fails when more than 5 % are bad).")(f)
    f = click.option("--trim-empty", is_flag=True,
                     help="Drop rows with no value at all at the start and end of the file (recorded).")(f)
    f = click.option("--resample", type=float, default=None, metavar="DT",
                     help="Resample linearly onto a uniform grid with step DT seconds.")(f)
    f = click.option("--interpolate-gaps", type=float, default=None, metavar="S",
                     help="Fill missing values and time gaps up to S seconds by linear interpolation.")(f)
    f = click.option("--require", default=None, metavar="NAMES",
                     help="Comma-separated channels that must be present, e.g. 'u,v,r,delta'.")(f)
    f = channels_option(f)
    f = click.option("--format", "fmt", type=click.Choice(FORMATS, case_sensitive=False), default=None,
                     help="File format (default: from the extension).")(f)
    return f


def _read(file, fmt, channels, require, interpolate_gaps, resample, trim_empty, skip_bad=False):
    required = [s.strip() for s in require.split(",") if s.strip()] if require else None
    return read_trial(file, fmt=fmt, channel_map=parse_channel_map(channels), required=required,
                      interpolate_gaps=interpolate_gaps, resample=resample, trim_empty_rows=trim_empty,
                      skip_bad=skip_bad)


@cli.command("check")
@click.argument("file", type=click.Path(dir_okay=False))
@_read_options
@out_options(json_help="Print the summary as JSON.",
             out_help="Write the summary as JSON to FILE (atomically; an existing FILE needs --force).")
def check(file, fmt, channels, require, interpolate_gaps, resample, trim_empty, as_json, out, force, skip_bad):
    """Read and validate a trial FILE; print what it holds (exit 2 with one line if it is bad)."""
    trial = _read(file, fmt, channels, require, interpolate_gaps, resample, trim_empty, skip_bad)
    derived = trial.meta.get("derived") or {}
    summary = {
        "file": file, "format": trial.meta.get("format"), "profile": trial.meta.get("profile"),
        "samples": len(trial), "dt": trial.dt, "t0": float(trial.t[0]), "duration": trial.duration,
        "channels": {name: {"unit": trial.units[name], "unit_in_file": trial.meta["units_in"].get(name),
                            "column": trial.meta["columns"].get(name),
                            "derived": derived.get(name) if trial.meta["columns"].get(name) is None else None,
                            "min": float(np.min(v)), "max": float(np.max(v))}
                     for name, v in trial.channels.items()},
        "repairs": [r["text"] for r in trial.meta.get("repairs", [])],
    }
    emit(summary, as_json=as_json, out=out, force=force, text=lambda: _print_summary(trial, summary))
    return 0


def _print_summary(trial, summary: dict) -> None:
    """The text form of ``shipid check``: one line for the file, one per channel, one per repair."""
    prof = f", profile {summary['profile']}" if summary["profile"] else ""
    click.echo(f"{summary['file']}: {summary['format']}{prof}, {len(trial)} samples, dt {trial.dt:.6g} s, "
               f"t {trial.t[0]:.6g}..{trial.t[-1]:.6g} s ({trial.duration:.6g} s)")
    width = max(len(n) for n in trial.channels)
    for name, c in summary["channels"].items():
        src = _source_text(c)
        click.echo(f"  {name:<{width}}  {c['unit']:<7} {c['min']:>12.6g} .. {c['max']:<12.6g}  {src}")
    for text in summary["repairs"]:
        click.echo(f"  repaired: {text}")


def _source_text(c: dict) -> str:
    """Where a channel came from: ``column [unit]``, or how it was derived (never ``None``)."""
    if c["column"] is not None:
        unit = f" [{c['unit_in_file']}]" if c["unit_in_file"] else ""
        return f"from {c['column']}{unit}"
    if c.get("derived"):
        return f"derived: {' '.join(str(c['derived']).split())}"
    return "derived by the reader"


@cli.command("convert")
@click.argument("src", type=click.Path(dir_okay=False))
@click.argument("dest", type=click.Path(dir_okay=False))
@_read_options
@click.option("--units", "units", default=None, metavar="MAP",
              help="Write channels in these units instead of SI: 'psi=deg,n=rpm'.")
@click.option("--force", is_flag=True, help="Overwrite DEST if it exists.")
def convert(src, dest, fmt, channels, require, interpolate_gaps, resample, trim_empty, units, force, skip_bad):
    """Read and validate SRC, write it to DEST (.csv or .parquet) with standard names."""
    trial = _read(src, fmt, channels, require, interpolate_gaps, resample, trim_empty, skip_bad)
    path = write_trial(trial, dest, units=parse_channel_map(units), force=force)
    click.echo(f"wrote {path} ({len(trial)} samples, {len(trial.channels)} channels)")
    return 0
