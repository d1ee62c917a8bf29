"""``shipid study kvlcc2-nested``: the nested CV by rudder angle of :mod:`shipid.methods.mmg.turning_nested`."""

from __future__ import annotations

import click

from shipid.cli import CONTEXT, study
from shipid.cli._common import emit, out_options


@study.command("kvlcc2-nested", context_settings=CONTEXT)
@out_options(json_help="Print the folds and summary as JSON.")
def kvlcc2_nested_cmd(as_json, out, force):
    """KVLCC2 HSVA: default, turning and automatic selection, leave-one-rudder-angle-out (nested CV).

    Outer folds leave one rudder-angle group of the frozen study's ten training zig-zags out; each
    procedure selects on the others only and predicts the left-out group (peak yaw rate per side,
    heading RMS, 60-s horizon score). Several minutes on 2 cores."""
    from shipid.methods.mmg import turning_nested as N

    say = (lambda s: None) if as_json else (lambda s: click.echo(f"  {s}", err=True))
    res = N.nested_cv(progress=say)

    def text():
        click.echo(f"KVLCC2 nested CV over {len(res['names'])} HSVA zig-zags, outer folds by rudder angle")
        click.echo(N.format_nested(res))

    emit(res, as_json=as_json, out=out, force=force, indent=1, text=text)
