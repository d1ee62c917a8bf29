"""``shipid monitor mass-cm --listen`` fed by ``shipid replay`` over real sockets on 127.0.0.1, as processes:
the same estimates as the file read directly; bad datagrams interleaved are counted and change nothing."""

import json
import re
import socket
import subprocess
import time

import numpy as np
import pytest
from monitor_procs import env, monitor_args, run, shipid_cmd

from shipid.io.files import read_trial
from shipid.io.nmea_live import sample_sentences


def _start(d, url, out, *extra):
    """The monitor listening on ``url`` (port 0: any free one); returns (process, the address it bound)."""
    proc = subprocess.Popen(shipid_cmd(*monitor_args(d, "--listen", url, "--idle-timeout", "3", "-o", str(out),
                                                     *extra)),
                            env=env(), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    line = proc.stderr.readline()
    m = re.match(r"shipid: listening on (\w+://127\.0\.0\.1:(\d+))", line)
    assert m, line
    return proc, m.group(1), int(m.group(2))


def _finish(proc):
    err = proc.stderr.read()
    assert proc.wait(timeout=120) == 0, err
    return err


def _lines(p):
    return p.read_text(encoding="utf-8").splitlines()


def test_udp_replay_at_25x_equals_the_file(stream300, tmp_path):
    d = stream300
    out = tmp_path / "udp.jsonl"
    proc, url, _ = _start(d, "udp://127.0.0.1:0", out)
    r = run("replay", str(d / "s.csv"), "--to", url, "--speed", "25")
    assert r.returncode == 0 and "15000 samples" in r.stderr
    err = _finish(proc)
    assert _lines(out) == _lines(d / "ref.jsonl")             # to the bit, every update
    assert f"{url}: 15000 datagrams received, 0 bad and dropped" in err and "0 incomplete" in err
    assert "warning" not in err


def test_tcp_replay_of_standard_sentences(stream300, tmp_path):
    """ROT (deg/min) and RSA (deg) carry r and delta in degrees: the values differ from the file's in the last
    bit (the unit conversions). The start-up's iterations stop at a tolerance, so last-bit input differences move
    the estimates within it (measured 8e-9 relative): they agree to 1e-6 relative, not to the bit. The standard
    errors are sums of squared block residuals (the sandwich of methods/monitor/covariance.py), and a residual
    is small next to the signals it is the difference of, so they move more (measured 2.3e-6 relative): 1e-4.
    The updates' times, alarm and change time are the same. Sent as fast as possible: TCP's flow control paces it."""
    d = stream300
    out = tmp_path / "tcp.jsonl"
    proc, url, _ = _start(d, "tcp://127.0.0.1:0", out)
    r = run("replay", str(d / "s.csv"), "--to", url, "--speed", "0", "--sentences", "standard")
    assert r.returncode == 0
    _finish(proc)
    got = [json.loads(x) for x in _lines(out)]
    ref = [json.loads(x) for x in _lines(d / "ref.jsonl")]
    assert len(got) == len(ref) == 30
    for g, f in zip(got, ref):
        assert (g["t"], g["alarm"], g["converged"], g["change_at"]) == (f["t"], f["alarm"], f["converged"],
                                                                       f["change_at"])
        for k, rel in (("m", 1e-6), ("zm_bar", 1e-6), ("m_std", 1e-4), ("zm_bar_std", 1e-4)):
            assert (g[k] is None) == (f[k] is None) and (g[k] is None or g[k] == pytest.approx(f[k], rel=rel))


def _fuzz(d, tmp_path, n_bad, seed, speed=25.0):
    """Replay the stream from this process over UDP with ``n_bad`` bad datagrams interleaved (random bytes,
    truncated sentences, oversized, empty); the monitor must count every one and give the clean run's lines."""
    rng = np.random.default_rng(seed)
    tr = read_trial(d / "s.csv")
    n = len(tr.t)
    out = tmp_path / "fuzz.jsonl"
    proc, url, port = _start(d, "udp://127.0.0.1:0", out)
    tx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    where = np.sort(rng.integers(0, n, n_bad))
    j = 0
    start = time.monotonic()
    for i in range(n):
        good = ("\r\n".join(sample_sentences(float(tr.t[i]), float(tr["p"][i]), float(tr["a_s"][i]),
                                             float(tr["r"][i]), float(tr["delta"][i]))) + "\r\n").encode()
        while j < n_bad and where[j] == i:
            kind = j % 4
            if kind == 0:
                bad = rng.integers(0, 256, int(rng.integers(1, 300)), dtype=np.uint8).tobytes()
            elif kind == 1:
                bad = good[:int(rng.integers(1, len(good) - 3))]
            elif kind == 2:
                bad = b"$IIXDR," + b"9" * 4000
            else:
                bad = b"" if j % 8 == 3 else b"\r\n  \r\n"
            tx.sendto(bad, ("127.0.0.1", port))
            j += 1
        tx.sendto(good, ("127.0.0.1", port))
        wait = start + (float(tr.t[i]) - float(tr.t[0])) / speed - time.monotonic()
        if wait > 0:
            time.sleep(wait)
    tx.close()
    err = _finish(proc)
    m = re.search(rf"{re.escape(url)}: (\d+) datagrams received, (\d+) bad and dropped", err)
    assert m, err
    assert (int(m.group(1)), int(m.group(2))) == (n + n_bad, n_bad)
    assert _lines(out) == _lines(d / "ref.jsonl")
    assert "Traceback" not in err


def test_fuzzed_feed_small(stream300, tmp_path):
    _fuzz(stream300, tmp_path, 400, 1)


@pytest.mark.slow
def test_fuzzed_feed_10000(stream300, tmp_path):
    _fuzz(stream300, tmp_path, 10000, 2)


def test_listen_refuses_an_address_without_host(stream300, capsys):
    from shipid.cli import main

    assert main(monitor_args(stream300, "--listen", "udp://:10110")) == 2
    assert "give the host and the port" in capsys.readouterr().err
    assert main(monitor_args(stream300, "--listen", "udp://127.0.0.1:1", "--stream", "x.csv")) == 2
    assert "give one of --stream" in capsys.readouterr().err


def test_emit_sends_estimates_and_the_alarm_as_nmea(stream300, tmp_path, capsys):
    from shipid.cli import main
    from shipid.io.live import Listener
    from shipid.io.nmea_live import checksum

    d = stream300
    with Listener("udp://127.0.0.1:0") as lst:
        url = f"udp://127.0.0.1:{lst.address[1]}"
        assert main(monitor_args(d, "--stream", str(d / "s.csv"), "--emit", url)) == 0
        got = [x[0] for x in lst.lines(idle_timeout=0.5) if x[0] is not None]
    capsys.readouterr()
    xdr = [g for g in got if g.startswith("$SIXDR")]
    alr = [g for g in got if g.startswith("$SIALR")]
    assert len(xdr) == 30 - 11 and len(alr) == 1 and "LOAD CHANGED AT T=200 S" in alr[0]   # estimates from 120 s
    for g in got:
        body, cs = g[1:].split("*")
        assert checksum(body) == cs
    ref = [json.loads(x) for x in _lines(d / "ref.jsonl") if json.loads(x)["m"] is not None]
    assert [float(x.split(",")[2]) for x in xdr] == [float(f"{r['m']:.6g}") for r in ref]
