"""``shipid monitor mass-cm``: online mass / centre-of-mass monitoring of a loaded-condition stream (Linder et al. 2015).

A thin loop over :class:`shipid.methods.monitor.session.MonitorSession` (sensor faults handled, then
:class:`shipid.methods.monitor.estimator.MassCMMonitor`): read the stream (a file, standard input, a growing
file, or a live NMEA feed on a socket) in chunks, feed them, print each update (one JSON line, or a live
panel on a terminal); ``-o/--out FILE`` also writes each JSON line to FILE as it is produced (the input of
``shipid report``); ``--state FILE`` saves the session after every update and resumes from it.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
import time
from pathlib import Path

import click

from shipid.cli import CONTEXT, cli, study
from shipid.cli._common import channels_option, emit, loud_lines, out_options, refuse_existing, warn
from shipid.cli.campaign_cmds import campaign_options
from shipid.errors import InputError

_CHANNELS = ["t", "p", "a_s", "r", "delta"]


@cli.group("monitor", context_settings=CONTEXT)
def monitor() -> None:
    """Monitor a ship online from a stream of measurements."""


def _csv_chunks(fh, header: list[str], label: str, lines_per_chunk: int, follow: bool, poll: float,
                idle_timeout: float | None, channels: str | None = None):
    """Trials of consecutive complete CSV lines of ``fh`` (after ``header``), parsed by ``read_trial``.

    With ``follow`` the end of the file is not the end of the stream: wait for more lines (as ``tail -f``)
    until ``idle_timeout`` seconds pass without a new line (never, when None).
    """
    from shipid.io.files import read_trial

    buf: list[str] = []
    partial = ""
    last = time.monotonic()
    row0 = len(header)
    with tempfile.TemporaryDirectory(prefix="shipid-monitor-") as tmp:
        tmpf = Path(tmp) / "chunk.csv"

        def parse(lines):
            nonlocal row0
            tmpf.write_text("".join(header + lines), encoding="utf-8")
            try:
                tr = read_trial(tmpf, fmt="csv", required=_CHANNELS, method="mass-cm", channel_map=channels,
                                validate=False)         # faults are the session's to name and survive
            except InputError as err:
                raise InputError(f"{label}: rows {row0 + 1}-{row0 + len(lines)}: {err}") from None
            row0 += len(lines)
            return tr

        while True:
            line = fh.readline()
            if line:
                last = time.monotonic()
                line = partial + line
                partial = ""
                if not line.endswith("\n"):
                    if follow:           # a line still being written
                        partial = line
                        continue
                    line += "\n"
                if line.strip():
                    buf.append(line)
                if len(buf) >= lines_per_chunk:
                    yield parse(buf)
                    buf = []
                continue
            if buf:
                yield parse(buf)
                buf = []
            if not follow or (idle_timeout is not None and time.monotonic() - last > idle_timeout):
                if partial.strip():
                    yield parse([partial + "\n"])
                return
            time.sleep(poll)


def _header(fh, label: str) -> list[str]:
    """Comment lines and the column header of a CSV stream (waits for it to appear when following)."""
    out = []
    while True:
        line = fh.readline()
        if not line:
            raise InputError(f"{label}: empty stream (no CSV header)")
        out.append(line)
        if line.strip() and not line.lstrip().startswith("#"):
            return out


def live_panel(u, nominal_label: str):
    from rich.markup import escape
    from rich.table import Table

    tb = Table(title=f"shipid monitor mass-cm  ({nominal_label})", show_header=True)
    tb.add_column("quantity")
    tb.add_column("estimate", justify="right")
    tb.add_column("± std", justify="right")
    j = u.to_json()

    def fmt(v, p=4):
        return "—" if v is None else f"{v:.{p}g}"
    tb.add_row(escape("t [s]"), fmt(j["t"], 6), f"window {j['window_s']:.0f} s")
    tb.add_row(escape("m [kg]"), fmt(j["m"]), fmt(j["m_std"], 2))
    tb.add_row(escape("zm_bar [m]"), fmt(j["zm_bar"]), fmt(j["zm_bar_std"], 2))
    tb.add_row(escape("rho [-]"), fmt(j["rho"]), fmt(j["rho_std"], 2))
    tb.add_row("converged", "yes" if j["converged"] else "no", "")
    tb.add_row("detector T", fmt(j["statistic"], 3), "ALARM" if j["alarm"] else "")
    tb.add_row(escape("last change at [s]"), fmt(j["change_at"], 6), "")
    return tb


@monitor.command("mass-cm")
@click.option("--nominal", required=True, type=click.Path(dir_okay=False),
              help="Nominal-condition trial (recorded once).")
@click.option("--calibration", required=True, type=click.Path(dir_okay=False),
              help="Calibration trial (known extra m_c at zc_bar, recorded once).")
@click.option("--known", "known_path", required=True, type=click.Path(dir_okay=False),
              help="TOML with U, M, zg_bar, m_c, zc_bar, zs_bar, g and z_f (required here).")
@click.option("--stream", type=str, default=None,
              help="Loaded-condition stream: a trial file, '-' for standard input (CSV), or with --follow a "
                   "CSV file still being written. Or --listen.")
@click.option("--listen", type=str, default=None,
              help="Read a live NMEA 0183 feed instead: udp://HOST:PORT or tcp://HOST:PORT (binds only that "
                   "address). Sentences: XDR (roll rate, acceleration), ROT or XDR (yaw rate), RSA or XDR "
                   "(rudder), VectorNav $VNYMR; tag-block times, else the receive time (shipid.io.nmea_live).")
@click.option("--state", "state_path", type=click.Path(dir_okay=False), default=None,
              help="Save the monitor's state to FILE after every update (atomically) and, when FILE exists, "
                   "resume from it: the start-up is not run again, and -o FILE goes on from the saved update.")
@click.option("--emit", "emit_url", type=str, default=None,
              help="Also send each update as NMEA sentences (XDR estimates, ALR on an alarm) to udp://HOST:PORT.")
@channels_option
@click.option("--window", type=click.FloatRange(min=30), default=300.0, show_default=True,
              help="Sliding window of the loaded-stream moments (s).")
@click.option("--every", type=click.FloatRange(min=1), default=10.0, show_default=True,
              help="Update period in stream time (s); also the block length.")
@click.option("--startup", "init_s", type=click.FloatRange(min=30), default=120.0, show_default=True,
              help="Stream seconds used by the start-up run of Algorithm 1 before the first estimate.")
@click.option("--threshold", type=click.FloatRange(min=0), default=None,
              help="Alarm threshold of the detector's Wald statistic [default: MonitorOptions.threshold].")
@click.option("--noise-model", type=click.Choice(["ar", "auto"]), default=None,
              help="Noise model of the prefilter: 'ar' AR(40), 'auto' the Box-Jenkins model (1 - c q^-2)^k/D(q) "
                   "(shipid.methods.monitor.bj_prefilter) [default: MonitorOptions().masscm.noise_model].")
@click.option("--json", "as_json", is_flag=True,
              help="One JSON line per update on stdout (the default when stdout is not a terminal).")
@click.option("-o", "--out", "out", type=click.Path(dir_okay=False), default=None, metavar="FILE",
              help="Also write each JSON line to FILE as it is produced (an existing FILE needs --force, unless "
                   "--state resumes it).")
@click.option("--force", is_flag=True, help="Overwrite an existing --out file.")
@click.option("--follow", is_flag=True, help="Keep reading a CSV file that is still being written (as tail -f).")
@click.option("--idle-timeout", type=click.FloatRange(min=0), default=None,
              help="With --follow or --listen: stop after this many seconds without new data (with --listen: once "
                   "data have come) [default: never].")
def monitor_mass_cm(nominal, calibration, known_path, stream, channels, listen, state_path, emit_url, window, every,
                    init_s, threshold, noise_model, as_json, out, force, follow, idle_timeout):
    """Estimate the load mass m and its centre zm_bar online, with an alarm when the loading changes.

    Every EVERY seconds of stream time one update: {"t", "m", "m_std", "zm_bar", "zm_bar_std", "rho",
    "rho_std", "converged", "alarm", "change_at", ...} (shipid.methods.monitor.estimator). Channels as for
    `shipid identify mass-cm`: t, p, a_s, r, delta. Sensor faults in the samples that arrive (gaps, NaN,
    repeated or late samples, clock jumps, frozen channels, spikes) are one warning line each and survived
    (shipid.methods.monitor.faults) whether they come from a file, standard input or a live feed; while a
    channel stays bad the update says it cannot estimate. A cell that is not a number is bad input (exit 2).
    Example: shipid simulate fishing-vessel mass-cm-stream --change-at 900 --to 0.7,-0.14 --out s.csv;
    shipid monitor mass-cm --nominal s.nominal.csv --calibration s.calibration.csv --known s.known.toml
    --stream s.csv -o run.jsonl
    """
    from dataclasses import replace

    from shipid.io.files import read_trial
    from shipid.methods.masscm.cli import read_known
    from shipid.methods.masscm.estimator import REQUIRED
    from shipid.methods.monitor.estimator import MassCMMonitor, MonitorOptions
    from shipid.methods.monitor.session import MonitorSession, fingerprint, load_state, save_state

    if out and not (state_path is not None and os.path.exists(state_path)):
        refuse_existing(out, force=force)        # before any work; a resumed run goes on with its FILE
    if (stream is None) == (listen is None):
        raise InputError("give one of --stream FILE|- and --listen udp://HOST:PORT|tcp://HOST:PORT")
    if listen is not None and follow:
        raise InputError("--follow reads a file; it does not go with --listen")
    kn = read_known(known_path)
    if kn["z_f"] is None:
        raise InputError("z_f is required for monitoring (m is not identifiable without it)", file=known_path)
    opts = MonitorOptions(window=window, every=every, init=init_s)
    if threshold is not None:
        opts = replace(opts, threshold=threshold)
    if noise_model is not None:
        opts = replace(opts, masscm=replace(opts.masscm, noise_model=noise_model))
    fp = fingerprint(nominal, calibration, known_path, opts)
    session = None
    if state_path is not None and os.path.exists(state_path):
        session = load_state(state_path, fp)
        click.echo(f"shipid: resumed from {state_path} at t = {session.t_pushed} s "
                   f"({session.n_updates} updates; the start-up is not run again)", err=True)
    if session is None:
        nom = read_trial(nominal, required=["t", *REQUIRED], method="mass-cm", channel_map=channels)
        cal = read_trial(calibration, required=["t", *REQUIRED], method="mass-cm", channel_map=channels)
        mon = MassCMMonitor(nom, cal, kn["known"], kn["z_f"], opts)
        mon.keep_updates = False
        session = MonitorSession(mon, fingerprint=fp)
    T = session.mon.T
    live = None
    out_fh = None
    if out:
        out_fh = open(out, "r+b" if os.path.exists(out) and session.n_updates else "wb")
        out_fh.truncate(session.out_bytes)
        out_fh.seek(session.out_bytes)
    emitter = None
    if emit_url is not None:
        from shipid.io.live import Sender, parse_url
        if parse_url(emit_url)[0] != "udp":
            raise InputError(f"'{emit_url}': --emit sends to udp://HOST:PORT")
        emitter = Sender(emit_url)
    as_json = as_json or not sys.stdout.isatty()
    if not as_json:
        from rich.live import Live
        live = Live(refresh_per_second=4)
        live.start()
    skip_to = session.t_pushed if listen is None else None     # a re-read file: skip what was pushed

    def handle(result):
        ups, warns = result
        for w in warns:
            warn(w)
        for u in ups:
            for w in u.warnings:        # one line each, counted for shipid --strict
                warn(w)
            if u.alarm:
                click.echo(f"shipid: alarm at t = {u.t:g} s: loading changed (change at {u.change_at:g} s, "
                           f"detector T = {u.statistic:.3g} > {session.mon.opt.threshold:g})", err=True)
            j = u.to_json()
            line = json.dumps(j)
            if out_fh is not None:
                out_fh.write((line + "\n").encode("utf-8"))
                out_fh.flush()
            if emitter is not None:
                emitter.send(nmea_estimates(j))
            if live is not None:
                live.update(live_panel(u, Path(nominal).name))
            else:
                click.echo(line)
                sys.stdout.flush()
        if ups and state_path is not None:
            session.out_bytes = out_fh.tell() if out_fh is not None else 0
            save_state(session, state_path)

    def push(t, p, a_s, r, delta):
        if skip_to is not None:
            keep = t > skip_to + 0.5 * T
            t, p, a_s, r, delta = t[keep], p[keep], a_s[keep], r[keep], delta[keep]
        if t.size:
            handle(session.push(t, p, a_s, r, delta))

    try:
        chunk_lines = max(1, int(round(every / T)))
        if listen is not None:
            _listen(listen, push, idle_timeout, every)
        elif stream == "-" or follow:
            fh = sys.stdin if stream == "-" else open(stream, encoding="utf-8", newline="")
            try:
                label = "stdin" if stream == "-" else stream
                hdr = _header(fh, label)
                for tr in _csv_chunks(fh, hdr, label, chunk_lines, follow, 0.2, idle_timeout, channels):
                    push(tr.t, tr["p"], tr["a_s"], tr["r"], tr["delta"])
            finally:
                if fh is not sys.stdin:
                    fh.close()
        else:
            if not os.path.exists(stream):
                raise InputError("no such file", file=stream)
            tr = read_trial(stream, required=["t", *REQUIRED], method="mass-cm", channel_map=channels,
                            validate=False)             # faults are the session's to name and survive
            for a in range(0, len(tr.t), chunk_lines):
                s = slice(a, a + chunk_lines)
                push(tr.t[s], tr["p"][s], tr["a_s"][s], tr["r"][s], tr["delta"][s])
        handle(session.finish())
    finally:
        if live is not None:
            live.stop()
        if out_fh is not None:
            out_fh.close()
        if emitter is not None:
            emitter.close()


def nmea_estimates(j: dict) -> list[str]:
    from shipid.io.nmea_live import estimate_sentences
    return estimate_sentences(j)


def _listen(url: str, push, idle_timeout, every: float) -> None:
    """Read the live feed at ``url`` until ``idle_timeout`` s of silence (or for ever); say what was dropped."""
    from shipid.io.live import Listener
    from shipid.methods.monitor.sources import FeedStats, live_samples

    stats = FeedStats()
    with Listener(url) as lst:
        click.echo(f"shipid: listening on {lst.scheme}://{lst.address[0]}:{lst.address[1]}", err=True)
        try:
            for chunk in live_samples(lst, stats, warn, idle_timeout=idle_timeout, every=every):
                push(*chunk)
        except KeyboardInterrupt:
            pass
        c = lst.counts
        bad = stats.bad_total(c)
        text = (f"{lst.scheme}://{lst.address[0]}:{lst.address[1]}: {c['datagrams']} {'datagrams' if lst.scheme == 'udp' else 'lines'} received, "
                f"{bad} bad and dropped ({stats.bad_lines} unparsable lines, {c['not_text']} not text, "
                f"{c['empty']} empty, {c['oversized']} oversized, {c['flood']} over the rate limit), "
                f"{stats.samples} samples, {stats.incomplete} incomplete, {c['overflow']} lost to a "
                "full queue")
        if bad or c["overflow"]:
            warn(text)
        else:
            click.echo(f"shipid: {text}", err=True)


@study.command("monitor-coverage")
@click.option("--runs", "streams", type=click.IntRange(min=1), default=40, show_default=True,
              help="Fresh streams per case (with a load change, without one).")
@click.option("--noise-scale", "noise_scales", type=click.FloatRange(min=0, min_open=True), multiple=True,
              help="Multiple of the default stream noise (gyro / accelerometer noise and biases, wave roll); "
                   "repeat for several  [default: 1 and 0.1].")
@click.option("--duration", type=click.FloatRange(min=600.0), default=1800.0, show_default=True,
              help="Stream length (s); the change, if any, at half of it.")
@click.option("--settle", type=click.FloatRange(min=0.0), default=300.0, show_default=True,
              help="Coverage counted from this many seconds after the change (after the start without one).")
@click.option("--covariance", type=click.Choice(["sandwich", "white"]), default="sandwich", show_default=True,
              help="The monitor's standard errors: the block sandwich (default) or Algorithm 1's (J^T J)^-1.")
@out_options(json_help="Print the per-case summaries and per-stream coverages as JSON on stdout.")
@campaign_options
def monitor_coverage(streams, noise_scales, duration, settle, covariance, as_json, out, force, campaign):
    """Per-stream coverage of the mass / CM monitor: in each fresh simulated stream, the fraction of updates
    whose ±2-std band holds the true m and zm_bar; the streams with >= 90 % covered, alarm delay, false alarms."""
    from dataclasses import replace

    from shipid.methods.monitor.coverage import run_cases

    res = run_cases(streams, noise_scales or (1.0, 0.1), duration=duration, settle=settle, covariance=covariance,
                    campaign=replace(campaign, progress=not as_json))
    res["warnings"] = loud_lines(res.pop("failures") + res["warnings"])
    emit(res, as_json=as_json, out=out, force=force, text=lambda: _coverage_text(res))


def _coverage_text(res: dict) -> None:
    """The table: per case the fraction of streams with >= 90 % of their updates covered, pooled and worst
    coverage, the std factor the target would need (std x), alarm delays, false alarms, real-time factor."""
    click.echo(f"monitor coverage: {res['streams']} streams per case, {res['duration']:g} s at 50 Hz, covered "
               f"from {res['settle']:g} s after the change, covariance {res['covariance']}, seed {res['seed']}, "
               f"{res['wall_s']:.0f} s")
    click.echo(f"  {'noise':>5s} {'change':>6s} {'>=90% m':>8s} {'zm_bar':>7s} {'both':>6s} {'pooled m':>9s} "
               f"{'zm_bar':>7s} {'worst m':>8s} {'zm_bar':>7s} {'std x':>6s} {'alarm delay':>14s} {'false':>6s} "
               f"{'x real':>7s}")
    for c in res["cases"]:
        s = c["summary"]
        d = (f"{s['detected']}/{s['streams']} {s['delay_mean']:.0f}-{s['delay_max']:.0f}s" if c["change"] and
             s.get("detected") else ("-" if not c["change"] else f"0/{s['streams']}"))
        click.echo(f"  {c['noise_scale']:5g} {'yes' if c['change'] else 'no':>6s} {s['streams_ge90_m']:8.2f} "
                   f"{s['streams_ge90_zm_bar']:7.2f} {s['streams_ge90_both']:6.2f} {s['pooled_m']:9.3f} "
                   f"{s['pooled_zm_bar']:7.3f} {s['worst_m']:8.2f} {s['worst_zm_bar']:7.2f} {s['std_factor_needed']:6.2f} "
                   f"{d:>14s} "
                   f"{s['false_alarms']:6d} {s['realtime_min']:7.0f}")
