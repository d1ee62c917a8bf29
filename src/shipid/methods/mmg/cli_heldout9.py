"""``shipid study esso-osaka-heldout9 [--folds K] [--train-only] [--no-retime] [--no-input-lags] [--json] [-o R.json]``.

The Esso Osaka 9-run held-out study of :mod:`shipid.methods.mmg.study_oe`: structure by
regression CV and regression vs output-error refinement by CV, both on the 32 training
runs; then, unless ``--train-only``, the 9 test runs are read once and the identified and
published models compared (mean over runs of the 60-s restarted-horizon RMS). By default the
runs are first re-timed onto the position clock (:mod:`shipid.methods.mmg.timing`; offsets
estimated on the training runs), and the rudder angle, propeller rate and wind with them
(:mod:`shipid.methods.mmg.timing_inputs`), reported as one data-repair line; ``--no-input-lags``
re-times the state channels only, ``--no-retime`` leaves all.
"""

from __future__ import annotations

import click

from shipid.cli import CONTEXT, study
from shipid.cli._common import emit, loud_lines, out_options


@study.command("esso-osaka-heldout9", context_settings=CONTEXT)
@click.option("--ninth", type=click.Choice(["issue", "seeded", "bench"]), default="issue", show_default=True,
              help="The ninth test run (shipid.methods.mmg.study_oe.NINTH).")
@click.option("--folds", default=4, show_default=True, type=int, help="CV folds within the 32 training runs.")
@click.option("--train-only", is_flag=True, help="Stop after the CV tables and the choice: no test run is read.")
@click.option("--symmetric-only", is_flag=True,
              help="Leave the port/starboard variants (shipid.methods.mmg.candidates_asym) out of the refinement CV.")
@click.option("--no-surge-terms", is_flag=True,
              help="Leave the surge / slipstream-rudder variants (shipid.methods.mmg.candidates_surge) out of the "
                   "refinement CV.")
@click.option("--retime/--no-retime", default=True, show_default=True,
              help="Re-time heading, velocities and yaw rate onto the position clock by offsets estimated on the "
                   "training runs (shipid.methods.mmg.timing); reported as one data-repair line.")
@click.option("--input-lags/--no-input-lags", default=True, show_default=True,
              help="With --retime, re-time the rudder angle, propeller rate and wind too, by offsets estimated on "
                   "the training runs (shipid.methods.mmg.timing_inputs); in the same data-repair line.")
@out_options(json_help="Print everything as JSON on stdout.")
def heldout9_cmd(ninth, folds, train_only, symmetric_only, no_surge_terms, retime, input_lags, as_json, out,
                 force):
    """Esso Osaka 3 m, 9 held-out runs (both papers' test runs + one seeded random run): choices by CV on
    the other 32 (structure; regression vs output-error refinement; port/starboard terms; surge and
    slipstream-rudder terms), then the held-out table."""
    from shipid.methods.mmg import study_oe as S

    say = (lambda s: None) if as_json else (lambda s: click.echo(s, err=True))
    st = S.heldout9_train(ninth=ninth, folds=folds, asymmetry=not symmetric_only,
                          surge=not no_surge_terms, retime=retime, input_lags=input_lags,
                          progress=say)
    if not as_json:
        click.echo(S.format_heldout9(st))
    if not train_only:
        st["heldout"] = S.heldout9_evaluate(st)
        if not as_json:
            click.echo(S.format_heldout9_test(st))
    lines = list(st["result"].get("diagnostics", {}).get("warnings", []))
    if st.get("retime"):
        lg = st["retime"]
        if any(lg.get(k, 0.0) for k in ("delta", "n", "wind")):
            lines.append(f"data repaired: heading, body velocities and yaw rate (advanced by {lg['psi']:.2f} s, "
                         f"{lg['uv']:.2f} s, {lg['r']:.2f} s) and rudder angle, propeller rate and wind (advanced by "
                         f"{lg['delta']:.2f} s, {lg['n']:.2f} s, {lg['wind']:.2f} s) of every run re-timed onto the "
                         f"position clock (estimated on the {lg['runs']} training runs)")
        else:
            lines.append(f"data repaired: heading, body velocities and yaw rate of every run re-timed onto the "
                         f"position clock (advanced by {lg['psi']:.2f} s, {lg['uv']:.2f} s, {lg['r']:.2f} s; "
                         f"estimated on the {lg['runs']} training runs)")
        for name in (st.get("retime_inputs") or {}).get("not_determined", []):
            lines.append(f"{name} offset on the end of the search grid: not determined within it (used as found)")
    warns = loud_lines(lines)
    if warns:
        st["warnings"] = warns
    emit(st, as_json=as_json, out=out, force=force, indent=1)
