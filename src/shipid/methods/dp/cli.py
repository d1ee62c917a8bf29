"""DP identification commands (Fossen, Sagatun & Sørensen 1996).

``shipid identify dp --surge S1.csv S2.csv --sway-yaw Y1.csv Y2.csv --azimuth A1.csv A2.csv [--json] [-o R.json]``
``shipid study dp-supply [--seed S] [--json] [-o R.json]`` and
``shipid study dp-coverage --runs N [--seed S] [--workers W | --dask-local N | --scheduler ADDR] [--json] [-o R.json]``.
"""

from __future__ import annotations

import json
import time
from dataclasses import replace
from pathlib import Path

import click
import numpy as np

from shipid.cli import CONTEXT, identify, study
from shipid.cli._common import ManyValues, channels_option, emit, loud, loud_lines, out_options, refuse_existing
from shipid.cli.campaign_cmds import campaign_options, echo_campaign_summary, failure_lines
from shipid.io.files import read_trial
from shipid.errors import ShipidError
from shipid.methods.dp.coverage import by_scale, summarise, worst_regime
from shipid.methods.dp.estimator import DPOptions, fit_dp
from shipid.methods.dp.series import with_series
from shipid.methods.dp.plot import plot_parameter_histories
from shipid.methods.dp.trials import TrialNoise, simulate_dp_trials
from shipid.models.dp import THETA_MEANING, THETA_NAMES, dp_vessel
from shipid.vessels import load_vessel

#: Channels a DP trial file must have: t, x, y, psi, p1..p6, alpha6.
REQUIRED = ["x", "y", "psi", "p1", "p2", "p3", "p4", "p5", "p6", "alpha6"]




def _read(paths, kind, channels=None):
    if not paths:
        raise ShipidError(f"no {kind} trials given (--{kind} FILE [FILE ...])")
    return [read_trial(p, required=REQUIRED, manoeuvre=f"dp-{kind}", method="identify dp", channel_map=channels)
            for p in paths]


def _print_table(result, theta_true=None) -> None:
    head = f"{'param':8s} {'meaning':32s} {'estimate':>11s} {'std':>10s}"
    if theta_true is not None:
        head += f" {'true':>11s} {'error %':>8s} {'err/std':>8s}"
    click.echo(head)
    for i, nm in enumerate(THETA_NAMES):
        e = result.estimates[nm]
        line = f"{nm:8s} {THETA_MEANING[nm]:32s} {e.value:11.4e} {e.std:10.2e}"
        if theta_true is not None:
            tt = theta_true[i]
            line += f" {tt:11.4e} {100 * (e.value - tt) / abs(tt):8.2f} {(e.value - tt) / e.std:8.2f}"
        click.echo(line)
    m = result.model
    np.set_printoptions(precision=4, suppress=False, linewidth=110)
    click.echo("A_h'' (eq. 48 form) =\n" + str(np.asarray(m["A_h"])))
    click.echo("K'' diag (eq. 49 form) = " + str(np.asarray(m["K"])))
    click.echo("A'' = M''^-1 A_h M'' (eq. 51 form) =\n" + str(np.asarray(m["A"])))
    click.echo("B'' = M''^-1 T'' K'' (eq. 52 form) =\n" + str(np.asarray(m["B"])))
    d = result.diagnostics
    for name, st in d["stages"].items():
        nis = ", ".join(f"{v:.2f}" for v in st["nis_mean"])
        click.echo(f"{name}: converged={st['converged']} settled={st['settled']} trials={len(st['samples'])} "
                   f"samples={st['samples']} NIS mean=[{nis}] (dof {st['nis_dof'][0]}) {st['seconds']:.1f} s")
        if not st["settled"]:
            click.echo(f"{name}: NOT SETTLED -- the std of its parameters are unreliable")
        if "noise" in st:
            click.echo(f"{name} noise (estimated): " + "; ".join(
                f"{k} = {v['value']:.3g} +- {v['std']:.2g} {v['unit'].split(' ')[0]} ({v['scale_vs_nominal']:.2f} x nominal)"
                for k, v in st["noise"].items()))
    if d.get("covariance"):
        click.echo(f"std: {d['covariance']}")
    # the warnings follow on stderr, one line each (shipid.cli._common.loud)


@identify.command("dp", context_settings=CONTEXT)
@click.option("--surge", cls=ManyValues, type=click.Path(), help="Uncoupled surge trial files (SI1).")
@click.option("--sway-yaw", "sway_yaw", cls=ManyValues, type=click.Path(),
              help="Coupled sway-yaw trial files (SI2).")
@click.option("--azimuth", cls=ManyValues, type=click.Path(), help="Azimuth trial files (SI3).")
@channels_option
@click.option("--vessel", default="supply", show_default=True,
              help="Packaged vessel giving M'', the thruster arms, L and m.")
