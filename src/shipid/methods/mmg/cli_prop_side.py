"""``shipid study kvlcc2-prop-side``: the yaw-balance terms of :mod:`shipid.methods.mmg.propeller_side`, by the forward angle CV."""

from __future__ import annotations

import click

from shipid.cli import CONTEXT, study
from shipid.cli._common import emit, out_options


@study.command("kvlcc2-prop-side", context_settings=CONTEXT)
@out_options(json_help="Print the folds, the yaw balance and the decision as JSON.")
def kvlcc2_prop_side_cmd(as_json, out, force):
    """KVLCC2 HSVA: neutral rudder angle and propeller side force, trained on smaller and scored on larger angles.

    The forward folds of `study kvlcc2-rudder-angle` (10-15 -> 20-35; 10-20 -> 25-35; 10-25 -> 30-35); each
    term calibrated on the fold's training runs by the training fold score; the mean fold score and its spread
    per candidate, the whole-run heading RMS per run, a Nomoto estimate of each run's neutral rudder angle."""
    from shipid.methods.mmg import propeller_side as PS

    say = (lambda s: None) if as_json else (lambda s: click.echo(f"  {s}", err=True))
    res = PS.cross_validate(progress=say)

    def text():
        click.echo("KVLCC2 forward CV by rudder angle: yaw-balance terms")
        click.echo(PS.format_cv(res))

    emit(res, as_json=as_json, out=out, force=force, indent=1, text=text)
