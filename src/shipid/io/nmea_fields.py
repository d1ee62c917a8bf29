"""Fields of single NMEA 0183 sentences and time stamps, in SI units, range-checked.

The sentence table, units and conventions are those of :mod:`shipid.io.nmea`, which
reads whole logs with these pieces. A field that is out of range, of a wrong unit or
unparsable raises :class:`BadLine` naming the sentence type and the channel; the log
reader turns it into one :class:`~shipid.errors.InputError` naming the line.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from datetime import date, datetime, time, timezone

#: Range checks: |rate of turn| [deg/min], |rudder| [deg], |rpm|, speeds [knots].
MAX_ROT_DEG_MIN = 1800.0
MAX_RUDDER_DEG = 90.0
#: Sentences carrying one status-gated angle: status field, value field, |limit|, label, channel, seconds
#: per unit of time in the value (ROT is in deg/min, so rad/s = radians(value) / 60).
_GATED_ANGLES = {
    "ROT": ("status", "rate_of_turn", MAX_ROT_DEG_MIN, "rate of turn [deg/min]", "r", 60.0),
    "RSA": ("rsa_starboard_status", "rsa_starboard", MAX_RUDDER_DEG, "rudder angle [deg]", "delta", 1.0),
}
MAX_RPM = 10000.0
MAX_SPEED_KN = 200.0

_KNOT = 1852.0 / 3600.0
_WIND_UNITS = {"K": 1000.0 / 3600.0, "M": 1.0, "N": _KNOT, "S": 1609.344 / 3600.0}


@dataclass
class Samples:
    """One channel's samples as read: times (s), values (SI) and the log line of each."""

    t: list = field(default_factory=list)
    v: list = field(default_factory=list)
    line: list = field(default_factory=list)

    def add(self, t: float, v: float, line: int) -> None:
        if self.t and self.t[-1] == t:      # same time stamp: keep the last value
            self.v[-1] = v
            self.line[-1] = line
            return
        self.t.append(t)
        self.v.append(v)
        self.line.append(line)


class BadLine(Exception):
    """A line that cannot be used: ``kind`` (sentence type, ``"tag"``, ``"time"`` or ``"line"``), the
    message and the channel it concerns (None: the whole line)."""

    def __init__(self, kind: str, message: str, channel: str | None = None):
        super().__init__(message)
        self.kind = kind
        self.message = message
        self.channel = channel


def number(msg, attr: str, kind: str, channel: str | None) -> float | None:
    """A numeric field of a pynmea2 sentence, None when empty."""
    try:
        raw = msg.data[[f[1] for f in msg.fields].index(attr)]
    except (ValueError, IndexError):
        return None
    if raw is None or not str(raw).strip():
        return None
    try:
        value = float(str(raw).strip())
    except ValueError:
        raise BadLine(kind, f"field '{attr}' is not a number: '{str(raw)[:20]}'", channel) from None
    if not math.isfinite(value):
        raise BadLine(kind, f"field '{attr}' is not finite", channel)
    return value


def text_field(msg, attr: str) -> str:
    try:
        return str(msg.data[[f[1] for f in msg.fields].index(attr)]).strip()
    except (ValueError, IndexError):
        return ""


def in_range(value: float, lo: float, hi: float, kind: str, what: str, channel: str | None) -> float:
    if not lo <= value <= hi:
        raise BadLine(kind, f"{what} {value:g} out of range [{lo:g}, {hi:g}]", channel)
    return value


def lat_lon(msg, kind: str) -> tuple[float, float] | None:
    lat, lat_dir = text_field(msg, "lat"), text_field(msg, "lat_dir")
    lon, lon_dir = text_field(msg, "lon"), text_field(msg, "lon_dir")
    if not lat or not lon:
        return None
    try:
        lat_d, lat_m = float(lat[:2]), float(lat[2:])
        lon_d, lon_m = float(lon[:3]), float(lon[3:])
    except ValueError:
        raise BadLine(kind, f"position '{lat},{lon}' is not ddmm.mmm,dddmm.mmm", "x") from None
    if lat_dir not in ("N", "S") or lon_dir not in ("E", "W"):
        raise BadLine(kind, f"hemisphere '{lat_dir}'/'{lon_dir}' is not N/S and E/W", "x")
    if not (0 <= lat_m < 60 and 0 <= lon_m < 60 and 0 <= lat_d <= 90 and 0 <= lon_d <= 180):
        raise BadLine(kind, f"position '{lat},{lon}' out of range", "x")
    phi = (lat_d + lat_m / 60.0) * (-1 if lat_dir == "S" else 1)
    lam = (lon_d + lon_m / 60.0) * (-1 if lon_dir == "W" else 1)
    if abs(phi) > 90 or abs(lam) > 180:
        raise BadLine(kind, f"position {phi:g}, {lam:g} deg out of range", "x")
    return phi, lam


