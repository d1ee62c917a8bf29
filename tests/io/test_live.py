"""Live NMEA feeds: the sentence parser, the sample assembler, and the UDP/TCP listener on 127.0.0.1."""

import math
import socket
import time

import numpy as np
import pytest

from shipid.errors import InputError
from shipid.io.live import Listener, Sender, parse_url
from shipid.io.nmea_fields import BadLine
from shipid.io.nmea_live import Assembler, checksum, estimate_sentences, parse_line, sample_sentences


def _s(body, tag=None):
    line = f"${body}*{checksum(body)}"
    if tag is not None:
        line = f"\\{tag}*{checksum(tag)}\\" + line
    return line


def test_exact_sentences_round_trip_bit_for_bit():
    vals = (0.12345678901234567, -0.6354167665395775, 1e-17, -0.0798535926437544)
    for t in (0.0, 0.02, 1799.98, 123456.78):
        (line,) = sample_sentences(t, *vals, style="exact")
        tt, d = parse_line(line)
        assert tt == t and tuple(d[c] for c in ("p", "a_s", "r", "delta")) == vals


def test_standard_sentences_in_degrees():
    lines = sample_sentences(1.5, 0.1, -0.2, 0.05, -0.03, style="standard")
    got = {}
    for ln in lines:
        t, d = parse_line(ln)
        assert t == 1.5
        got.update(d)
    assert [s.split(",")[0][-3:] for s in (ln.split("$")[1] for ln in lines)] == ["XDR", "ROT", "RSA"]
    for k, v in {"p": 0.1, "a_s": -0.2, "r": 0.05, "delta": -0.03}.items():
        assert got[k] == pytest.approx(v, rel=1e-14)


def test_units_sentences_and_vectornav():
    assert parse_line(_s("HEROT,-60.0,A")) == (None, {"r": pytest.approx(-math.radians(1.0))})
    assert parse_line(_s("HEROT,12.0,V")) == (None, {})                    # status V: not valid, not bad
    assert parse_line(_s("IIRSA,5.0,A,,V"))[1] == {"delta": pytest.approx(math.radians(5.0))}
    assert parse_line(_s("IIXDR,A,2.0,D,ROLLRATE,G,1.0,G,ACCY,C,20.1,C,TEMP"))[1] == {
        "p": pytest.approx(math.radians(2.0)), "a_s": pytest.approx(9.80665)}
    vn = _s("VNYMR,+010.1,-002.3,+001.2,+0.2,-0.1,+0.4,-0.051,+0.532,-9.801,+0.0101,-0.0020,+0.0300")
    assert parse_line(vn)[1] == {"p": 0.0101, "a_s": 0.532, "r": 0.03}
    assert parse_line(_s("GPHDT,123.4,T")) == (None, {})                   # other sentences: ignored


@pytest.mark.parametrize("line, kind", [
    ("$IIXDR,G,0.1,R,ROLLRATE*00", "XDR"),                                  # checksum
    ("$IIXDR,G,0.1,R,ROLLRATE", "line"),                                    # no checksum
    (_s("IIXDR,G,0.1,Q,ROLLRATE"), "XDR"),                                  # unknown unit
    (_s("IIXDR,G,abc,R,ROLLRATE"), "XDR"),                                  # not a number
    (_s("IIXDR,G,50,R,ROLLRATE"), "XDR"),                                   # out of range
    (_s("IIXDR,G,0.1,R"), "XDR"),                                           # not quadruplets
    (_s("HEROT,9000,A"), "ROT"),
    (_s("VNYMR,1,2,3"), "VNYMR"),
    (_s("IIXDR,G,0.1,R,ROLLRATE", tag="c:-5"), "tag"),
    ("\\c:12*00\\" + _s("IIXDR,G,0.1,R,ROLLRATE"), "tag"),                  # tag checksum
    ("x" * 300, "line"),
    ("hello", "line"),
])
def test_bad_lines_raise_badline(line, kind):
    with pytest.raises(BadLine) as e:
        parse_line(line)
    assert e.value.kind == kind


def test_assembler_joins_by_time_and_expires_lost_channels():
    a = Assembler(horizon=0.5)
    a.add(1.0, 0, {"p": 1.0, "a_s": 2.0})
    a.add(1.0, 0, {"r": 3.0})
    a.add(1.0, 0, {"delta": 4.0})
    assert a.take() == [(1.0, (1.0, 2.0, 3.0, 4.0))]
    a.add(1.02, 0, {"p": 1.0})                  # the rest of 1.02 lost
    for k in range(30):
        t = 1.04 + 0.02 * k
        a.add(t, 0, {"p": 1.0, "a_s": 2.0, "r": 3.0, "delta": 4.0})
    out = a.take()
    lost = [s for s in out if s[0] == 1.02]
    assert len(lost) == 1 and lost[0][1][0] == 1.0 and all(math.isnan(v) for v in lost[0][1][1:])
    assert a.incomplete == 1
    b = Assembler()                              # receive time: a sample per p, the others held
    b.add(None, 5.0, {"r": 0.3, "delta": 0.1})
    b.add(None, 5.02, {"p": 0.2, "a_s": 0.5})
    assert b.take() == [(5.02, (0.2, 0.5, 0.3, 0.1))]


