"""MMG commands: validate a model on a run, identify MMG models.

The commands parse their options, call the library and print; what decides the model (data profile,
rudder sign, prior, re-timing, checks, selection) is :mod:`shipid.methods.mmg.entry` and
:mod:`shipid.methods.mmg.profile`, the same functions ``shipid.identify("mmg", ...)`` and
``shipid.validate`` run.

* ``shipid validate MODEL.json --trial RUN.csv [--json] [--plot out.png] [--no-retime]``
  (``MODEL`` may also be ``published:esso_osaka_3m`` or ``published:kvlcc2_L7``)
* ``shipid identify mmg --trial RUN.csv [--trial ...] [--channels MAP | --format esso] [--json] [-o MODEL.json]``;
  ``--selection``: the structure by 60-s horizon errors (:data:`shipid.methods.mmg.candidates.CANDIDATES`),
  by a forward CV by rudder angle (:func:`shipid.methods.mmg.rudder_angle.select_manoeuvres`, the
  Yasukawa-2015 default) or by what a turning circle measures (:mod:`shipid.methods.mmg.turning_selection`)
"""

from __future__ import annotations

import json
import math

import click

from shipid.cli import CONTEXT, cli, identify
from shipid.cli._common import CHANNELS_HELP, channels_option, emit, loud, loud_lines, out_options
from shipid.io.files import FORMATS
from shipid.errors import ShipidError


@cli.command("validate", context_settings=CONTEXT)
@click.argument("model")
@click.option("--trial", "trial_path", required=True, type=click.Path(dir_okay=False),
              help="Measured run (CSV/Parquet/Esso CSV/KVLCC2 .dat).")
@click.option("--format", "fmt", default=None, type=click.Choice(FORMATS, case_sensitive=False),
              help="Trial format [default: from the file, else MODEL.json's].")
@channels_option(help=CHANNELS_HELP + " [default: MODEL.json's, if any]")
@click.option("--horizon", default=None, type=float,
              help="Length of restarted horizons, s [default: MODEL.json's, else the method's: 60, mass-cm 10].")
@click.option("--rudder-sign", default=None, type=int,
              help="-1 if the log's rudder is positive to port (MMG: positive turns to starboard) "
                   "[default: MODEL.json's training convention, else from the data profile: -1 for HSVA KVLCC2].")
@click.option("--json", "as_json", is_flag=True,
              help="Print the error table as JSON (every window and quantity, the settings and the warnings).")
@click.option("--plot", "plot_path", default=None, type=click.Path(dir_okay=False),
              help="Write a figure of measured vs predicted motion (PNG/PDF/SVG).")
@click.option("-o", "--out", "out_path", default=None, type=click.Path(dir_okay=False),
              help="Write the whole-run open-loop prediction beside the measured channels (CSV/Parquet).")
@click.option("--force", is_flag=True, help="Overwrite the plot / --out file.")
@click.option("--no-retime", "no_retime", is_flag=True,
              help="MMG: do not re-time the run by the offsets MODEL.json records (estimated on its training runs).")
