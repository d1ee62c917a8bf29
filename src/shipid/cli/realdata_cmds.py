"""Real-data commands (issue 6): validate a model on a run, identify MMG models, held-out studies.

* ``shipid validate MODEL.json --trial RUN.csv [--json] [--plot out.png]``
  (``MODEL`` may also be ``published:esso_osaka_3m`` or ``published:kvlcc2_L7``)
* ``shipid identify mmg --trial RUN.csv [--trial ...] [--channels MAP | --format esso]``
  and ``shipid identify realdata --train RUN.csv ...`` (the same pipeline)
* ``shipid study esso-osaka-heldout [--split miyauchi2022|wakita2022|both] [--train-only] [--json]``
* ``shipid study kvlcc2-zigzag [--train-only] [--json]``

The studies print the cross-validation table over the candidate structures (training
runs only) and the chosen one before any test run is read (``--train-only`` stops
there); see :mod:`shipid.studies.realdata_study` for the frozen protocol.
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
@click.option("--rudder-sign", default=1, type=int, show_default=True,
              help="-1 if the log's rudder is positive to port (HSVA KVLCC2); MMG: positive turns to starboard.")
@click.option("--json", "as_json", is_flag=True, help="Print the error table as JSON.")
@click.option("--plot", "plot_path", default=None, type=click.Path(dir_okay=False),
              help="Write a figure of measured vs predicted motion (PNG/PDF/SVG).")
@click.option("--out", "out_path", default=None, type=click.Path(dir_okay=False),
              help="Write the whole-run open-loop prediction beside the measured channels (CSV/Parquet).")
@click.option("--force", is_flag=True, help="Overwrite the plot / --out file.")
def validate_cmd(model, trial_path, fmt, channels, horizon, rudder_sign, as_json, plot_path, out_path, force):
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
    if rudder_sign not in (1, -1):
        raise ShipidError("--rudder-sign must be 1 or -1")
    if out_path and not force:
        from pathlib import Path

        from shipid.errors import OutputExistsError
        if Path(out_path).exists():          # before the simulation, not after
            raise OutputExistsError(out_path)
    m = V.load_model(model)
    tr = _read_run(trial_path, fmt, channels)
    if rudder_sign == -1 and "delta" in tr:
        tr = tr.with_channels(delta=-tr["delta"])
    v = V.validate(m, tr, horizon=horizon)
    if out_path:
        from shipid.methods.predict_export import write_prediction
        _, pt = write_prediction(v, tr, out_path, rudder_sign=rudder_sign, force=force)
        if pt.meta["diverged_from_s"] is not None:
            click.echo(f"warning: the prediction diverged at t = {pt.meta['diverged_from_s']:g} s; "
                       f"{out_path} has empty predicted cells from there", err=True)
    if plot_path:
        V.plot(v, plot_path, force=force)
    if as_json:
        click.echo(json.dumps(v.to_dict(), indent=2))
    else:
        click.echo(V.format_table(v))
        if plot_path:
            click.echo(f"plot written to {plot_path}")
        if out_path:
            click.echo(f"prediction written to {out_path}")


# ----------------------------------------------------------------------------- identify
def _prior(spec: str | None, fmt: str | None):
    from shipid.methods import validate as V
    from shipid.models import mmg

    if spec is None:
        spec = "kvlcc2_hsva" if fmt == "kvlcc2" else "esso_osaka_3m"
    if spec.endswith(".json"):
        return V.load_model(spec)
    return mmg.load_published(spec.replace("published:", ""))


def _print_result(res) -> None:
    click.echo(f"structure {res.model['structure']} / candidate '{res.model.get('structure_candidate')}'"
               f" (fixed constants from {res.model.get('fixed_from')})")
    sel = res.diagnostics.get("structure_selection")
    if sel:
        click.echo(f"chosen by {sel['method']}:")
        for c, row in sel["table"].items():
            click.echo(f"  {c:<40} score {row['score']:.3f}")
    click.echo(f"{'coefficient':<12} {'value':>12} {'std':>10} {'unit':>5}  status")
    for k, e in res.estimates.items():
        click.echo(f"{k:<12} {e.value:12.5g} {e.std:10.3g} {e.unit:>5}  {e.status}")
    for m, d in res.diagnostics.get("ridge", {}).items():
        click.echo(f"mode {m}: R2 {d['R2']:.3f}, k {d['k']:.3g}, kappa {d['kappa']:.3g}, n {d['n']}")


def _identify(paths, fmt, channels, prior, structure, folds, rudder_sign, as_json, output, force):
    from shipid.methods import realdata as R

    if not paths:
        raise ShipidError("no training runs given")
    if rudder_sign not in (1, -1):
        raise ShipidError("--rudder-sign must be 1 or -1")
    trials = []
    for p in paths:
        tr = _read_run(p, fmt, channels)
        if rudder_sign == -1 and "delta" in tr:
            tr = tr.with_channels(delta=-tr["delta"])
            tr.meta["rudder_sign_flipped"] = True
        trials.append(tr)
    pm = _prior(prior, fmt)
    st = None if structure in (None, "auto") else structure
    res = R.identify(trials, pm, structure=st, select=st is None, folds=folds,
                     extra_provenance={"command": "shipid identify", "rudder_sign": rudder_sign})
    if output:
        res.write_json(output, force=force)
    if as_json:
        click.echo(res.to_json())
    else:
        _print_result(res)
        if output:
            click.echo(f"model written to {output}")


_ID_OPTS = [
    click.option("--format", "fmt", default=None, help="Trial format: csv, parquet, esso, kvlcc2."),
    click.option("--channels", default=None,
                 help="Column map for own column names, e.g. 'x=x_position_mid,u=u_velo,psi=hdg[deg]'."),
    click.option("--prior", default=None,
                 help="Structure and fixed constants: esso_osaka_3m (default), kvlcc2_hsva, kvlcc2_L7 or MODEL.json."),
    click.option("--structure", default="auto", show_default=True,
                 help="Free-coefficient set (see shipid.methods.realdata.CANDIDATES) or 'auto' (cross-validated)."),
    click.option("--folds", default=None, type=int, help="CV folds for 'auto' (default: leave one run out)."),
    click.option("--rudder-sign", default=1, type=int, show_default=True,
                 help="-1 if the log's rudder is positive to port (MMG: positive turns to starboard)."),
    click.option("--json", "as_json", is_flag=True, help="Print the Result (MODEL.json) to stdout."),
    click.option("--output", "-o", default=None, type=click.Path(dir_okay=False), help="Write MODEL.json here."),
    click.option("--force", is_flag=True, help="Overwrite --output."),
]


def _with_id_opts(f):
    for opt in reversed(_ID_OPTS):
        f = opt(f)
    return f


@identify.command("mmg", context_settings=CONTEXT)
@click.option("--trial", "trials", multiple=True, required=True, type=click.Path(dir_okay=False),
              help="A training run (repeat for several).")
@_with_id_opts
def identify_mmg(trials, fmt, channels, prior, structure, folds, rudder_sign, as_json, output, force):
    """Identify an MMG model from real runs (EKF + smoother, forces, ridge per mode).

    The structure (which coefficients are free) is chosen by cross-validation over the
    given runs unless --structure names one. The result is a self-describing MODEL.json
    for 'shipid validate'.
    """
    _identify(trials, fmt, channels, prior, structure, folds, rudder_sign, as_json, output, force)


from shipid.cli.dp_cmds import _ManyValues  # noqa: E402  (an option taking several files)


@identify.command("realdata", context_settings=CONTEXT)
@click.option("--train", "train", cls=_ManyValues, required=True, type=click.Path(dir_okay=False),
              help="Training runs: --train A.csv B.csv ...")
@_with_id_opts
def identify_realdata(train, fmt, channels, prior, structure, folds, rudder_sign, as_json, output, force):
    """Same pipeline as 'identify mmg', taking the training runs as --train A.csv B.csv ..."""
    _identify(train, fmt, channels, prior, structure, folds, rudder_sign, as_json, output, force)


# ----------------------------------------------------------------------------- studies
@study.command("esso-osaka-heldout", context_settings=CONTEXT)
@click.option("--split", type=click.Choice(["miyauchi2022", "wakita2022", "both"]), default="both",
              show_default=True, help="Training/test split of the data set's README.")
@click.option("--folds", default=0, show_default=True, type=int,
              help="CV folds within the training runs (0: leave one run out, the frozen scheme).")
@click.option("--train-only", is_flag=True,
              help="Stop after the CV table and the chosen structure: no test run is read.")
@click.option("--json", "as_json", is_flag=True, help="Print everything as JSON.")
def esso_heldout_cmd(split, folds, train_only, as_json):
    """Esso Osaka 3 m: CV table over the candidate structures (training runs only), the chosen one,
    then the held-out error table of the identified model vs the published MMG set."""
    from shipid.studies import realdata_study as S

    say = (lambda s: None) if as_json else (lambda s: click.echo(s, err=True))
    splits = ["miyauchi2022", "wakita2022"] if split == "both" else [split]
    out = {}
    for sp in splits:                      # every selection is made (and printed) before any test run is read
        out[sp] = S.esso_train(sp, folds=folds or None, progress=say)
        if not as_json:
            click.echo(S.format_esso_training(out[sp]))
    if not train_only:
        for sp in splits:
            out[sp]["heldout"] = S.esso_evaluate(out[sp], progress=say)
            if not as_json:
                click.echo(S.format_esso_heldout(out[sp]))
    if as_json:
        click.echo(json.dumps(out, indent=1, allow_nan=True))


@study.command("kvlcc2-zigzag", context_settings=CONTEXT)
@click.option("--folds", default=0, show_default=True, type=int,
              help="CV folds within the training zig-zags (0: leave one out, the frozen scheme).")
@click.option("--train-only", is_flag=True,
              help="Stop after the CV table and the chosen structure: no held-out zig-zag is read.")
@click.option("--json", "as_json", is_flag=True, help="Print everything as JSON.")
def kvlcc2_cmd(folds, train_only, as_json):
    """KVLCC2 HSVA: structure by overshoot CV on ten zig-zags; predict 20/10 (both sides) and 35/5 overshoots."""
    from shipid.studies import realdata_study as S

    say = (lambda s: None) if as_json else (lambda s: click.echo(s, err=True))
    st = S.kvlcc2_train(folds=folds or None, progress=say)
    if not as_json:
        click.echo(S.format_kvlcc2_training(st))
    if not train_only:
        st.update(S.kvlcc2_evaluate(st, progress=say))
        if not as_json:
            click.echo(S.format_kvlcc2_heldout(st))
    if as_json:
        click.echo(json.dumps(st, indent=1, allow_nan=True))
