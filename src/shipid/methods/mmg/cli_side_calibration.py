"""``shipid study kvlcc2-sides``: the large-angle CV of :mod:`shipid.methods.mmg.side_calibration`."""

from __future__ import annotations

import click

from shipid.cli import CONTEXT, study
from shipid.cli._common import emit, out_options


@study.command("kvlcc2-sides", context_settings=CONTEXT)
@click.option("--base", "bases", multiple=True, default=("linear-hull+rudder",), show_default=True,
              help="Base candidate(s) of the extrapolation study (repeat for several).")
@click.option("--crossflow", "crossflow", multiple=True, type=float, default=(1.0, 0.0), show_default=True,
              help="Rudder cross-flow drag coefficient C_Dc of the normal force (0: the standard method).")
@click.option("--parameter", type=click.Choice(["gamma_R_asymmetry", "rudder_side_gain"]), default="gamma_R_asymmetry",
              show_default=True, help="The asymmetry parameter calibrated.")
@click.option("--every-grid-value", is_flag=True, help="Also score each grid value's model (diagnostic).")
@out_options(json_help="Print the table as JSON.")
def kvlcc2_side_calibration_cmd(bases, crossflow, parameter, every_grid_value, as_json, out, force):
    """KVLCC2 HSVA: port/starboard asymmetry fitted to 10/15 deg zig-zag yaw peaks, scored on 20-30 deg.

    The asymmetry parameter is calibrated on the training zig-zags' open-loop peak yaw
    rates, then the model is scored on the 20-30 deg ones as 'study kvlcc2-large-angle'
    scores."""
    from shipid.methods.mmg import extrapolation as E
    from shipid.methods.mmg import side_calibration as S

    say = (lambda s: None) if as_json else (lambda s: click.echo(f"  calibrated and scored: {s}", err=True))
    table = {}
    for cf in crossflow:
        table.update(S.cross_validate(tuple(bases), particulars={"rudder_crossflow": cf}, parameter=parameter,
                                      grid=S.GRID if parameter == "gamma_R_asymmetry" else S.SIDE_GAIN_GRID,
                                      every_grid_value=every_grid_value, progress=say))
    payload = {"train": list(E.TRAIN), "validate": list(E.VALIDATE), "table": table}

    def text():
        click.echo(f"KVLCC2 side calibration: trained on {len(E.TRAIN)} zig-zags (10, 15 deg), scored on "
                   f"{', '.join(E.VALIDATE)}")
        click.echo(E.format_table(table))
        for k, r in table.items():
            if "calibrated_asymmetry" in r:
                tr = ", ".join(f"{a:g}: {v:.2f}" for a, v in sorted(r["training_peak_score"].items()))
                click.echo(f"  {k}: {parameter} {r['calibrated_asymmetry']:.3g} "
                           f"(training peak-yaw-rate RMS % by value: {tr})")

    emit(payload, as_json=as_json, out=out, force=force, indent=1, text=text)
