"""NMEA 0183 logs as trials (shipid.io.nmea): synthetic logs from a known trajectory, read back.

The logs are written with pynmea2 (so every checksum is right) from an exact
constant-turn trajectory: speed U, heading psi(t) = psi0 + r t, which gives
x = U/r (sin psi - sin psi0), y = -U/r (cos psi - cos psi0) (Fossen 2011 eq. 2.18,
flat earth, north-east).
"""

import math
import subprocess
import sys
from datetime import datetime, timezone

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import pynmea2

from shipid.cli import main
from shipid.io import Trial, read_trial
from shipid.io.nmea import MAX_BAD_FRACTION, flat_earth, flat_earth_inverse, looks_like_nmea
from shipid.errors import InputError

LAT0, LON0 = 57.70, 11.95            # Gothenburg approaches
U = 5.0                              # m/s
R_DEG_S = 0.5                        # deg/s yaw rate (30 deg/min)
PSI0_DEG = 350.0                     # crosses 0/360 after 20 s
T_END = 100.0                        # 500 m track
T0_UNIX = 1763778600.0               # 2025-11-22T02:30:00Z
RUDDER_DEG = -7.5
RPM = 84.0


def truth(t):
    r = math.radians(R_DEG_S)
    psi = math.radians(PSI0_DEG) + r * t
    x = U / r * (np.sin(psi) - math.sin(math.radians(PSI0_DEG)))
    y = -U / r * (np.cos(psi) - math.cos(math.radians(PSI0_DEG)))
    return x, y, np.mod(psi, 2 * np.pi)


def _ddmm(deg, lat):
    a = abs(deg)
    d = int(a)
    m = (a - d) * 60.0
    h = ("N" if deg >= 0 else "S") if lat else ("E" if deg >= 0 else "W")
    return (f"{d:02d}" if lat else f"{d:03d}") + f"{m:010.7f}", h


def _hms(t_unix):
    dt = datetime.fromtimestamp(t_unix, tz=timezone.utc)
    return dt.strftime("%H%M%S.") + f"{dt.microsecond // 10000:02d}", dt.strftime("%d%m%y")


def sentences(t_end=T_END):
    """(time, sentence string) pairs of a synthetic log, in time order."""
    out = []
    for k in range(int(round(t_end * 10)) + 1):
        t = k / 10.0
        x, y, psi = truth(np.array(t))
        if k % 10 == 0:
            lat, lon = flat_earth_inverse(x, y, LAT0, LON0)
            la, lah = _ddmm(float(lat), True)
            lo, loh = _ddmm(float(lon), False)
            hms, dmy = _hms(T0_UNIX + t)
            out.append((t, pynmea2.GGA("GP", "GGA", (hms, la, lah, lo, loh, "1", "09", "0.9", "12.0", "M",
                                                      "40.0", "M", "", ""))))
            cog = math.degrees(float(psi))
            out.append((t, pynmea2.RMC("GN", "RMC", (hms, "A", la, lah, lo, loh, f"{U / (1852 / 3600):.3f}",
                                                      f"{cog:.2f}", dmy, "", ""))))
            out.append((t, pynmea2.VHW("II", "VHW", ("", "T", "", "M", f"{U / (1852 / 3600):.3f}", "N", "", "K"))))
            out.append((t, pynmea2.MWV("II", "MWV", ("30.0", "R", "12.0", "N", "A"))))
            out.append((t, pynmea2.GSV("GP", "GSV", ("1", "1", "01", "03", "03", "111", "00"))))
        if k % 5 == 0:
            out.append((t, pynmea2.RPM("II", "RPM", ("S", "1", f"{RPM:.1f}", "", "A"))))
            out.append((t, pynmea2.RSA("II", "RSA", (f"{RUDDER_DEG:.1f}", "A", "", ""))))
        out.append((t, pynmea2.HDT("HE", "HDT", (f"{math.degrees(float(psi)):.3f}", "T"))))
        out.append((t, pynmea2.ROT("TI", "ROT", (f"{R_DEG_S * 60:.2f}", "A"))))
    return [(t, str(s)) for t, s in out]


def _tag(c, fmt=".3f"):
    body = f"c:{c:{fmt}},s:logger"
    cs = 0
    for ch in body:
        cs ^= ord(ch)
    return f"\\{body}*{cs:02X}\\"


