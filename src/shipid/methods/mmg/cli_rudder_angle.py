"""``shipid study kvlcc2-rudder-angle``: the forward CV by rudder angle of :mod:`shipid.methods.mmg.rudder_angle`."""

from __future__ import annotations

import click

from shipid.cli import CONTEXT, study
from shipid.cli._common import emit, out_options


@study.command("kvlcc2-rudder-angle", context_settings=CONTEXT)
@out_options(json_help="Print the folds and the decision as JSON.")
def kvlcc2_rudder_angle_cmd(as_json, out, force):
    """KVLCC2 HSVA: angle-dependent rudder terms, trained on smaller and scored on larger rudder angles.

    Three forward folds (train 10-15 deg -> score 20-35; 10-20 -> 25-35; 10-25 -> 30-35); each candidate's
    side or stall parameter calibrated on the fold's training runs; score = RMS peak yaw-rate error (%) +
    RMS whole-run heading error (deg) of the open-loop replays. About 6 minutes on 2 cores."""
    from shipid.methods.mmg import rudder_angle as RA

    say = (lambda s: None) if as_json else (lambda s: click.echo(f"  {s}", err=True))
    res = RA.cross_validate(progress=say)

    def text():
        click.echo(f"KVLCC2 forward CV by rudder angle over {len(RA.RUNS)} HSVA zig-zags")
        click.echo(RA.format_cv(res))

    emit(res, as_json=as_json, out=out, force=force, indent=1, text=text)
