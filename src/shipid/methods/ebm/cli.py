"""EBM commands (Yoon & Rhee 2003).

* ``shipid identify ebm --trial T1.csv [--trial T2.csv ...] --vessel esso-osaka [--antenna X,Y --log-offset Y]
  [--json] [-o RESULT.json [--force]]``
* ``shipid study ebm-esso-osaka --input standard|optimal-prbs [--seed S] [--json] [-o RESULT.json [--force]]``
* ``shipid design prbs --vessel esso-osaka [--json] [-o RESULT.json [--force]]``
"""

from __future__ import annotations

import click
import numpy as np

from shipid.cli import CONTEXT, design, identify, study
from shipid.cli._common import channels_option, emit, loud, out_options
from shipid.errors import ShipidError


def _config(paper: bool):
    from shipid.methods.ebm.estimator import EbmConfig

    # --paper: the paper's constant-Q Gauss–Markov force model (no rudder-aware noise)
    return EbmConfig(rudder_q_gain=0.0) if paper else EbmConfig()


def _check_vessel(vessel: str) -> str:
    from shipid.vessels import load_vessel

    v = load_vessel(vessel)
    if v.name != "esso-osaka":
        raise ShipidError(f"EBM needs the modified Abkowitz model; vessel {v.name!r} has none (use esso-osaka)")
    return v.name


def _converged_line(res) -> str:
    """``converged: yes`` or ``converged: NO (...)``: the text output never hides non-convergence."""
    d = res.diagnostics
    if d.get("converged", True):
        return f"converged: yes (ridge iterations {d.get('iterations')})"
    return f"converged: NO (ridge iterations {d.get('iterations')}); do not trust these estimates"


def _print_coefficients(res) -> None:
    from shipid.models import abkowitz as ab

    click.echo(_converged_line(res))
    click.echo(f"{'coefficient':<12}{'estimate':>13}{'std':>12}  verdict")
    for name in ab.THETA_X_NAMES + ab.THETA_Y_NAMES + ab.THETA_N_NAMES:
        e = res.estimates[name]
        if e.status == "estimated":
            click.echo(f"{name:<12}{e.value:>13.4e}{e.std:>12.2e}  estimated")
        else:  # never printed as an estimate
            why = e.note.split(": ", 1)[-1]
            click.echo(f"{name:<12}{'-':>13}{'-':>12}  not determined ({why})")
    cs, cd = res.estimates["current_speed"], res.estimates["current_direction"]
    click.echo(f"current: {cs.value:.4f} ± {cs.std:.4f} m/s towards {np.rad2deg(cd.value):.2f} ± "
               f"{np.rad2deg(cd.std):.2f} deg")
    click.echo(f"{'mode':<8}{'kappa':>12}{'R^2':>9}{'Cp':>8}{'p':>4}{'k':>11}")
    for m, d in res.diagnostics["modes"].items():
        click.echo(f"{m:<8}{d['kappa']:>12.4e}{d['R2']:>9.4f}{d['Cp']:>8.3f}{d['p']:>4d}{d['k']:>11.3e}")
    c = res.diagnostics["combined_eq21"]
    click.echo(f"alpha (eq. 20) = {res.diagnostics['alpha']:.4f};  eq. 21: Y'v+Y'r/alpha = "
               f"{c['Yv+Yr/alpha']:.4e},  N'v alpha+N'r = {c['Nv*alpha+Nr']:.4e}")
    a = res.diagnostics.get("approach", {})
    if a:
        click.echo(f"approach (from {a['source']}): U0 {a['U0']:.4f} m/s, n0 {a['n0']:.4f} 1/s, c0 {a['c0']:.4f} m/s")
    # the warnings (not-determined coefficients among them) follow on stderr, one line each (cli._common.loud)


@identify.command("ebm", context_settings=CONTEXT)
@click.option("--trial", "trials", multiple=True, required=True, type=click.Path(dir_okay=False),
              help="Trial file (CSV or Parquet) with x, y, x_dot, y_dot, psi, U, delta, n; repeatable.")