def write_log(path, base="tag", lines=None):
    lines = lines if lines is not None else sentences()
    out = []
    for t, s in lines:
        if base == "tag":
            out.append(_tag(T0_UNIX + t) + s)
        elif base == "epoch":
            out.append(f"{T0_UNIX + t:.3f} {s}")
        elif base == "iso":
            iso = datetime.fromtimestamp(T0_UNIX + t, tz=timezone.utc).isoformat(timespec="milliseconds")
            out.append(iso.replace("+00:00", "Z") + "," + s)
        else:
            out.append(s)
    path.write_text("\n".join(out) + "\n")
    return path


@pytest.fixture(scope="module")
def tag_log(tmp_path_factory):
    return write_log(tmp_path_factory.mktemp("nmea") / "trial.nmea", "tag")


def test_tag_block_log_reads_back_the_trajectory(tag_log):
    tr = read_trial(tag_log)
    assert tr.meta["format"] == "nmea" and tr.meta["time_base"] == "tag_block"
    assert tr.dt == pytest.approx(0.1, rel=1e-9)
    t_abs = tr.t + tr.meta["t0_unix"] - T0_UNIX
    x, y, psi = truth(t_abs)
    # positions: 7-decimal minutes (~0.2 mm) and linear interpolation between 1-Hz fixes on a
    # 573-m circle (sag 5^2/(8*573) = 5.5 mm) -> well inside the 0.05 m asked for
    assert np.max(np.hypot(tr["x"] - x, tr["y"] - y)) < 0.05
    assert np.max(np.abs(tr["x"])) > 100 and np.hypot(x[-1], y[-1]) > 400   # a real 500-m track
    # heading crosses 0/360 (350 deg -> 40 deg): no jump through 180 on the way
    err = np.angle(np.exp(1j * (tr["psi"] - psi)))
    assert np.max(np.abs(err)) < math.radians(0.002)
    assert np.all((tr["psi"] >= 0) & (tr["psi"] < 2 * np.pi))
    assert tr["psi"].min() < 0.1 and tr["psi"].max() > 6.2
    # ROT: 30 deg/min -> 0.5 deg/s in rad/s
    np.testing.assert_allclose(tr["r"], math.radians(0.5), rtol=1e-12)
    np.testing.assert_allclose(tr["delta"], math.radians(RUDDER_DEG), rtol=1e-12)
    np.testing.assert_allclose(tr["n"], RPM / 60.0, rtol=1e-12)
    # speeds are written to 0.001 kn: 9.719 kn for 9.7192 kn, relative rounding <= 0.0005/9.72 = 5e-5
    np.testing.assert_allclose(tr["U"], U, rtol=6e-5)
    np.testing.assert_allclose(tr["sog"], U, rtol=6e-5)
    # derived over-ground velocities: the ship moves along its heading (no drift in the truth)
    np.testing.assert_allclose(tr["u"], U, rtol=6e-5)
    np.testing.assert_allclose(tr["v"], 0.0, atol=U * math.radians(0.01))    # cog written to 0.01 deg
    np.testing.assert_allclose(np.hypot(tr["x_dot"], tr["y_dot"]), U, rtol=6e-5)
    np.testing.assert_allclose(tr["wind_speed_rel"], 12.0 * 1852 / 3600, rtol=1e-12)
    np.testing.assert_allclose(tr["wind_dir_rel"], math.radians(30.0), rtol=1e-12)
    assert tr.meta["ignored"] == {"GSV": 101}
    assert tr.meta["skipped"] == {}
    assert tr.meta["origin"] == {"lat": LAT0, "lon": LON0}
    assert tr.meta["rpm_source"] == "shaft 1"


@pytest.mark.parametrize("base, name", [("epoch", "prefix_epoch"), ("iso", "prefix_iso")])
def test_prefix_time_bases(tmp_path, base, name):
    tr = read_trial(write_log(tmp_path / "p.log", base))
    assert tr.meta["format"] == "nmea" and tr.meta["time_base"] == name
    assert tr.meta["t0_unix"] == pytest.approx(T0_UNIX, abs=1e-3)
    t_abs = tr.t + tr.meta["t0_unix"] - T0_UNIX
    x, y, _ = truth(t_abs)
    assert np.max(np.hypot(tr["x"] - x, tr["y"] - y)) < 0.05


