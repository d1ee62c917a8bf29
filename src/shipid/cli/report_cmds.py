"""``shipid report RESULT.json --out report.html``: the HTML report of a result."""

from __future__ import annotations

import json
from pathlib import Path

import click

import shipid.demo.report_step  # noqa: F401  (registers the "report" step of ``shipid demo``)
from shipid.cli import cli
from shipid.errors import InputError, OutputExistsError


def load_result(path: str | Path):
    """Read a ``Result`` JSON file; any problem is an :class:`InputError` naming the file."""
    from shipid.result import Result

    p = Path(path)
    if not p.exists():
        raise InputError("no such file", file=str(path))
    if p.is_dir():
        raise InputError("is a directory, expected a result JSON file", file=str(path))
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise InputError("not a text file (expected JSON written by shipid --json)", file=str(path)) from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as err:
        raise InputError(f"not valid JSON: {err.msg} at line {err.lineno} column {err.colno}",
                         file=str(path)) from None
    if not isinstance(data, dict) or "method" not in data:
        raise InputError("not a shipid result (no 'method' field)", file=str(path))
    if not isinstance(data.get("estimates", {}), dict):
        raise InputError("'estimates' must be an object of name -> {value, std, unit, ...}", file=str(path))
    try:
        return Result.from_dict(data)
    except (TypeError, ValueError, KeyError) as err:
        raise InputError(f"not a valid shipid result: {' '.join(str(err).split())}", file=str(path)) from None


@cli.command("report")
@click.argument("result_json", metavar="RESULT.json", type=click.Path(dir_okay=False, path_type=str))
@click.option("--out", "-o", "out", required=True, type=click.Path(dir_okay=False, path_type=str),
              help="HTML file to write (self-contained; open it in any browser, no network needed).")
@click.option("--force", is_flag=True, help="Overwrite OUT if it exists.")
@click.option("--truth", "truth", type=click.Path(dir_okay=False, exists=True), default=None,
              help="Monitoring runs: the truth sidecar (*.truth.json) of a simulated stream.")
def report_cmd(result_json: str, out: str, force: bool, truth: str | None = None) -> None:
    """Write the HTML report of a result written with --json.

    The report shows the data used, the estimates with standard errors and 95 %
    confidence intervals, diagnostics and warnings, measured-vs-model overlays,
    residuals with their autocorrelation and the method's own figures.
    A monitoring run (the JSON lines of `shipid monitor mass-cm`) gives its own page:
    m(t), zm_bar(t) with ±2 std bands, the alarms, and the truth with --truth.
    """
    from shipid.report.html import write_report
    from shipid.methods.monitor.report import is_monitor_jsonl, write_monitor_report

    if Path(out).exists() and not force:
        raise OutputExistsError(out)
    if Path(result_json).is_file() and is_monitor_jsonl(result_json):
        path = write_monitor_report(result_json, out, truth_path=truth, force=force)
        click.echo(f"report written to {path} ({path.stat().st_size / 1024:.0f} kB)")
        return
    result = load_result(result_json)
    click.echo(f"shipid: building the {result.method} report from {result_json} ...", err=True)
    path = write_report(result, out, force=force)
    size_kb = path.stat().st_size / 1024
    click.echo(f"report written to {path} ({size_kb:.0f} kB)")
