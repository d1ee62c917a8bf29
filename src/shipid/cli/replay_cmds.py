"""``shipid replay FILE --to udp://HOST:PORT``: a trial file sent as a live NMEA feed (tests, demonstrations)."""

from __future__ import annotations

import click

from shipid.cli import CONTEXT, cli


@cli.command("replay", context_settings=CONTEXT)
@click.argument("file", type=click.Path(dir_okay=False))
@click.option("--to", "url", required=True, type=str, help="Where to send: udp://HOST:PORT or tcp://HOST:PORT.")
@click.option("--speed", type=click.FloatRange(min=0), default=1.0, show_default=True,
              help="Times real time (the file's own time column); 0: as fast as possible.")
@click.option("--sentences", type=click.Choice(["exact", "standard"]), default="exact", show_default=True,
              help="'exact': one XDR per sample in SI units with 17 digits (the receiver gets the file's float64 "
                   "values); 'standard': XDR for roll rate and acceleration, ROT (deg/min) and RSA (deg).")
def replay_cmd(file, url, speed, sentences):
    """Send the IMU + rudder channels of a trial file (t, p, a_s, r, delta) as NMEA 0183 sentences, one
    datagram (or line group) per sample, each with a tag-block time: the live feed `shipid monitor mass-cm
    --listen` reads (shipid.io.nmea_live).
    Example: shipid replay s.csv --to udp://127.0.0.1:10110 --speed 10
    """
    from shipid.io.files import read_trial
    from shipid.io.live import Sender
    from shipid.io.nmea_live import replay

    tr = read_trial(file, required=["t", "p", "a_s", "r", "delta"])
    with Sender(url) as snd:
        n = replay(tr.t, tr["p"], tr["a_s"], tr["r"], tr["delta"], snd.send, speed=speed, style=sentences)
    click.echo(f"shipid: replay: {n} samples of {file} sent to {url}", err=True)