@channels_option
@click.option("--vessel", default="esso-osaka", show_default=True, help="Packaged vessel.")
@out_options(json_help="Print the Result as JSON on stdout.")
@click.option("--paper", is_flag=True, help="Constant-Q force model exactly as in the paper (no rudder-aware noise).")
@click.option("--yaw-variant", is_flag=True, help="Yaw rudder regressors of eq. 22.")
@click.option("--figures", is_flag=True,
              help="Also store a coarse D-optimal input map (Fig. 7; ~12 simulations) for `shipid report`.")
@click.option("--antenna", default=None, metavar="X,Y",
              help="DGPS antenna position in body axes [m] for trials that do not state it [default: body origin].")
@click.option("--log-offset", "log_offset", default=None, type=float, metavar="Y",
              help="Speed-log athwartship position [m] for trials that do not state it [default: 0].")
def identify_ebm(trials, channels, vessel, as_json, out, force, paper, yaw_variant, figures, antenna, log_offset):
    """Estimation-Before-Modelling (Yoon & Rhee 2003): EKF + MBF smoother, then ridge regression."""
    from dataclasses import replace

    from shipid.io.files import read_trial
    from shipid.methods.ebm import estimator as ebm
    from shipid.methods.ebm.series import with_series
    from shipid.progress import progress_bar

    vessel = _check_vessel(vessel)
    data = [read_trial(p, required=list(ebm.REQUIRED), method="ebm", vessel=vessel, channel_map=channels) for p in trials]
    cfg = replace(_config(paper), yaw_rudder_variant=yaw_variant)
    if antenna is not None or log_offset is not None:
        try:
            xa, ya = (float(v) for v in (antenna or "0,0").split(","))
        except ValueError:
            raise ShipidError(f"--antenna needs X,Y in metres, got {antenna!r}") from None
        cfg = replace(cfg, sensors=(xa, ya, float(log_offset or 0.0)))
    with progress_bar(len(data), "EBM step 1 (EKF + smoother)") as advance:
        run = ebm.identify_run(data, vessel, config=cfg, progress=advance)
    res = with_series(run)     # the report series of the result it prints
    if figures:  # opt-in: the coarse Fig. 7 map of this vessel (shipid.methods.ebm.series)
        from shipid.methods.ebm.series import coarse_d_optimal
        res.series.setdefault("contours", {})["d_optimal"] = coarse_d_optimal(vessel)
    loud(res, trials=data)
    emit(res, as_json=as_json, out=out, force=force, text=lambda: _print_coefficients(res))


@study.command("ebm-esso-osaka", context_settings=CONTEXT)
@click.option("--input", "kind", type=click.Choice(["standard", "optimal-prbs"]), default="standard",
              show_default=True, help="Standard manoeuvres (Table 3) or the D-optimal PRBS (Table 5).")
@click.option("--seed", default=0, show_default=True, type=int,
              help="Seed of the simulated trials' random draws.")
@click.option("--scale", default=1.0, show_default=True, type=click.FloatRange(0.1, 10.0),
              help="Scale the trial durations (quick runs < 1).")
@out_options(json_help="Print the Result as JSON on stdout.")
@click.option("--paper", is_flag=True, help="Constant-Q force model exactly as in the paper.")
def study_ebm(kind, seed, scale, as_json, out, force, paper):
    """Reproduce Table 3 / Table 5 of Yoon & Rhee (2003) on simulated ESSO OSAKA trials."""
    from shipid.methods.ebm.study import make_trials, study as run_study
    from shipid.progress import progress_bar

    n = 3 if kind == "standard" else 1
    with progress_bar(n, f"EBM study ({kind})") as advance:
        res = run_study(kind, seed, scale=scale, config=_config(paper), progress=advance)
    loud(res)
    emit(res, as_json=as_json, out=out, force=force, text=lambda: _print_study(res, kind, seed))