@click.option("--sigma-pos", type=float, default=None, help="Position noise, m: the starting value (the level is estimated from the data) [default 0.5].")
@click.option("--sigma-psi", type=float, default=None, help="Heading noise, deg: the starting value (estimated from the data) [default 0.25].")
@out_options(force_help="Overwrite existing --out/--plot files.")
@click.option("--plot", type=click.Path(dir_okay=False), default=None,
              help="Write parameter estimates vs time (Fig. 8 style) as PNG.")
def identify_dp_cmd(surge, sway_yaw, azimuth, channels, vessel, sigma_pos, sigma_psi, as_json, out, plot, force):
    """Identify a DP vessel's LF model from decoupled trials (Fossen, Sagatun & Sorensen 1996).

    \b
    Trial files: CSV/Parquet with t [s], x [m], y [m], psi [rad or deg],
    p1..p6 [-] (pitch ratios P/D), alpha6 [rad or deg] (azimuth angle).
    SI1 uses the surge trials, SI2 the sway-yaw trials, SI3 the azimuth trials;
    each processes its trials in parallel (N >= 1) and freezes what the previous found.
    Example: shipid identify dp --surge s1.csv s2.csv --sway-yaw y1.csv y2.csv --azimuth a1.csv a2.csv
    """
    v = dp_vessel(load_vessel(vessel))
    trials = {k: _read(p, k, channels) for k, p in (("surge", surge), ("sway-yaw", sway_yaw), ("azimuth", azimuth))}
    opt = DPOptions()
    if sigma_pos is not None:
        opt = replace(opt, sigma_pos=sigma_pos)
    if sigma_psi is not None:
        opt = replace(opt, sigma_psi=float(np.deg2rad(sigma_psi)))
    refuse_existing(plot, force=force)
    res = with_series(fit_dp(trials["surge"], trials["sway-yaw"], trials["azimuth"], v, opt,
                             provenance={"inputs": [str(p) for p in (*surge, *sway_yaw, *azimuth)],
                                         "command": "shipid identify dp"}))   # the report series of the result it prints
    _emit(res, as_json, out, plot, force, trials=[tr for k in trials for tr in trials[k]])


def _emit(res, as_json, out, plot, force, theta_true=None, trials=()):
    loud(res, trials=trials)
    if plot is not None:
        plot_parameter_histories(res, plot, force=force)
    emit(res, as_json=as_json, out=out, force=force, text=lambda: _print_table(res, theta_true))


@study.command("dp-supply", context_settings=CONTEXT)
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of every random draw.")
@click.option("--duration", type=float, default=1200.0, show_default=True, help="Length of each trial, s.")
@click.option("--trials", "n_trials", type=int, default=2, show_default=True,
              help="Trials per manoeuvre (N of the parallel EKF).")
@out_options(force_help="Overwrite existing --out/--plot files.")
@click.option("--plot", type=click.Path(dir_okay=False), default=None,
              help="Write parameter estimates vs time (Fig. 8 style) as PNG.")
def study_dp_supply(seed, duration, n_trials, as_json, out, plot, force):
    """Simulate the six trials of §4.2 for the supply vessel and identify it.

    Truth: the paper's identified values (eqs. 48-49) with M'' (eq. 30) and T'' (eq. 29);
    disturbances: earth-fixed current 0.3 m/s, a drifting bias, white force noise;
    sensors: position 0.5 m, heading 0.25 deg (1 sigma), 1 Hz. Prints true vs estimated.
    """
    if seed < 0:
        raise ShipidError(f"--seed must be >= 0, got {seed}")
    if duration < 60 or n_trials < 1:
        raise ShipidError("--duration must be >= 60 s and --trials >= 1")
    refuse_existing(plot, force=force)
    v = dp_vessel(load_vessel("supply"))
    t0 = time.perf_counter()
    noise = TrialNoise()
    trials = simulate_dp_trials(v, seed, duration=duration, n_per_kind=n_trials, noise=noise)
    t_sim = time.perf_counter() - t0
    res = with_series(fit_dp(trials["surge"], trials["sway-yaw"], trials["azimuth"], v, theta_true=v.theta,
                             provenance={"seed": seed, "command": f"shipid study dp-supply --seed {seed}",
                                         "noise": noise.as_dict(), "duration_s": duration,
                                         "trials_per_kind": n_trials}))
    res.diagnostics["simulation_seconds"] = t_sim
    _emit(res, as_json, out, plot, force, theta_true=v.theta)


@study.command("dp-coverage", context_settings=CONTEXT)
@click.option("--runs", type=click.IntRange(min=1), default=24, show_default=True, help="Realisations.")
@click.option("--duration", type=float, default=1200.0, show_default=True, help="Length of each trial, s.")
@click.option("--covariance", type=click.Choice(["observed", "ekf"]), default="observed", show_default=True,
              help="observed: noise levels and std from the likelihood (default); ekf: the paper's P_theta.")