def test_sentence_utc_time_base_is_coarse_and_says_so(tmp_path):
    # a log that starts with two heading sentences before the first fix
    lines = [(0.0, str(pynmea2.HDT("HE", "HDT", ("1.0", "T"))))] * 2 + sentences(20.0)
    tr = read_trial(write_log(tmp_path / "u.txt", "none", lines))
    assert tr.meta["time_base"] == "sentence_utc"
    assert "coarse" in tr.meta["time_base_note"]
    assert tr.meta["before_first_fix"] == 2
    assert tr.dt == pytest.approx(1.0)          # every sentence carries the 1-Hz fix time
    assert tr.meta["t0_unix"] == pytest.approx(T0_UNIX, abs=1e-6)
    x, y, _ = truth(tr.t)
    assert np.max(np.hypot(tr["x"] - x, tr["y"] - y)) < 0.05


def test_local_tangent_plane_against_wgs84_radii():
    """Small steps north/east match the WGS-84 meridian and prime-vertical radii (textbook values)."""
    a, f = 6378137.0, 1 / 298.257223563
    e2 = f * (2 - f)
    for lat0 in (0.0, 45.0, 60.0, -70.0):
        p0 = np.radians(lat0)
        r_m = a * (1 - e2) / (1 - e2 * np.sin(p0) ** 2) ** 1.5      # meridian radius
        r_n = a / np.sqrt(1 - e2 * np.sin(p0) ** 2)                  # prime-vertical radius
        step = 1e-3                                                   # deg: ~111 m
        x, y, _ = flat_earth(np.array([lat0 + step, lat0]), np.array([10.0, 10.0 + step]), lat0, 10.0)
        # 111-m steps: the tangent plane departs from the arc by ~d^2/R = 2 mm in the other axis
        assert abs(x[0] - r_m * np.radians(step)) < 1e-4 and abs(y[0]) < 1e-9
        assert abs(y[1] - r_n * np.cos(p0) * np.radians(step)) < 1e-4 and abs(x[1]) < 5e-3
    assert a * (1 - e2) * np.radians(1 / 60) == pytest.approx(1842.9, abs=0.05)   # 1' of latitude at 0 deg
    rng = np.random.default_rng(7)
    for lat0 in (0.0, 60.0, -70.0):
        xs, ys = rng.uniform(-5000, 5000, (2, 50))
        lat, lon = flat_earth_inverse(xs, ys, lat0, 10.0)
        x, y, _ = flat_earth(lat, lon, lat0, 10.0)
        np.testing.assert_allclose(np.hypot(x - xs, y - ys), 0, atol=1e-6)   # inverse to a micrometre


def test_corrupt_checksum_is_one_line_with_line_number(tmp_path):
    lines = sentences(10.0)
    text = write_log(tmp_path / "c.nmea", "epoch", lines).read_text().splitlines()
    i = [k for k, s in enumerate(text) if "HDT" in s][6]
    assert i > 10
    text[i] = text[i].replace("HDT,", "HDT,1")         # payload changed, checksum kept
    p = tmp_path / "c.nmea"
    p.write_text("\n".join(text) + "\n")
    with pytest.raises(InputError) as info:
        read_trial(p)
    msg = str(info.value)
    assert "\n" not in msg and str(p) in msg and f"line {i + 1}," in msg and "HDT" in msg
    assert msg.endswith(f"line {i + 1}, HDT sentence: checksum does not match: " + msg.split(": ")[-1])
    assert "[" not in msg                                  # the message, not pynmea2's field list
    assert main(["check", str(p)]) == 2


def test_out_of_range_field_names_channel_and_line(tmp_path):
    lines = sentences(5.0)
    lines[3] = (lines[3][0], str(pynmea2.RSA("II", "RSA", ("95.0", "A", "", ""))))
    p = write_log(tmp_path / "r.nmea", "tag", lines)
    with pytest.raises(InputError, match=r"channel 'delta': line 4, RSA sentence: rudder angle \[deg\] 95 out"):
        read_trial(p)


def test_skip_bad_sentences_counts_per_type_and_limits_the_fraction(tmp_path):
    lines = sentences(20.0)
    n = len(lines)
    text = write_log(tmp_path / "s.nmea", "tag", lines).read_text().splitlines()
    hdt = [i for i, s in enumerate(text) if "HEHDT" in s][5:35:10]     # single losses: bridged
    rot = [i for i, s in enumerate(text) if "TIROT" in s][3:4]
    for i in hdt + rot:
        text[i] = text[i][:-1] + ("0" if text[i][-1] != "0" else "1")   # corrupt the checksum
    text.insert(40, "garbage line without a sentence")
    p = tmp_path / "s.nmea"
    p.write_text("\n".join(text) + "\n")
    with pytest.raises(InputError, match="checksum"):
        read_trial(p)
    tr = read_trial(p, skip_bad=True)
    assert tr.meta["skipped"] == {"HDT": 3, "ROT": 1, "line": 1}
    assert tr.meta["sentences"] == n + 1
    # too many bad lines: still an error, even with skip_bad
    many = int(MAX_BAD_FRACTION * n) + 2
    for i in [i for i, s in enumerate(text) if "HEHDT" in s][10:10 + many]:
        text[i] = text[i][:-1] + ("0" if text[i][-1] != "0" else "1")
    p.write_text("\n".join(text) + "\n")
    with pytest.raises(InputError, match=r"lines bad, more than 5%"):
        read_trial(p, skip_bad=True)


