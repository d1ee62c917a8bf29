"""Commands of Linder et al. (2015): mass and centre of mass from IMU and rudder.

* ``shipid identify mass-cm --nominal N.csv --calibration C.csv --loaded L.csv --known known.toml [--json] [-o R.json]``
* ``shipid study mass-cm-sensitivity --runs N [--seed S] [--workers W | --dask-local N | --scheduler ADDR]
  [--store FILE [--resume]] [--json] [-o R.json]`` (Table 3)
* ``shipid study mass-cm-contour -o fig.png|grid.json [--json]`` (Fig. 4)
* ``shipid analyse crlb mass-cm [--duration S] [--wave-roll DEG] ...`` (Cramér–Rao bounds)

``known.toml`` holds ``U, M, zg_bar, m_c, zc_bar, zs_bar, g`` (bare numbers in SI, or tables
``{ value = ..., unit = "..." }``) and optionally ``z_f`` (known centre of rotation) or
``z_f_prior = [mean, std]``, and ``theta0`` (9 initial values in the order of
:data:`shipid.models.roll_reduced.THETA_NAMES`).
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import click
import numpy as np

from shipid.cli import analyse, identify, study
from shipid.cli._common import channels_option, emit, loud, loud_lines, out_options
from shipid.cli.campaign_cmds import campaign_options, failure_lines
from shipid.errors import InputError, ShipidError
from shipid.methods.masscm.known import KNOWN_KEYS, read_known  # noqa: F401  (read_known re-exported for monitor)
from shipid.methods.masscm.refine_modes import REFINE_MODES

def _fmt(v: float) -> str:
    return "inf" if math.isinf(v) else ("nan" if math.isnan(v) else f"{v:.5g}")


@identify.command("mass-cm")
@click.option("--nominal", "nominal", multiple=True, required=True, type=click.Path(dir_okay=False),
              help="Nominal-condition trial(s) (known M at zg_bar). Repeat for extra datasets.")
@click.option("--calibration", "calibration", multiple=True, required=True, type=click.Path(dir_okay=False),
              help="Calibration trial(s) (known extra m_c at zc_bar).")
@click.option("--loaded", "loaded", multiple=True, required=True, type=click.Path(dir_okay=False),
              help="Loaded trial(s): the unknown load m at zm_bar.")
@click.option("--known", "known_path", required=True, type=click.Path(dir_okay=False),
              help="TOML with U, M, zg_bar, m_c, zc_bar, zs_bar, g [, z_f | z_f_prior, theta0].")
@channels_option
@click.option("--max-iter", type=click.IntRange(min=1), default=50, show_default=True,
              help="Most iterations of Algorithm 1's iterative IV before it stops unconverged (with a warning).")
@click.option("--no-prefilter", is_flag=True, help="Plain iterative IV without the ARMA prefilters (43).")
@click.option("--noise-model", type=click.Choice(["auto", "ar", "ar-structured", "arma", "bj"]), default="auto",
              show_default=True,
              help="Noise model of the prefilter (43): auto (= bj): Box-Jenkins (1 - c q^-2)^k / D(q), k <= 2, with "
                   "(c, k) chosen by the data (innovation likelihood); ar: AR(40); ar-structured: c = 0.99; "
                   "arma: structured ARMA.")
@click.option("--refine", type=click.Choice(REFINE_MODES), default="auto",
              show_default=True,
              help="auto: refine only where the data show sensor noise and a wave structure (the rule of "
                   "methods/masscm/refine.py); pem: always the maximum-likelihood refinement of Algorithm 1's "
                   "estimate on the state-space model of the bound (needs z_f known and sensor noise in the data); "
                   "whittle: the same in the frequency domain (the engine auto uses; cost per iteration independent "
                   "of the record length); none: Algorithm 1 alone. A refinement "
                   "that fails keeps Algorithm 1's estimate, with a warning; the decision is in diagnostics.refine. The report series stay Algorithm 1's.")
@click.option("--cost-map", is_flag=True, help="Also store the Fig. 4 cost map over (m, zm_bar) for `shipid report`.")
@out_options(json_help="Print the result as one JSON object.")
def identify_mass_cm(nominal, calibration, loaded, known_path, channels, max_iter, no_prefilter, noise_model, refine,
                     cost_map, as_json, out, force):
    """Estimate load mass m and its centre zm_bar (Linder et al. 2015, Algorithm 1).

    Channels: t [s], p [rad/s] roll rate, a_s [m/s^2] tangential acceleration at the IMU, r [rad/s]
    yaw rate (SNAME sign), delta [rad] rudder. Without z_f in known.toml m is NOT identifiable
    (only zm_bar and rho = m z_m/(m_c z_c) are); the tool says so.
    """
    from shipid.io.files import read_trial
    from shipid.methods.masscm.estimator import MassCMOptions, REQUIRED, fit_mass_cm
    from shipid.methods.masscm.refine import apply as apply_refine
    from shipid.methods.masscm.series import with_series

    kn = read_known(known_path)
    datasets = []
    for cond, paths in (("nominal", nominal), ("calibration", calibration), ("loaded", loaded)):
        for p in paths:
            datasets.append((cond, read_trial(p, required=["t", *REQUIRED], method="mass-cm",
                                                        channel_map=channels)))
    opts = MassCMOptions(max_iter=max_iter, prefilter=not no_prefilter, noise_model=noise_model, refine=refine)
    fit = fit_mass_cm(datasets, kn["known"], theta0=kn["theta0"], z_f=kn["z_f"], z_f_prior=kn["z_f_prior"],
                      options=opts, init="given" if kn["theta0"] is not None else "linear")
    res = with_series(fit, cost_map=cost_map)     # the report series of the result it prints
    del fit                                       # the prepared datasets: freed before the refinement prepares its own
    res = apply_refine(res, datasets, kn["known"], kn["z_f"], refine)
    res.provenance["known"] = known_path
    loud(res, trials=[tr for _, tr in datasets])
    d = res.to_dict()
    flat = {k: e.value for k, e in res.estimates.items()}
    flat.update({f"{k}_std": e.std for k, e in res.estimates.items()})
    d.update(flat)
    d["converged"] = res.diagnostics["converged"]
    d["iterations"] = res.diagnostics["iterations"]

    def text():
        click.echo(f"mass-cm (Linder et al. 2015): converged={res.diagnostics['converged']} "
                   f"after {res.diagnostics['iterations']} iterations, z_f {res.diagnostics['z_f_mode']}")
        for k, e in res.estimates.items():
            click.echo(f"  {k:8s} = {_fmt(e.value):>11s} ± {_fmt(e.std):<10s} {e.unit:10s} {e.note}")

    emit(d, as_json=as_json, out=out, force=force, text=text)


@study.command("mass-cm-sensitivity")
@click.option("--runs", type=click.IntRange(min=1), default=10_000, show_default=True,
              help="Random initial values drawn (one Algorithm 1 run each).")
@click.option("--z-f", "zf_mode", type=click.Choice(["known", "free"]), default="known", show_default=True,
              help="known: z_f given (identifiable m); free: estimated as in the paper (m then not identifiable).")
@click.option("--init", type=click.Choice(["given", "linear"]), default="given", show_default=True,
              help="given: start from the random Table-3 draw (paper); linear: the equation-error start.")
@click.option("--data-seed", type=int, default=0, show_default=True, help="Seed of the three synthetic datasets.")
@out_options(json_help="Print the Table-3 summary as JSON on stdout.",
             out_help="Write the study as a result JSON (Table 3 spread, for `shipid report`) to FILE "
                      "(atomically; an existing FILE needs --force).")
@campaign_options
def mass_cm_sensitivity(runs, zf_mode, init, data_seed, as_json, out, force, campaign):
    """Table 3: sensitivity of Algorithm 1 to the initial values (noise-free 60 s datasets).

    Runs through the campaign engine: a local process pool by default, ``--dask-local N``
    or ``--scheduler ADDR`` for Dask, ``--store FILE [--resume]`` to keep and continue it.
    """
    from dataclasses import replace

    from shipid.methods.masscm.study import summarise

    seed = campaign.seed
    t0 = time.perf_counter()
    # warm_up compiles the numba kernels once here, then warms the forkserver every worker is forked from
    res = replace(campaign, progress=not as_json).run(
        "shipid.methods.masscm.study:run_one", runs,
        kwargs={"zf_mode": zf_mode, "data_seed": data_seed, "init": init}, name="mass-cm-sensitivity",
        warm_up="shipid.methods.masscm.study:warm_up")
    outs = [r.outputs if r.status == "ok" else None for r in res.records]
    s = summarise(outs, zf_mode=zf_mode, wall_s=time.perf_counter() - t0)
    s.update({"seed": seed, "data_seed": data_seed, "init": init, "workers": res.workers})
    s["warnings"] = loud_lines(failure_lines(res) + ([f"{s['flagged']} of {s['runs']} runs flagged implausible or "
                                                      "not converged (left out of the means)"] if s["flagged"] else []))
    if out:  # Table 3 as a Result (tables/xy "spread") for `shipid report`
        from shipid.methods.masscm.series import spread_result
        spread_result(s, outs, command=f"shipid study mass-cm-sensitivity --runs {runs} --z-f {zf_mode} "
                      f"--init {init} --data-seed {data_seed} --seed {seed}").write_json(out, force=force)
    emit(s, as_json=as_json, out=None, force=force, text=lambda: _sensitivity_table(s, zf_mode, init))


def _sensitivity_table(s: dict, zf_mode: str, init: str) -> None:
    click.echo(f"Table 3 reproduction: {s['runs']} runs, {s['flagged']} flagged implausible, "
               f"z_f {zf_mode}, init {init}, {s['wall_s']:.1f} s")
    click.echo(f"  {'param':8s} {'true':>9s} {'mean':>10s} {'std':>10s} {'paper mean':>11s} {'paper std':>10s}")
    for n, p in s["parameters"].items():
        click.echo(f"  {n:8s} {p['true']:9.4g} {p['mean']:10.5g} {p['std']:10.3g} {p['paper_mean']:11.5g} "
                   f"{p['paper_std']:10.3g}")


@study.command("mass-cm-coverage")
@click.option("--regime", type=click.Choice(["waves", "sensors", "both"]), required=True,
              help="waves: 0.5 deg wave roll, noise-free sensors; sensors: gyro/accelerometer noise and biases, "
                   "no waves; both: the two together.")
@click.option("--runs", type=click.IntRange(min=2), default=100, show_default=True,
              help="Simulated experiments (three datasets and one identification each).")
@click.option("--duration", type=click.FloatRange(min=30.0), default=300.0, show_default=True,
              help="Length of each of the three datasets (s).")
@click.option("--noise-model", type=click.Choice(["ar", "ar-structured", "arma", "auto", "bj"]), default=None,
              help="Noise model of Algorithm 1 (default: the estimator's default).")
@click.option("--refine", type=click.Choice(REFINE_MODES), default="auto",
              show_default=True,
              help="auto (the estimator's default): refine where the rule of methods/masscm/refine.py finds sensor "
                   "noise and a wave structure; pem: always the maximum-likelihood refinement of Algorithm 1's "
                   "estimate (methods/masscm/pem.py); whittle: the same in the frequency domain (whittle.py, auto's "
                   "engine); none: Algorithm 1 alone. A run whose refinement fails keeps "
                   "Algorithm 1's estimate.")
@out_options(json_help="Print the coverage summary as JSON on stdout.")
@campaign_options
def mass_cm_coverage(regime, runs, duration, noise_model, refine, as_json, out, force, campaign):
    """Coverage of Algorithm 1 per noise regime: bias, spread, spread/bound, ±2-std coverage of m, zm_bar, rho.

    Fresh rudder and noise realisations per run (SeedSequence([seed, i])), z_f known; the bound is
    `shipid analyse crlb mass-cm` for the same regime and record length.
    """
    from dataclasses import replace

    from shipid.methods.masscm.estimator import MassCMOptions
    from shipid.methods.masscm.coverage import bound_for, summarise

    t0 = time.perf_counter()
    kw = {"regime": regime, "duration": duration,
          "noise_model": noise_model or MassCMOptions().noise_model, "refine": refine}
    res = replace(campaign, progress=not as_json).run("shipid.methods.masscm.coverage:run_one", runs, kwargs=kw,
                                                     name="mass-cm-coverage",
                                                     warm_up="shipid.methods.masscm.coverage:warm_up")
    outs = [r.outputs if r.status == "ok" else None for r in res.records]
    s = summarise(outs, regime=regime, duration=duration, bound=bound_for(regime, duration))
    if refine != "none":
        s["refined"] = sum(1 for o in outs if o is not None and o.get("refine_decision", "none") != "none")
        s["refine_failed"] = sum(1 for o in outs if o is not None and not o.get("pem_ok", True))
    s.update({"seed": campaign.seed, "workers": res.workers, "noise_model": kw["noise_model"], "refine": refine,
              "wall_s": time.perf_counter() - t0})
    s["warnings"] = loud_lines(failure_lines(res) + list(s.get("warnings", [])))
    emit(s, as_json=as_json, out=out, force=force, text=lambda: _coverage_table(s, regime, duration, campaign.seed))


def _coverage_table(s: dict, regime: str, duration: float, seed: int) -> None:
    click.echo(f"mass-cm coverage, regime {regime}: {s['used']} of {s['runs']} runs ({s['failed']} failed, "
               f"{s['flagged_implausible']} flagged implausible, {s['not_converged']} not converged), "
               f"3 x {duration:g} s, seed {seed}, {s['wall_s']:.1f} s")
    click.echo(f"  {'':7s} {'true':>9s} {'mean':>9s} {'bias/se':>8s} {'spread':>9s} {'mean std':>9s} "
               f"{'bound':>9s} {'spr/bnd':>8s} {'95% CI':>13s} {'cov 2std':>8s}")
    rows = [(k, q) for k, q in s["quantities"].items()]
    rows += [(f"{k}*", q) for k, q in s["quantities_unflagged"].items()]
    for k, q in rows:
        ratio = q["spread_over_bound"]
        ci = q.get("spread_over_bound_ci95")
        ci_s = f"[{ci[0]:.3g}, {ci[1]:.3g}]" if ci else "-"
        click.echo(f"  {k:7s} {q['true']:9.4g} {q['mean']:9.4g} {(q['bias'] / q['bias_se'] if q['bias_se'] else float('nan')):8.2f} {q['spread']:9.3g} "
                   f"{q['mean_std']:9.3g} {q['bound'] or float('nan'):9.3g} "
                   f"{ratio if ratio is not None else float('nan'):8.3g} {ci_s:>13s} {q['coverage_2std']:8.2f}")
    click.echo(f"  (* over the {s['used_unflagged']} converged, unflagged runs)")
    fr = s["flag_rate"]
    click.echo(f"  flagged implausible: {fr['flagged']} of {fr['of']} = {100 * fr['rate']:.1f} % (one-sided 95 % "
               f"upper limit {100 * fr['upper95']:.1f} %); nuisance K_vdot/K_r/K_delta outside their physical "
               f"range (reported, not flagged): {s['nuisance_outside_physical']}")
    if "refined" in s:
        click.echo(f"  refine {s['refine']}: refined in {s['refined']} of {s['runs']} runs, failed (Algorithm 1 kept) "
                   f"in {s['refine_failed']}")


_FIGURE_SUFFIXES = (".png", ".pdf", ".svg")


@study.command("mass-cm-contour")
@click.option("--z-f", "zf_mode", type=click.Choice(["known", "free"]), default="known", show_default=True,
              help="known: z_f given (identifiable m); free: estimated as in the paper (m then not identifiable).")
@click.option("--data-seed", type=int, default=0, show_default=True, help="Seed of the three synthetic datasets.")
@out_options(json_help="Print the cost grid, its minimum and the estimate as JSON on stdout.",
             out_help="Write the result to FILE: the figure for .png/.pdf/.svg, the cost grid as JSON for "
                      "any other name (atomically; an existing FILE needs --force).",
             force_help="Overwrite an existing --out file.")
def mass_cm_contour(zf_mode, data_seed, as_json, out, force):
    """Fig. 4: cost of (40) over (m, zm_bar) with the other parameters at the estimate."""
    from shipid.methods.masscm.contour import contour_figure, cost_grid

    g = cost_grid(data_seed=data_seed, zf_mode=zf_mode)
    i = np.unravel_index(np.argmin(g["cost"]), g["cost"].shape)
    payload = {"study": "mass-cm-contour", "data_seed": data_seed, "z_f": zf_mode,
               "converged": bool(g["converged"]), "theta": g["theta"].tolist(),
               "minimum": {"m": float(g["m"][i[1]]), "zm_bar": float(g["zm_bar"][i[0]]),
                           "cost": float(g["cost"][i])},
               "m": g["m"].tolist(), "zm_bar": g["zm_bar"].tolist(), "cost": g["cost"].tolist()}
    figure = out is not None and Path(out).suffix.lower() in _FIGURE_SUFFIXES
    if figure:
        path = contour_figure(out, data_seed=data_seed, zf_mode=zf_mode, force=force, grid=g)
        click.echo(f"wrote {path}", err=as_json)

    def text():
        mn = payload["minimum"]
        click.echo(f"Fig. 4 cost grid {len(payload['m'])} x {len(payload['zm_bar'])}, z_f {zf_mode}, data seed "
                   f"{data_seed}: minimum at m = {mn['m']:.6g} kg, zm_bar = {mn['zm_bar']:.6g} m "
                   f"(cost {mn['cost']:.6g})")

    emit(payload, as_json=as_json, out=None if figure else out, force=force, text=text)


@analyse.group("crlb")
def crlb_group():
    """Cramér–Rao lower bounds for planned experiments."""


@crlb_group.command("mass-cm")
@click.option("--vessel", default="fishing-vessel", show_default=True,
              help="Packaged vessel giving the ship model and its particulars (shipid vessels).")
@click.option("--duration", type=float, default=300.0, show_default=True, help="Length of each dataset (s).")
@click.option("--fs", type=float, default=50.0, show_default=True, help="Sampling rate (Hz).")
@click.option("--rudder-deg", type=float, default=5.0, show_default=True, help="PRBS rudder amplitude (deg).")
@click.option("--gyro-std", type=float, default=0.002, show_default=True, help="Gyro white noise (rad/s).")
@click.option("--acc-std", type=float, default=0.02, show_default=True, help="Accelerometer white noise (m/s^2).")
@click.option("--wave-roll", type=float, default=0.5, show_default=True, help="Roll std from waves alone (deg).")
@click.option("--wave-period", type=float, default=1.0, show_default=True, help="Wave peak period (s).")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Seed of the simulated datasets (rudder PRBS and noise) the bounds are evaluated on.")
@click.option("--method", type=click.Choice(["kf", "spectrum", "ar"]), default="kf", show_default=True,
              help="kf: Cramér–Rao bound of the data-generating model (ship (11), wave filter, sensor noise, biases; "
                   "exact Kalman-filter likelihood, sway/yaw rows and noise levels as nuisance); spectrum: optimal-IV "
                   "bound of the rudder-driven regressors with the exact equation-error spectrum (Whittle form); ar: "
                   "the same with an AR(40) noise model (cannot represent the wave-roll zeros).")
@out_options(json_help="Print the bounds as JSON on stdout.")
def crlb_mass_cm(vessel, duration, fs, rudder_deg, gyro_std, acc_std, wave_roll, wave_period, seed, method, as_json,
                 out, force):
    """Bounds on zm_bar, rho and m (z_f known) for a ship, excitation, noise and record length."""
    from shipid.methods.masscm.crlb import crlb
    from shipid.models.roll_sim import NoiseSpec
    if duration <= 0 or fs <= 0:
        raise ShipidError("--duration and --fs must be positive")
    if gyro_std < 0 or acc_std < 0 or wave_roll < 0 or (gyro_std == acc_std == wave_roll == 0):
        raise ShipidError("--gyro-std, --acc-std and --wave-roll must be >= 0 and not all 0 (noise-free data: no bound)")
    noise = NoiseSpec(gyro_std=gyro_std, acc_std=acc_std, wave_roll_deg=wave_roll, wave_period=wave_period)
    try:
        b = crlb(vessel, duration=duration, fs=fs, delta_amp=np.deg2rad(rudder_deg), noise=noise, seed=seed,
                 method=method)
    except ValueError as exc:
        raise ShipidError(f"crlb mass-cm: {exc}") from None
    emit(b, as_json=as_json, out=out, force=force,
         text=lambda: _crlb_table(b, vessel, duration, fs, rudder_deg, wave_roll, gyro_std, acc_std, method))


def _crlb_table(b: dict, vessel: str, duration: float, fs: float, rudder_deg: float, wave_roll: float,
                gyro_std: float, acc_std: float, method: str) -> None:
    click.echo(f"Cramér–Rao bounds ({method}), {vessel}, {duration:g} s per dataset at {fs:g} Hz, rudder "
               f"±{rudder_deg:g} deg, waves {wave_roll:g} deg roll, gyro {gyro_std:g} rad/s, acc {acc_std:g} m/s^2 "
               f"(z_f known):")
    for k in ("zm_bar", "rho", "m"):
        e = b["bounds"][k]
        click.echo(f"  {k:7s} true {e['true']:.5g}  std >= {e['std']:.3g}  ({100 * e['rel']:.2f} %)")


@analyse.group("identifiability")
def identifiability_group():
    """Which unknowns the data of an experiment determine (structural identifiability)."""


@identifiability_group.command("mass-cm")
@click.option("--vessel", default="fishing-vessel", show_default=True,
              help="Packaged vessel giving the known particulars and the parameters at which to analyse.")
@click.option("--dt", type=float, default=0.02, show_default=True, help="Sample interval (s) of the discrete model.")
@out_options(json_help="Print the analysis as JSON on stdout.")
def identifiability_mass_cm(vessel, dt, as_json, out, force):
    """Rank of the map from the 9 unknowns to the transfer functions of the three datasets (Linder et al. 2015).

    Prints the rank of the Jacobian of the 15 discrete coefficients (nominal, calibration, loaded) with respect
    to theta = [k, A_x, d, K_r, K_vdot, K_delta, z_f, m, zm_bar], its singular values and the direction it
    cannot see: z_f is not identifiable, zm_bar and rho = m z_m/(m_c z_c) are, and m needs z_f from elsewhere
    (dm/dz_f is printed).
    """
    from shipid.methods.masscm.crlb import true_theta
    from shipid.methods.masscm.identifiability import report
    from shipid.models.roll_reduced import KnownParams

    if not dt > 0:
        raise ShipidError("--dt must be positive")
    try:
        theta, known = true_theta(vessel), KnownParams.from_vessel(vessel)
    except (KeyError, ValueError) as exc:
        raise ShipidError(f"identifiability mass-cm: {vessel}: no mass-cm parameters ({exc})") from None
    r = report(theta, known, T=dt)
    payload = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in r.items()}
    payload["vessel"] = vessel

    def text() -> None:
        click.echo(f"identifiability of mass-cm ({vessel}, dt {dt:g} s): rank {r['rank']} of 9")
        click.echo("  identifiable: " + (", ".join(r["identifiable"]) or "-") +
                   "; not identifiable: " + (", ".join(r["not_identifiable"]) or "-"))
        click.echo(f"  dm/dz_f = {r['dm_dzf']:.4g} kg/m")
        click.echo("  " + r["statement"])

    emit(payload, as_json=as_json, out=out, force=force, text=text)
