"""``shipid study mmg-coverage``: simulated coverage of the MMG standard errors.

* ``shipid study mmg-coverage --runs N [--vessel esso-osaka|kvlcc2] [--seed S] [--workers W ...] [--duration T]
  [--json] [-o R.json]``
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


@study.command("mmg-coverage")
@click.option("--runs", type=click.IntRange(min=1), default=50, show_default=True,
              help="Simulated experiments (one identification each).")
@click.option("--vessel", type=click.Choice(["esso-osaka", "kvlcc2"]), default="esso-osaka", show_default=True,
              help="Ship, fixed structure and test programme (shipid.methods.mmg.coverage.VESSELS): the Esso Osaka "
                   "3 m with turns, a zig-zag and a random run, or the KVLCC2 L7 with seven HSVA-like zig-zags "
                   "(needs the shared data folder).")
@click.option("--duration", "seconds", type=click.FloatRange(30.0, 1200.0), default=None,
              help="Length of each simulated manoeuvre (s) [default: the vessel's, 120 Esso / 150 KVLCC2].")
@click.option("--equation", type=click.Choice(["differential", "integral"]), default=None,
              help="Step-2 regression form (FitConfig.equation); default: identify mmg's.")
@click.option("--window", "window_s", type=click.FloatRange(0.1, 120.0), default=None,
              help="Window of the integral form (s); default: FitConfig's.")
@click.option("--simex", type=click.Choice(["on", "off"]), default="on", show_default=True,
              help="Correct the regression for step-1 state errors (shipid.methods.mmg.simex): 'on' always, "
                   "'off' never.")
@click.option("--rudder-rate", type=click.FloatRange(min=0.1), default=None,
              help="Rudder rate of the simulated steering gear, deg/s [default: Esso the IMO 2.32 deg/s Froude-scaled "
                   "to the 3-m model, 24.1; KVLCC2 the HSVA runs' 13]; 'inf' for instantaneous steps.")
@click.option("--refine", type=click.Choice(["none", "output-error"]), default="none", show_default=True,
              help="Refine each fit by output error (shipid.methods.mmg.output_error, the Esso default of "
                   "identify mmg): its horizon-cluster sandwich std are then the ones compared.")
@click.option("--criterion", type=click.Choice(["huber", "least-squares"]), default="huber", show_default=True,
              help="With --refine output-error: the refinement's criterion (OEConfig.robust or LEAST_SQUARES).")
@click.option("--imo-samples", type=click.IntRange(min=0), default=0, show_default=True,
              help="Also check the IMO criteria's bands (shipid imo) against the truth's, with this many Monte "
                   "Carlo draws per run (0: no IMO check).")
@out_options(json_help="Print the summary as JSON on stdout.")
@campaign_options(seed_default=700)
def mmg_coverage(runs, vessel, seconds, equation, window_s, simex, rudder_rate, refine, criterion, imo_samples,
                 as_json, out, force, campaign):
    """Coverage of the MMG std on perturbed ships (shipid.methods.mmg.coverage).

    Per run: coefficients x (1 + 0.15 N(0,1)), noise levels drawn per run, the vessel's manoeuvres, then
    `identify mmg` with its fixed structure (Esso: hull+rudder+thrust; KVLCC2: full/symmetric-gamma_R)
    and no refinement unless --refine says so. Prints per free coefficient the bias and spread of the
    relative error and the coverage of +-2 std.
    """
    from shipid.methods.mmg.coverage import VESSELS, summarise

    ves = VESSELS[vessel]
    seconds = ves.seconds if seconds is None else float(seconds)
    simex = simex == "on"
    kw = {"seconds": seconds, "equation": equation, "window_s": window_s, "simex": simex,
          **({"imo_samples": imo_samples} if imo_samples else {}),
          **({"refine": refine, "criterion": criterion} if refine != "none" else {}),
          **({} if rudder_rate is None else {"rudder_rate": float(rudder_rate)}),
          **({} if vessel == "esso-osaka" else {"vessel": vessel})}
    res = replace(campaign, progress=not as_json).run("shipid.methods.mmg.coverage:run_one", runs, kwargs=kw,
                                                       name="mmg-coverage")
    outs = [r.outputs if r.status == "ok" else None for r in res.records]
    s = summarise(outs)
    s.update({"vessel": vessel, "structure": ves.structure, "seed": campaign.seed, "seconds": seconds,
              "failed": res.n_failed, "equation": equation, "window_s": window_s, "simex": simex,
              "rudder_rate": ves.rudder_rate if rudder_rate is None else float(rudder_rate),
              "imo_samples": imo_samples, "refine": refine,
              **({"criterion": criterion} if refine != "none" else {}), **({"imo_rps": ves.rps} if imo_samples else {})})
    s["warnings"] = loud_lines(failure_lines(res) + s["warnings"])
    emit(s, as_json=as_json, out=out, force=force, text=lambda: _table(res, s))


def _table(res, s: dict) -> None:
    echo_campaign_summary(res)
    click.echo(f"MMG coverage study ({s['vessel']}, {s['structure']}): {s['runs']} runs, seed {s['seed']}, "
               f"{s['seconds']:g} s per manoeuvre")
    wf = any("coverage_2std_with_form" in t for t in s["table"].values())
    ws = any("coverage_2std_with_shift" in t for t in s["table"].values())
    if ws:
        click.echo("refined by output error: 'start' the regression estimate it started from, 'with shift' the "
                   "+-2 std with the refinement's shift counted as one std")
    click.echo(f"{'coefficient':<12}{'estimated':>10}{'bias %':>10}{'spread %':>10}{'cover 2sd':>10}"
               + (f"{'with form':>10}" if wf else "")
               + (f"{'start b %':>10}{'start s %':>10}{'with shift':>11}" if ws else ""))
    for nm, t in s["table"].items():
        b = None if t["bias_rel"] is None else 100 * t["bias_rel"]
        sp = None if t["spread_rel"] is None else 100 * t["spread_rel"]
        extra = ""
        if ws:
            bs, ss = t.get("bias_rel_start"), t.get("spread_rel_start")
            extra = (_fmt(None if bs is None else 100 * bs, '10.1f') + _fmt(None if ss is None else 100 * ss, '10.1f')
                     + _fmt(t.get("coverage_2std_with_shift"), '11.2f'))
        click.echo(f"{nm:<12}{t['estimated']:>6d}/{t['runs']:<3d}{_fmt(b, '10.1f')}{_fmt(sp, '10.1f')}"
                   f"{_fmt(t['coverage_2std'], '10.2f')}" + (_fmt(t.get("coverage_2std_with_form"), '10.2f')
                                                              if wf else "") + extra)
    fc = s.get("form_check")
    if fc:
        top = sorted(fc["by_coefficient"].items(), key=lambda kv: -kv[1])[:6]
        click.echo(f"differential-form check (pipeline.form_check): {fc['flagged']} of {fc['runs']} fits said their "
                   "standard errors were off" + (" (most often: " + ", ".join(f"{k} {v}" for k, v in top) + ")"
                                                  if top else ""))
    if s.get("imo"):
        click.echo(f"IMO criteria at {s['imo_rps']:g} rev/s (each model at its own speed), truth inside the band / "
                   "inside nominal +- 2 std:")
        est = s.get("imo_estimation") or {}
        if est:
            click.echo("(bands with the model-form term; 'est': the same draws without it)")
        click.echo(f"{'criterion':<52}{'n':>4}{'bias':>9}{'rms err':>9}{'mean std':>9}{'band':>6}{'2sd':>6}"
                   + (f"{'est':>6}" if est else ""))
        for nm, t in s["imo"].items():
            e = est.get(nm)
            click.echo(f"{nm + ' [' + t['unit'] + ']':<52}{t['n']:>4d}{t['bias']:>9.3f}{t['rms_error']:>9.3f}"
                       f"{t['mean_std']:>9.3f}{t['coverage_band']:>6.2f}{t['coverage_2std']:>6.2f}"
                       + (f"{e['coverage_band']:>6.2f}" if e else ("" if not est else f"{'-':>6}")))