def time_of_day(msg) -> float | None:
    ts = text_field(msg, "timestamp")
    if not ts:
        return None
    if not re.fullmatch(r"\d{6}(\.\d+)?", ts):
        raise BadLine(msg.sentence_type, f"UTC time '{ts[:12]}' is not hhmmss.ss", "t")
    try:
        tod = msg.timestamp
    except (ValueError, TypeError, IndexError):
        raise BadLine(msg.sentence_type, f"UTC time '{ts[:12]}' is not hhmmss.ss", "t") from None
    if not isinstance(tod, time):
        raise BadLine(msg.sentence_type, f"UTC time '{ts[:12]}' is not hhmmss.ss", "t")
    return tod.hour * 3600 + tod.minute * 60 + tod.second + tod.microsecond * 1e-6


def sentence_date(msg) -> date | None:
    try:
        if msg.sentence_type == "RMC" and text_field(msg, "datestamp"):
            # pynmea2 hands back the raw text when it cannot convert, and strptime reads
            # '2211' as 2 Feb 2011: insist on ddmmyy
            d = msg.datestamp
            if not re.fullmatch(r"\d{6}", text_field(msg, "datestamp")) or not isinstance(d, date):
                raise ValueError
            return d
        if msg.sentence_type == "ZDA" and text_field(msg, "year"):
            return date(int(msg.year), int(msg.month), int(msg.day))
    except (ValueError, TypeError):
        raise BadLine(msg.sentence_type, "date is not ddmmyy or out of range", "t") from None
    return None