def test_long_gap_left_nan_for_validation(tmp_path):
    lines = [(t, s) for t, s in sentences(30.0) if not ("HDT" in s and 10.0 < t < 15.0)]
    p = write_log(tmp_path / "g.nmea", "tag", lines)
    with pytest.raises(InputError, match=r"channel 'psi', row \d+: missing value"):
        read_trial(p)
    tr = read_trial(p, interpolate_gaps=6.0)
    assert np.all(np.isfinite(tr["psi"]))


@pytest.mark.parametrize("field, value, fragment", [
    (9, "2211", "date is not ddmmyy"),          # pynmea2 would read this as 2 Feb 2011
    (9, "2211x5", "date is not ddmmyy"),        # pynmea2 would hand back the text
    (1, "0230", "UTC time '0230' is not hhmmss.ss"),
    (1, "256000", "UTC time"),
])
def test_bad_rmc_time_or_date_is_an_error(tmp_path, field, value, fragment):
    # found by fuzzing: pynmea2 does not refuse a malformed date, it returns a wrong or raw value
    lines = sentences(3.0)
    k = next(i for i, (_, s) in enumerate(lines) if "RMC" in s and i > 10)
    fields = lines[k][1].split("*")[0].split(",")
    fields[field] = value
    msg = pynmea2.parse(",".join(fields))
    lines[k] = (lines[k][0], str(msg))
    p = write_log(tmp_path / "d.nmea", "none", lines)
    with pytest.raises(InputError, match=fragment) as info:
        read_trial(p)
    assert f"line {k + 1}, RMC sentence" in str(info.value)


def test_hdg_with_variation_gives_true_heading(tmp_path):
    lines = []
    for k in range(20):
        t = k * 0.5
        hms, _ = _hms(T0_UNIX + t)
        lines.append((t, str(pynmea2.HDG("HC", "HDG", ("355.0", "2.0", "E", "4.5", "W")))))
        lines.append((t, str(pynmea2.ROT("HE", "ROT", ("-6.0", "A")))))
    tr = read_trial(write_log(tmp_path / "h.nmea", "tag", lines))
    np.testing.assert_allclose(tr["psi"], math.radians(355.0 + 2.0 - 4.5), rtol=1e-12)
    np.testing.assert_allclose(tr["r"], -math.radians(6.0) / 60, rtol=1e-12)
    assert tr.meta["psi_source"].startswith("HDG")


def test_other_units_millisecond_tags_zda_and_format_option(tmp_path):
    lines = []
    for k in range(11):
        t = k * 1.0
        hms, _ = _hms(T0_UNIX + t)
        lines += [(t, str(pynmea2.MWV("WI", "MWV", ("270.0", "T", "36.0", "K", "A")))),
                  (t, str(pynmea2.VTG("GP", "VTG", ("90.0", "T", "", "M", "", "N", "18.52", "K", "A")))),
                  (t, str(pynmea2.RPM("II", "RPM", ("E", "2", "-120.0", "", "A")))),
                  (t, str(pynmea2.ZDA("GP", "ZDA", (hms, "22", "11", "2025", "00", "00"))))]
    p = tmp_path / "w.dat"                                    # not an NMEA extension: --format nmea
    p.write_text("\n".join(_tag(1000 * (T0_UNIX + t), ".0f") + s.split("*")[0]
                           for t, s in lines) + "\n")         # c: in ms, sentences without checksum
    with pytest.raises(InputError):
        read_trial(p)                                         # .dat -> HSVA format: not this file
    tr = read_trial(p, fmt="nmea")
    assert tr.meta["t0_unix"] == pytest.approx(T0_UNIX) and tr.dt == pytest.approx(1.0)
    assert tr.meta["no_checksum"] == len(lines)
    np.testing.assert_allclose(tr["wind_speed"], 10.0, rtol=1e-12)           # 36 km/h
    np.testing.assert_allclose(tr["wind_angle_true"], math.radians(270.0), rtol=1e-12)
    np.testing.assert_allclose(tr["sog"], 18.52 / 3.6, rtol=1e-12)            # km/h when knots are empty
    np.testing.assert_allclose(tr["cog"], math.pi / 2, rtol=1e-12)
    np.testing.assert_allclose(tr["n"], -2.0, rtol=1e-12)                     # astern, engine 2
    assert tr.meta["rpm_source"] == "engine 2"