def _print_study(res, kind: str, seed: int) -> None:
    d = res.diagnostics
    click.echo(f"EBM study, ESSO OSAKA, input {kind}, seed {seed} ({d['paper_table']})")
    click.echo(_converged_line(res))
    click.echo(f"{'coefficient':<12}{'true':>12}{'estimated':>12}{'std':>11}{'error %':>9}"
               f"{'paper':>12}{'paper err %':>12}")
    for row in d["table"]:
        click.echo(f"{row['coefficient']:<12}{row['true']:>12.3e}{row['estimated']:>12.3e}{row['se']:>11.2e}"
                   f"{100 * row['rel_error']:>9.1f}{row['paper_estimated']:>12.3e}"
                   f"{100 * row['paper_rel_error']:>12.1f}")
    for m, md in d["modes"].items():
        pk, pr, pc = d["paper_table4"][m]
        click.echo(f"{m:<8} kappa {md['kappa']:.4e}  R^2 {md['R2']:.4f}  Cp {md['Cp']:.3f} (p = {md['p']})"
                   f"   [paper Table 4, standard input: kappa {pk:.4e}, R {pr:.4f}, Cp {pc:.4f}]")
    from shipid.models import abkowitz as ab

    for mode, names, tab in (("surge", ab.THETA_X_NAMES, "Table 1"), ("sway", ab.THETA_Y_NAMES, "Table 2")):
        C = np.asarray(d["correlation"][mode])
        click.echo(f"correlation of the {mode} regressors ({tab} analogue)")
        click.echo(" " * 9 + "".join(f"{n:>9}" for n in names))
        for i, n in enumerate(names):
            click.echo(f"{n:<9}" + " " * (9 * i) + "".join(f"{C[i, j]:>9.2f}" for j in range(i, len(names))))
    ce = d["combined_eq21_rel_error"]
    click.echo(f"eq. 21 combined coefficients (alpha = {d['alpha']:.4f}): errors "
               f"{100 * ce['Yv+Yr/alpha']:.2f} % and {100 * ce['Nv*alpha+Nr']:.2f} %")
    click.echo(f"largest error of a linear coefficient: {100 * d['linear_max_rel_error']:.1f} %")
    for tr in d["tracking_rms"]:
        click.echo(f"step 1 {tr['manoeuvre']}: RMS(v_r) {tr['v_r']:.4f} m/s, RMS(r) {np.rad2deg(tr['r']):.2e} deg/s")
    v = d.get("validation", {})
    if v.get("diverged"):
        click.echo(f"validation: simulation with identified coefficients failed ({v.get('error')})")
    elif v:
        click.echo(f"validation (held-out ±10 deg PRBS): RMS psi {np.rad2deg(v['psi']):.3f} deg, "
                   f"RMS r {np.rad2deg(v['r']):.2e} deg/s, max position error {v['max_position_error_m']:.1f} m")
    cs = res.estimates["current_speed"]
    click.echo(f"current: {cs.value:.4f} m/s (true {np.hypot(*d['current_true']):.4f})")


def _values(text: str) -> list[float]:
    """``"5,10,35"`` or ``"15:200:5"`` (start, stop inclusive, step) as a list of floats."""
    out: list[float] = []
    for part in (p.strip() for p in text.split(",")):
        if not part:
            continue
        if ":" in part:
            a, b, d = (float(x) for x in part.split(":"))
            if d <= 0 or b < a:
                raise ValueError(part)
            n = int(np.floor((b - a) / d + 1e-9))
            out += [float(np.round(a + k * d, 10)) for k in range(n + 1)]
        else:
            out.append(float(part))
    return out


@design.command("prbs", context_settings=CONTEXT)
@click.option("--vessel", default="esso-osaka", show_default=True,
              help="Packaged vessel whose manoeuvring model the PRBS is designed for (shipid vessels).")
@click.option("--amplitudes", default="5:35:10", show_default=True,
              help="deg: comma-separated values or START:STOP:STEP (stop included).")
@click.option("--periods", default="15:200:5", show_default=True,
              help="s: comma-separated values or START:STOP:STEP (stop included).")