def sentence_values(msg, stype: str, out: dict, counts: dict) -> None:
    """Channel values of one sentence (SI units) into ``out``: name -> value."""
    def invalid() -> None:
        counts["invalid"][stype] = counts["invalid"].get(stype, 0) + 1

    if stype in ("GGA", "RMC"):
        if stype == "GGA":
            q = text_field(msg, "gps_qual")
            if q in ("", "0"):
                invalid()
                return
        elif text_field(msg, "status") != "A":
            invalid()
            return
        pos = lat_lon(msg, stype)
        if pos is not None:
            out["lat"], out["lon"] = pos
        if stype == "RMC":
            sog = number(msg, "spd_over_grnd", stype, "sog")
            cog = number(msg, "true_course", stype, "cog")
            if sog is not None:
                out["sog"] = in_range(sog, 0, MAX_SPEED_KN, stype, "speed over ground [kn]", "sog") * _KNOT
            if cog is not None:
                out["cog"] = math.radians(in_range(cog, 0, 360, stype, "course [deg]", "cog")) % (2 * math.pi)
    elif stype == "VTG":
        cog = number(msg, "true_track", stype, "cog")
        kn = number(msg, "spd_over_grnd_kts", stype, "sog")
        kmh = number(msg, "spd_over_grnd_kmph", stype, "sog")
        if text_field(msg, "faa_mode") == "N":
            invalid()
            return
        if cog is not None:
            out["cog"] = math.radians(in_range(cog, 0, 360, stype, "course [deg]", "cog")) % (2 * math.pi)
        if kn is not None:
            out["sog"] = in_range(kn, 0, MAX_SPEED_KN, stype, "speed over ground [kn]", "sog") * _KNOT
        elif kmh is not None:
            out["sog"] = in_range(kmh / 1.852, 0, MAX_SPEED_KN, stype, "speed over ground [kn]", "sog") * _KNOT
    elif stype == "HDT":
        h = number(msg, "heading", stype, "psi")
        if h is not None:
            out["psi"] = math.radians(in_range(h, 0, 360, stype, "heading [deg]", "psi")) % (2 * math.pi)
    elif stype == "HDG":
        h = number(msg, "heading", stype, "psi")
        if h is None:
            return
        in_range(h, 0, 360, stype, "heading [deg]", "psi")
        dev = number(msg, "deviation", stype, "psi")
        var = number(msg, "variation", stype, "psi")
        for val, d, what in ((dev, text_field(msg, "dev_dir"), "deviation"), (var, text_field(msg, "var_dir"), "variation")):
            if val is not None:
                in_range(val, 0, 180, stype, f"{what} [deg]", "psi")
                if d not in ("E", "W"):
                    raise BadLine(stype, f"{what} direction '{d}' is not E or W", "psi")
        dev = 0.0 if dev is None else (dev if text_field(msg, "dev_dir") == "E" else -dev)
        name = "psi_hdg"
        if var is None:
            name = "psi_magnetic"
            var = 0.0
        else:
            var = var if text_field(msg, "var_dir") == "E" else -var
        out[name] = math.radians(h + dev + var) % (2 * math.pi)
    elif stype in _GATED_ANGLES:      # ROT, RSA: one angle (rate) each, valid only with status A
        status, fld, limit, what, channel, per_s = _GATED_ANGLES[stype]
        if text_field(msg, status) != "A":
            invalid()
            return
        v = number(msg, fld, stype, channel)
        if v is not None:
            out[channel] = math.radians(in_range(v, -limit, limit, stype, what, channel)) / per_s
    elif stype == "RPM":
        if text_field(msg, "status") != "A":
            invalid()
            return
        src, num = text_field(msg, "source"), text_field(msg, "engine_no")
        if src not in ("S", "E"):
            raise BadLine(stype, f"source '{src}' is not S (shaft) or E (engine)", "n")
        rpm = number(msg, "speed", stype, "n")
        if rpm is not None:
            out[f"rpm:{src}{num}"] = in_range(rpm, -MAX_RPM, MAX_RPM, stype, "speed [rpm]", "n") / 60.0
    elif stype == "VHW":
        kn = number(msg, "water_speed_knots", stype, "U")
        kmh = number(msg, "water_speed_km", stype, "U")
        if kn is not None:
            out["U"] = in_range(kn, -MAX_SPEED_KN, MAX_SPEED_KN, stype, "water speed [kn]", "U") * _KNOT
        elif kmh is not None:
            out["U"] = in_range(kmh / 1.852, -MAX_SPEED_KN, MAX_SPEED_KN, stype, "water speed [kn]", "U") * _KNOT
    elif stype == "MWV":
        if text_field(msg, "status") != "A":
            invalid()
            return
        ref = text_field(msg, "reference")
        if ref not in ("R", "T"):
            raise BadLine(stype, f"reference '{ref}' is not R (relative) or T (true)", "wind_speed")
        sp_name, dir_name = ("wind_speed_rel", "wind_dir_rel") if ref == "R" else ("wind_speed", "wind_angle_true")
        ang = number(msg, "wind_angle", stype, dir_name)
        sp = number(msg, "wind_speed", stype, sp_name)
        unit = text_field(msg, "wind_speed_units")
        if ang is not None:
            out[dir_name] = math.radians(in_range(ang, 0, 360, stype, "wind angle [deg]", dir_name)) % (2 * math.pi)
        if sp is not None:
            if unit not in _WIND_UNITS:
                raise BadLine(stype, f"wind speed unit '{unit}' is not K, M, N or S", sp_name)
            out[sp_name] = in_range(sp * _WIND_UNITS[unit], 0, 100, stype, "wind speed [m/s]", sp_name)


def tag_time(tag: str) -> float | None:
    """Unix time from the ``c:`` field of a tag block (checksum checked), None without one."""
    body, star, cs = tag.partition("*")
    if star:
        want = 0
        for ch in body:
            want ^= ord(ch)
        try:
            ok = int(cs.strip(), 16) == want
        except ValueError:
            ok = False
        if not ok:
            raise BadLine("tag", f"tag block checksum does not match ({cs.strip()[:4]} != {want:02X})", "t")
    for part in body.split(","):
        if part.startswith("c:"):
            try:
                c = float(part[2:])
            except ValueError:
                raise BadLine("tag", f"tag block time '{part[:20]}' is not a number", "t") from None
            if not math.isfinite(c) or c < 0:
                raise BadLine("tag", f"tag block time '{part[:20]}' out of range", "t")
            return c / 1000.0 if c > 1e11 else c
    return None


def prefix_time(prefix: str) -> tuple[str, float] | None:
    """``("prefix_epoch"|"prefix_iso", unix seconds)`` for a receive-time prefix, None if it is none."""
    s = prefix.strip().rstrip(",;:").strip()
    if not s:
        return None
    try:
        v = float(s)
        if math.isfinite(v) and v >= 0:
            return "prefix_epoch", v
        return None
    except ValueError:
        pass
    try:
        dt = datetime.fromisoformat(s)
    except ValueError:
        return None
    if dt.tzinfo is None:
        dt = dt.replace(tzinfo=timezone.utc)
    return "prefix_iso", dt.timestamp()