@click.option("--regime", type=click.Choice(["scales", "hard"]), default="scales", show_default=True,
              help="scales: noise scales from {0.5, 1, 2}, 1 Hz, --duration; hard: measurement, process-noise, "
                   "bias random-walk and initial-bias scales each log-uniform over 0.3-3, 1-10 Hz, 600-1800 s.")
@out_options(json_help="Print the summary (and every run) as JSON on stdout.")
@campaign_options
def study_dp_coverage(runs, duration, covariance, regime, as_json, out, force, campaign):
    """Coverage of the DP std over realisations with unknown noise levels.

    Each run: the six trials of `study dp-supply` with its own noise seed. --regime scales (1 Hz):
    measurement noise (0.5 m, 0.2 deg) and process noise (white force, wandering bias) each scaled
    by a factor drawn from {0.5, 1, 2}. --regime hard: measurement noise, white force noise, bias
    random walk and initial bias each scaled log-uniformly over 0.3-3, sampling 1-10 Hz, trials of
    600-1800 s. The estimator is told none of it. Prints per theta the coverage of +-1 and +-2 std,
    the RMS of error/std and the worst realisations; every run is kept (--store FILE).
    """
    if duration < 60:
        raise ShipidError("--duration must be >= 60 s")
    res = replace(campaign, progress=not as_json).run(
        "shipid.methods.dp.coverage:run_one", runs,
        kwargs={"duration": duration, "covariance": covariance, "regime": regime},
        name=f"dp-coverage-{regime}-{covariance}", warm_up="shipid.methods.dp.coverage:warm_up",
        chunk_size=1)  # runs of ~30 s: each is stored as soon as it is done
    outs = [r.outputs if r.status == "ok" else None for r in res.records]
    s = summarise(outs)
    s.update({"seed": campaign.seed, "covariance": covariance, "regime": regime, "duration_s": duration,
              "wall_s": res.wall_s, "worst": worst_regime(outs)})
    if regime == "hard":
        s["by_setting"] = {k: by_scale(outs, k) for k in ("s_m", "s_p", "s_b")}
    s["warnings"] = loud_lines(failure_lines(res) + list(s.get("warnings", [])))
    emit({"summary": s, "runs": outs}, as_json=as_json, out=out, force=force, indent=1,
         text=lambda: _coverage_table(res, s, covariance, campaign.seed))


def _coverage_table(res, s: dict, covariance: str, seed: int) -> None:

    echo_campaign_summary(res)
    click.echo(f"dp-coverage: {s['ok']} realisations (seed {seed}), regime {s.get('regime', 'scales')}, covariance {covariance}, "
               f"{s.get('unsettled_runs', 0)} with an unsettled scheme, "
               f"{s.get('seconds_per_identify', float('nan')):.1f} s per identify")
    click.echo(f"  {'param':8s} {'cover 1sd':>9s} {'cover 2sd':>9s} {'2sd all':>8s} {'RMS e/sd':>9s} "
               f"{'mean err%':>9s} {'RMS err%':>9s} {'max|err|%':>9s} {'in band':>11s} {'no std':>6s} "
               f"{'unreliable':>10s}")
    for nm, p in s["parameters"].items():
        band = f"{p['within_band']}/{s['ok']} {p['band_pct']:.0f}%"
        click.echo(f"  {nm:8s} {p['cover_1sd']:9.2f} {p['cover_2sd']:9.2f} {p['cover_2sd_all']:8.2f} "
                   f"{p['rms_error_over_std']:9.2f} {p['mean_rel_error_pct']:9.2f} {p['rms_rel_error_pct']:9.2f} "
                   f"{p['max_abs_rel_error_pct']:9.2f} {band:>11s} {p['no_std']:6d} {p['std_unreliable']:10d}")
    if "pooled" in s:
        p = s["pooled"]
        click.echo(f"  {'pooled':8s} {p['cover_1sd']:9.2f} {p['cover_2sd']:9.2f} {p['cover_2sd_all']:8.2f} "
                   f"{p['rms_error_over_std']:9.2f} {'':9s} {'':9s} {'':9s} {'':11s} {p['no_std']:6d}")
    click.echo("  (coverage and RMS over the estimates with a std; '2sd all' counts those without one as misses;"
               " 'in band': |error| within the band)")
    for key, rows in s.get("by_setting", {}).items():
        click.echo(f"  by {key}: " + "; ".join(f"{r['range'][0]:g}-{r['range'][1]:g}: {r['runs']} runs, "
                                              f"2sd {r['cover_2sd']:.2f}, RMS {r['rms_error_over_std']:.2f}"
                                              for r in rows))
    for w in s.get("worst", []):
        sets = ", ".join(f"{k} {v:.3g}" for k, v in w.items() if k not in ("max_abs_error_over_std", "theta"))
        click.echo(f"  worst: {w['theta']} at {w['max_abs_error_over_std']:.2f} std ({sets})")