def validate_cmd(model, trial_path, fmt, channels, horizon, rudder_sign, as_json, plot_path, out_path, force,
                 no_retime):
    """Simulate MODEL open loop on a held-out run and report RMS/max errors.

    Prints the error table of Validation.summary() (windows and restarted horizons by
    quantity, at most 100 columns); --json gives it in full with the settings and the
    warnings, -o the whole-run prediction beside the measured channels.

    MODEL is a result JSON of 'shipid identify mmg | ebm | dp | mass-cm --json' (the
    method is read from its 'method' field), or 'published:esso_osaka_3m' /
    'published:kvlcc2_L7' for the published MMG sets read from the shared data folder.
    EBM: the Abkowitz ship driven by the measured rudder and propeller rate, compared
    in heading, antenna position and velocity and speed log; DP: the LF model driven
    by the measured pitch ratios and azimuth angle, compared in x, y and heading;
    mass-cm: the roll model (33) of the run's loading condition driven by the measured
    a_s, r and rudder, compared in roll rate (and roll angle where recorded), with
    10-s horizons by default. An MMG model starts from the measured
    initial state and is driven by the measured rudder, propeller revolutions and
    true wind; errors of heading (deg), yaw rate (deg/s), u, v (m/s) and position (m)
    over the first 30 s, 60 s, the whole run and 60-s horizons restarted from the
    measured state. The reading settings and the rudder sign convention of the
    model's training runs come from MODEL.json; it warns when the model did not
    converge and when the run's yaw response to its first rudder step contradicts
    the convention.
    """
    if horizon is not None and horizon <= 0:
        raise ShipidError("--horizon must be positive")
    if rudder_sign not in (None, 1, -1):
        raise ShipidError("--rudder-sign must be 1 or -1")
    from shipid.api import validate

    v = validate(model, trial_path, horizon=horizon, fmt=fmt, channels=channels, rudder_sign=rudder_sign,
                 retime=not no_retime, out=out_path, force=force)
    warns = loud_lines(v.settings.pop("warnings", []))
    if plot_path:
        v.plot(plot_path, force=force)
    if as_json:
        d = v.to_dict()
        d["warnings"] = warns
        click.echo(json.dumps(d, indent=2))
    else:
        click.echo(v.summary())
        if plot_path:
            click.echo(f"plot written to {plot_path}")
        if out_path:
            click.echo(f"prediction written to {out_path}")


# ----------------------------------------------------------------------------- identify
def _print_result(res) -> None:
    conv = res.diagnostics.get("converged")
    if conv is not None:
        click.echo("converged: " + ("yes" if conv else "NO (do not trust this model)"))
    click.echo(f"structure {res.model['structure']} / candidate '{res.model.get('structure_candidate')}'"
               f" (fixed constants from {res.model.get('fixed_from')})")
    sel = res.diagnostics.get("structure_selection")
    if sel:
        click.echo(f"chosen by {sel['method']}:")
        qs = [q for q in next(iter(sel["table"].values())) if q.endswith("_rms") or q.endswith("_mean_pct")]
        for c, row in sel["table"].items():
            mark = "  <-" if c == res.model.get("structure_candidate") else ""
            folds = "".join(f" {x:.2f}" for x in row.get("fold_scores", ()))
            folds = f"  folds{folds} (better than H in {row['folds_better_than_H']})" if folds else ""
            click.echo(f"  {c:<68} score {row['score']:8.3f}" + "".join(f"  {q} {row[q]:8.3f}" for q in qs)
                       + folds + mark)
        ref = sel.get("refinement_table") or {}
        if ref:
            click.echo("  then regression and output error of the best and their variants (score, pooled RMS "
                       "psi [deg] / pos [m]):")
            pick = f"{sel['chosen']}/{sel.get('chosen_criterion')}"
            for c, row in ref.items():
                click.echo(f"  {c:<68} score {row['score']:8.3f}  psi_rms {row['psi_rms']:8.3f}  "
                           f"pos_rms {row['pos_rms']:8.3f}" + ("  <-" if c == pick else ""))
        if sel.get("why"):
            click.echo(f"  why: {sel['why']}")
        if sel.get("note"):
            click.echo(f"  note: {sel['note']}")
        rows = [*sel["table"].values(), *ref.values()]
        if any(not math.isfinite(row["score"]) for row in rows):
            click.echo("  (score inf: the candidate's fit failed or its simulation diverged in at least one fold, "
                       "so it cannot be chosen)")
    cal = res.diagnostics.get("calibration")
    if cal:
        click.echo(f"{cal['parameter']} calibrated on all training runs: {cal['value']:.4g} ({cal['criterion']})")
    # the differential form's std with its model-form term (pipeline.form_check), where there is one
    fc = res.diagnostics.get("form_check") or {}
    wf, loose = fc.get("std_with_form"), set(fc.get("not_determined_with_form") or ())
    click.echo(f"{'coefficient':<12} {'value':>12} {'std':>10}" + (f" {'with form':>10}" if wf else "")
               + f" {'unit':>5}  status")
    for k, e in res.estimates.items():
        f = "" if not wf else (f" {wf[k]:10.3g}" if k in wf else f" {'-':>10}")
        # estimated by its SE alone, but not once the model-form term counts: never printed as an estimate
        status = "not determined with form" if k in loose else e.status
        click.echo(f"{k:<12} {e.value:12.5g} {e.std:10.3g}{f} {e.unit:>5}  {status}")
    if wf:
        click.echo("with form: the std with the differential-minus-integral difference of step 2 as one more "
                   "standard deviation (model-form error; shipid imo draws with it)")
    for m, d in res.diagnostics.get("ridge", {}).items():
        click.echo(f"mode {m}: R2 {d['R2']:.3f}, k {d['k']:.3g}, kappa {d['kappa']:.3g}, n {d['n']}")