def test_estimate_sentences_are_valid_nmea():
    lines = estimate_sentences({"m": 0.7, "m_std": 0.05, "zm_bar": -0.14, "zm_bar_std": 0.01, "alarm": True,
                                "change_at": 900.0})
    assert len(lines) == 2 and lines[1].startswith("$SIALR")
    for ln in lines:
        body, cs = ln[1:].split("*")
        assert checksum(body) == cs
    assert estimate_sentences({"m": None, "alarm": False}) == []


def test_parse_url_needs_host_and_port():
    assert parse_url("udp://127.0.0.1:10110") == ("udp", "127.0.0.1", 10110)
    for bad in ("udp://:10110", "udp://127.0.0.1", "http://127.0.0.1:80", "127.0.0.1:5", "tcp://h:notaport"):
        with pytest.raises(InputError):
            parse_url(bad)


def _free_port(kind):
    s = socket.socket(socket.AF_INET, kind)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def test_udp_listener_binds_only_the_address_and_counts_bad_datagrams():
    with Listener("udp://127.0.0.1:0", max_datagram=200) as lst:
        host, port = lst.address
        assert host == "127.0.0.1" and port > 0
        tx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        good = sample_sentences(0.0, 0.1, 0.2, 0.3, 0.4)[0].encode()
        for data in (good, b"\xff\xfe\x00garbage", b"x" * 1000, b"   ", good + b"\r\n" + good):
            tx.sendto(data, ("127.0.0.1", port))
        tx.close()
        got = [x for x in lst.lines(idle_timeout=0.5) if x[0] is not None]
    assert [g[2] for g in got] == [1, 5, 5]            # datagram numbers of the good lines
    c = lst.counts
    assert (c["datagrams"], c["not_text"], c["oversized"], c["empty"], c["lines"]) == (5, 1, 1, 1, 3)


def test_tcp_listener_lines_oversized_and_reconnect():
    port = _free_port(socket.SOCK_STREAM)
    with Listener(f"tcp://127.0.0.1:{port}", max_line=100) as lst:
        gen = lst.lines(idle_timeout=1.0)
        for payload in ([b"$A*00\r\n" + b"y" * 300 + b"\r\n$B*00\r\n"], [b"$C*00\n"]):
            with socket.create_connection(("127.0.0.1", port)) as c:
                for p in payload:
                    c.sendall(p)
            time.sleep(0.2)
        got = [x[0] for x in gen if x[0] is not None]
    assert got == ["$A*00", "$B*00", "$C*00"]
    assert lst.counts["oversized"] == 1 and lst.counts["connections"] == 2


def test_sender_udp_and_flood_limit():
    with Listener("udp://127.0.0.1:0", max_rate=50) as lst:
        with Sender(f"udp://127.0.0.1:{lst.address[1]}") as snd:
            for i in range(120):
                snd.send([f"line {i}"])
        got = [x for x in lst.lines(idle_timeout=0.5) if x[0] is not None]
    c = lst.counts
    assert c["datagrams"] == 120 and c["flood"] + len(got) == 120 and c["flood"] >= 120 - 2 * 50


def test_live_samples_untagged_use_receive_time_and_bad_lines_are_said():
    from shipid.methods.monitor.sources import FeedStats, live_samples

    said = []
    stats = FeedStats()
    with Listener("udp://127.0.0.1:0") as lst:
        with Sender(f"udp://127.0.0.1:{lst.address[1]}") as snd:
            snd.send([_s("HEROT,60.0,A"), _s("IIRSA,2.0,A,,")])
            for i in range(8):
                snd.send([_s(f"IIXDR,G,{0.01 * i!r},R,ROLLRATE,G,0.5,M,ACCY")])
            for i in range(7):
                snd.send([f"$IIXDR,G,0.1,R,ROLLRATE*{i:02d}"])          # bad checksums
        t0 = time.time()
        chunks = list(live_samples(lst, stats, said.append, idle_timeout=0.5, say_first=3))
    t = np.concatenate([c[0] for c in chunks])
    p = np.concatenate([c[1] for c in chunks])
    r = np.concatenate([c[3] for c in chunks])
    assert p.tolist() == [0.01 * i for i in range(8)] and np.all(r == math.radians(1.0))
    assert np.all(np.abs(t - t0) < 5.0) and np.all(np.diff(t) >= 0)     # receive times (s since the epoch)
    assert stats.bad_lines == 7 and stats.bad_total(lst.counts) == 7 and stats.samples == 8
    assert len(said) == 4 and said[-1].endswith("4 more bad sentences dropped (7 in all)")