def test_sniffing_txt_and_log():
    assert looks_like_nmea(b"$GPGGA,1,2*00\n$GPHDT,1,T*00\n")
    assert looks_like_nmea(b"\\c:1700000000*00\\$GPHDT,1,T*00\n")
    assert looks_like_nmea(b"2026-11-22T02:30:00.1Z $HEHDT,1,T*00\n")
    assert not looks_like_nmea(b"t [s],x [m]\n0,1\n")
    assert not looks_like_nmea(b"")


def test_cli_convert_then_check(tmp_path, tag_log, capsys):
    out = tmp_path / "t.parquet"
    assert main(["convert", str(tag_log), str(out)]) == 0
    assert main(["check", str(out)]) == 0
    text = capsys.readouterr().out
    assert "psi" in text and "delta" in text
    tr = read_trial(out)
    assert tr.meta["time_base"] == "tag_block"
    np.testing.assert_allclose(tr["r"], math.radians(0.5), rtol=1e-12)


def test_cli_skip_bad_sentences_subprocess(tmp_path):
    text = write_log(tmp_path / "b.nmea", "epoch", sentences(10.0)).read_text().splitlines()
    text[20] = text[20][:-1] + ("0" if text[20][-1] != "0" else "1")
    p = tmp_path / "b.nmea"
    p.write_text("\n".join(text) + "\n")
    bad = subprocess.run([sys.executable, "-m", "shipid", "check", str(p)], capture_output=True, text=True)
    assert bad.returncode == 2 and "line 21" in bad.stderr + bad.stdout
    assert len((bad.stderr + bad.stdout).strip().splitlines()) == 1
    good = subprocess.run([sys.executable, "-m", "shipid", "check", str(p), "--skip-bad-sentences"],
                          capture_output=True, text=True)
    assert good.returncode == 0, good.stderr
    assert "nmea" in good.stdout


# ---------------------------------------------------------------------------- fuzz
VALID = None


def _valid():
    global VALID
    if VALID is None:
        lines = sentences(3.0)
        VALID = "\n".join(_tag(T0_UNIX + t) + s for t, s in lines).encode() + b"\n"
    return VALID


FUZZ = settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


def _answer(path, data, **kw):
    path.write_bytes(data)
    try:
        tr = read_trial(path, **kw)
    except InputError as err:
        assert "\n" not in str(err) and str(path) in str(err)
        return
    assert isinstance(tr, Trial)
    assert np.all(np.isfinite(tr.t)) and np.all(np.diff(tr.t) > 0)
    for v in tr.channels.values():
        assert np.all(np.isfinite(v))


@FUZZ
@given(data=st.binary(max_size=300))
def test_fuzz_random_bytes(tmp_path, data):
    _answer(tmp_path / "f.nmea", data)


@FUZZ
@given(cut=st.integers(0, 4000), length=st.integers(0, 30),
       insert=st.text(alphabet="$!\\*,.-0123456789ABCDEFGHPTNSEWc:\n ", max_size=10), skip=st.booleans())
def test_fuzz_mutated_log(tmp_path, cut, length, insert, skip):
    v = _valid()
    cut = cut % (len(v) + 1)
    _answer(tmp_path / "m.nmea", v[:cut] + insert.encode() + v[cut + length:], skip_bad=skip)


def test_speed_over_ground_gives_u_when_a_method_needs_it(tmp_path, capsys):
    """No speed log (no VHW): a method that needs U gets the speed over ground, and says so."""
    log = write_log(tmp_path / "nolog.nmea", "tag", [(t, s) for t, s in sentences() if "VHW" not in s])
    plain = read_trial(log)
    assert "sog" in plain and "U" not in plain
    tr = read_trial(log, required=["x", "y", "psi", "U"], method="ebm")
    np.testing.assert_array_equal(tr["U"], tr["sog"])
    assert any(r.get("channel") == "U" and "speed over ground" in r["text"] for r in tr.meta["repairs"])
    assert main(["check", str(log), "--require", "U"]) == 0
    out = capsys.readouterr().out
    assert "repaired: U, the speed through the water" in out and "derived: sog (speed over ground)" in out