def _identify(paths, fmt, channels, prior, structure, folds, rudder_sign, as_json, output, force, refine="auto",
              selection="auto", simex="auto", equation="auto", water_depth=None, no_retime=False):
    from shipid.api import identify as api_identify

    if rudder_sign not in (None, 1, -1):
        raise ShipidError("--rudder-sign must be 1 or -1")
    res = api_identify("mmg", list(paths), prior=prior, fmt=fmt, channels=channels, rudder_sign=rudder_sign,
                       structure=structure, folds=folds, selection=selection, refine=refine, simex=simex,
                       equation=equation, water_depth=water_depth, retime=False if no_retime else "auto",
                       command="shipid identify")
    loud(res)

    def text():
        _print_result(res)
        if output:
            click.echo(f"model written to {output}"
                       + ("" if res.diagnostics.get("converged", True) else " (NOT converged: see the warnings)"))

    emit(res, as_json=as_json, out=output, force=force, text=text)


_ID_OPTS = [
    click.option("--format", "fmt", default=None, type=click.Choice(FORMATS, case_sensitive=False),
                 help="Trial format [default: from the file]."),
    channels_option(),
    click.option("--prior", default=None,
                 help="Structure and fixed constants: esso_osaka_3m, kvlcc2_hsva, kvlcc2_L7 or MODEL.json "
                      "[default: from the data profile (Esso CSV: esso_osaka_3m, HSVA .dat: kvlcc2_hsva); "
                      "other files: esso_osaka_3m with a warning]."),
    click.option("--structure", default="auto", show_default=True,
                 help="Free-coefficient set (shipid.methods.mmg.candidates.CANDIDATES) or 'auto' (chosen by "
                      "cross-validation over the given runs; see --selection)."),
    click.option("--folds", default=None, type=int,
                 help="CV folds for 'auto' [default: leave one run out; the output-error stages of the Esso "
                      "selection: 4]."),
    click.option("--selection", default="auto", show_default=True,
                 type=click.Choice(["auto", "horizons", "manoeuvres", "turning", "turning-auto", "rudder-angle"]),
                 help="Criterion and candidate list of --structure auto: 'manoeuvres' (Yasukawa-2015 only: a forward "
                      "CV by rudder angle on the given zig-zags, trained below a cut angle and scored above it by "
                      "open-loop peak yaw rate per side and heading, among the horizon choice, the 'rudder-angle' "
                      "candidate and both with the integral form; the horizon choice below 3 rudder angles; "
                      "shipid.methods.mmg.rudder_angle.select_manoeuvres); 'horizons' (60-s restarted horizon errors; "
                      "for the Esso low-speed prior with enough horizons the staged CV of "
                      "shipid.methods.mmg.staged: regression, output error, port/starboard and surge variants; "
                      "else the regression CV over shipid.methods.mmg.candidates.CANDIDATES); 'turning' "
                      "(open-loop peak yaw rate per side and heading of the left-out zig-zags, Yasukawa-2015 "
                      "structure only, shipid.methods.mmg.turning_selection); 'turning-auto' (the peak criterion "
                      "under a heading limit, shipid.methods.mmg.turning_auto); 'rudder-angle' (Yasukawa-2015 "
                      "only: the candidate with the rudder cross-flow part per side, its side parameter calibrated "
                      "on the given runs, shipid.methods.mmg.rudder_angle); 'auto': manoeuvres for the Yasukawa-2015 "
                      "structure, else horizons."),
    click.option("--refine", default="auto", show_default=True,
                 type=click.Choice(["auto", "none", "output-error"]),
                 help="Refine the regression estimate by output error on the runs' 60-s restarted horizons "
                      "(shipid.methods.mmg.output_error); 'auto': as the staged selection chose, else for the "
                      "Esso low-speed structure with at least 5 horizons per refined coefficient; 'output-error' "
                      "with --structure auto: the staged selection chooses among refined candidates only."),
    click.option("--rudder-sign", default=None, type=int,
                 help="-1 if the log's rudder is positive to port (MMG: positive turns to starboard) "
                      "[default: from the data profile: -1 for HSVA KVLCC2 .dat, else +1]."),
    click.option("--equation", default="auto", show_default=True,
                 type=click.Choice(["auto", "integral", "differential"]),
                 help="Step-2 regression form (shipid.methods.mmg.estimator.FitConfig): 'integral' regresses the "
                      "impulse over Froude-scaled windows (10 s at L = 3 m) and needs no smoothed accelerations; "
                      "'differential' the forces of the smoothed accelerations (Yoon & Rhee eq. 16; biased after "
                      "fast rudder changes); 'auto' the form chosen for the "
                      "prior's structure (EQUATION_BY_STRUCTURE: integral for the Esso low-speed hull, "
                      "differential for KVLCC2)."),
    click.option("--simex", default="auto", show_default=True, type=click.Choice(["auto", "on", "off"]),
                 help="Correct the regression for the errors of the smoothed states by SIMEX "
                      "(shipid.methods.mmg.simex): 'auto' only where a pilot with added noise of twice the "
                      "measured variance moves an "
                      "estimate by a quarter of its SE; 'on' always; 'off' never."),
    click.option("--water-depth", type=float, default=None,
                 help="Water depth of the training runs, m, recorded in MODEL.json's training conditions "
                      "(simulate / imo warn when asked for another depth class) [default: from the data profile "
                      "where it records one (HSVA KVLCC2: 6.0 m), else not recorded]."),
    click.option("--no-retime", "no_retime", is_flag=True,
                 help="Do not re-time the runs onto their position clock [default: re-time Esso CSV runs: the "
                      "offsets of heading, velocities, yaw rate, rudder, propeller and wind are estimated on the "
                      "training runs, recorded in MODEL.json and applied by 'shipid validate'; one data-repair "
                      "line]."),
    out_options(json_help="Print the Result (MODEL.json) on stdout.", metavar="MODEL.json",
                out_help="Write MODEL.json (the Result, for 'shipid validate') to FILE, atomically; an existing "
                         "file needs --force."),
]


def _with_id_opts(f):
    for opt in reversed(_ID_OPTS):
        f = opt(f)
    return f


@identify.command("mmg", context_settings=CONTEXT)
@click.option("--trial", "trials", multiple=True, required=True, type=click.Path(dir_okay=False),
              help="A training run (repeat for several).")
@_with_id_opts
def identify_mmg(trials, fmt, channels, prior, structure, folds, selection, refine, rudder_sign, equation, simex,
                 water_depth, no_retime, as_json, out, force):
    """Identify an MMG model from real runs (EKF + smoother, forces, ridge per mode; see --refine).

    The structure (which coefficients are free) is chosen by cross-validation over the
    given runs unless --structure names one. The result is a self-describing MODEL.json
    for 'shipid validate'.
    """
    _identify(trials, fmt, channels, prior, structure, folds, rudder_sign, as_json, out, force, refine, selection,
              simex, equation, water_depth, no_retime)
