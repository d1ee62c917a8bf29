"""``shipid study ebm-coverage``: EBM on perturbed, unknown ships (Yoon & Rhee 2003).

* ``shipid study ebm-coverage --runs N [--seed S] [--workers W ...] [--duration T] [--json] [-o R.json]``
"""

from __future__ import annotations

from dataclasses import replace

import click

from shipid.cli import study
from shipid.cli._common import emit, loud_lines, out_options
from shipid.cli.campaign_cmds import campaign_options, echo_campaign_summary, failure_lines


def _fmt(x, spec):
    width = int(spec.split(".")[0]) if spec.split(".")[0].isdigit() else 0
    return f"{'-':>{width}}" if x is None else format(x, spec)


@study.command("ebm-coverage")
@click.option("--runs", type=click.IntRange(min=1), default=50, show_default=True,
              help="Simulated experiments (one identification each).")
@click.option("--duration", type=click.FloatRange(300.0, 7200.0), default=1200.0, show_default=True,
              help="Length of each run's PRBS 35 deg / 105 s trial (s).")
@out_options(json_help="Print the summary as JSON on stdout.")
@campaign_options(seed_default=100)
def ebm_coverage(runs, duration, as_json, out, force, campaign):
    """Coverage of the EBM std: noise seeds x ships with every Table-3 coefficient scaled by U[0.7, 1.3].

    Per run (shipid.methods.ebm.coverage): a straight-line-stable perturbed ship, a current,
    an unknown noise scale, one D-optimal PRBS trial; then `identify ebm` on the measured
    channels. Prints per coefficient the bias and spread of the relative error and the
    coverage of +-2 std over the runs where it is `estimated`.
    """
    from shipid.methods.ebm.coverage import summarise

    res = replace(campaign, progress=not as_json).run("shipid.methods.ebm.coverage:run_one", runs,
                                                       kwargs={"duration": float(duration)}, name="ebm-coverage")
    outs = [r.outputs if r.status == "ok" else None for r in res.records]
    s = summarise(outs)
    s.update({"seed": campaign.seed, "duration": duration, "failed": res.n_failed})
    s["warnings"] = loud_lines(failure_lines(res) + list(s.get("warnings", [])))
    emit(s, as_json=as_json, out=out, force=force, text=lambda: _table(res, s, duration, campaign.seed))


def _table(res, s: dict, duration: float, seed: int) -> None:
    from shipid.methods.ebm.coverage import LINEAR

    echo_campaign_summary(res)
    click.echo(f"EBM coverage study: {s['runs']} runs, seed {seed}, PRBS 35 deg / 105 s, {duration:g} s")
    click.echo(f"{'coefficient':<12}{'estimated':>10}{'bias %':>9}{'spread %':>10}{'mean|z|':>9}{'cover 2sd':>10}"
               f"{'wrong sign':>11}")
    for nm, t in s["table"].items():
        b = None if t["bias_rel"] is None else 100 * t["bias_rel"]
        sp = None if t["spread_rel"] is None else 100 * t["spread_rel"]
        click.echo(f"{nm:<12}{t['estimated']:>6d}/{t['runs']:<3d}{_fmt(b, '9.2f')}{_fmt(sp, '10.2f')}"
                   f"{_fmt(t['mean_abs_z'], '9.2f')}{_fmt(t['coverage_2std'], '10.2f')}{t['wrong_sign']:>11d}")
    click.echo(f"linear coefficients ({', '.join(LINEAR)}): pooled coverage of +-2 std "
               f"{_fmt(s['linear_pooled_coverage'], '.3f')}, lowest {_fmt(s['linear_min_coverage'], '.3f')}")
    click.echo(f"current speed: largest error {_fmt(s['current_speed_error_max'], '.4f')} m/s")