@click.option("--duration", default=1200.0, show_default=True, type=click.FloatRange(100, 20000),
              help="Length of each simulated PRBS trial (s).")
@click.option("--seeds", default=3, show_default=True, type=click.IntRange(1, 50),
              help="PRBS realisations averaged per grid point (with 2 or more, the comparison with the "
                   "paper's optimum carries a standard error).")
@click.option("--currents", default="", help="Also sweep the current speed (knots, comma-separated) at the optimum (Fig. 8).")
@click.option("--dt", default=1.0, show_default=True, type=click.FloatRange(0.05, 5.0),
              help="Simulation / sampling step of each PRBS run [s].")
@out_options(json_help="Print the map as a shipid Result (JSON) on stdout.", metavar="RESULT.json",
             out_help="Write the map as a shipid Result for `shipid report` (Fig. 7), atomically; an existing "
                      "file needs --force.")
def design_prbs(vessel, amplitudes, periods, duration, seeds, currents, dt, as_json, out, force):
    """D-optimal PRBS rudder input: log10 |W'W| over amplitude x period (Fig. 7).

    The optimum is the best point of the stated grid (default 4 amplitudes x 38
    periods, 5 s apart, x 3 PRBS seeds: 456 noise-free 1200-s simulations), and the
    output says whether the paper's optimum (35 deg, 105 s) agrees with it within 2
    standard errors of the PRBS-realisation spread. A quick look: --periods 15,60,105,200.
    """
    from shipid.methods.ebm.design import current_sweep, design_result, prbs_grid
    from shipid.progress import progress_bar

    vessel = _check_vessel(vessel)
    try:
        A, T = _values(amplitudes), _values(periods)
        C = [float(a) for a in currents.split(",") if a.strip()]
    except ValueError:
        raise ShipidError("amplitudes and periods must be comma-separated numbers or START:STOP:STEP, "
                          "currents comma-separated numbers") from None
    if not A or not T or min(A) <= 0 or min(T) <= 0 or max(A) > 35:
        raise ShipidError("need amplitudes in (0, 35] deg and positive periods")
    with progress_bar(len(A) * len(T), "D-optimality grid") as advance:
        g = prbs_grid(A, T, duration=duration, seeds=tuple(range(seeds)), dt=dt, vessel=vessel, progress=advance)
    a, per, val = g.optimum("sway")
    sweep = current_sweep(a, per, C, duration=duration, seeds=tuple(range(seeds)), dt=dt, vessel=vessel) if C else None
    cmd = (f"shipid design prbs --vessel {vessel} --amplitudes {','.join(f'{x:g}' for x in A)} "
           f"--periods {','.join(f'{x:g}' for x in T)} --duration {duration:g} --seeds {seeds} --dt {dt:g}"
           + (f" --currents {','.join(f'{x:g}' for x in C)}" if C else ""))
    res = design_result(g, command=cmd, sweep=sweep)
    loud(res)
    if out is not None:
        path = res.write_json(out, force=force)
        click.echo(f"wrote {path} (shipid report {path} --out report.html)", err=as_json)
    if as_json:
        click.echo(res.to_json())
        return
    click.echo("log10 |W'W| of the sway (= yaw) regressors; rows amplitude (deg), columns period (s)")
    click.echo(" " * 8 + "".join(f"{p:>9g}" for p in g.periods))
    for i, amp in enumerate(g.amplitudes):
        click.echo(f"{amp:>8g}" + "".join(f"{v:>9.2f}" for v in g.sway[i]))
    click.echo(f"optimum: amplitude {a:g} deg, period {per:g} s (log10 |W'W| = {val:.2f})")
    click.echo(f"paper (Fig. 7): {res.diagnostics['paper_fig7']['text']}")
    if sweep is not None:
        cs = sweep
        click.echo("current (kn): " + ", ".join(f"{s:g}: {v:.2f}" for s, v in zip(cs["speeds_knot"], cs["sway"])))
