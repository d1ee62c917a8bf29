"""NMEA 0183 sea-trial logs as trials.

A log is a text file of NMEA 0183 sentences, one a line. Sentence parsing and
checksums are done by :mod:`pynmea2`; this module picks a time base, turns the
sentences into channels in SI units, and interpolates every channel onto one
uniform time grid, returning the raw table :func:`shipid.data.io.read_trial`
then maps, checks and validates like any other file.

Sentences (any talker id: GP, GN, HE, II, ...)
------------------------------------------------
=====  ==========================================================================
GGA    position (fix quality 0 = no fix: no position); UTC time of the fix
RMC    position, speed over ground ``sog`` and course ``cog`` (status ``V``: not
       used); UTC time and date
ZDA    UTC time and date only
HDT    true heading -> ``psi``
HDG    magnetic sensor heading; used for ``psi`` only when the log holds no HDT:
       ``psi = heading + deviation + variation`` (east positive). Without a
       variation the true heading is unknown and the channel is ``psi_magnetic``
       (``heading + deviation``).
ROT    rate of turn in **deg/min** (negative: bow turns to port) -> ``r`` [rad/s],
       positive turning to starboard, the z-down convention of the package.
RSA    starboard (or single) rudder sensor -> ``delta``. NMEA: "'-' means bow
       turns to port", so a positive angle turns the ship to starboard (the MMG
       convention of shipid; HSVA logs are the opposite, see realdata).
RPM    shaft (``S``, preferred) or engine (``E``) speed in rev/min, negative
       astern -> ``n`` [rev/s]; only the lowest-numbered shaft (else engine) is
       read, the source is recorded in ``meta["rpm_source"]``.
VTG    ``cog`` (true track) and ``sog``
VHW    speed through water -> ``U`` (the log speed)
MWV    wind: reference ``R`` -> ``wind_speed_rel``, ``wind_dir_rel`` (angle off the
       bow, clockwise, the direction the wind comes from); reference ``T``
       (true/theoretical, still measured off the bow) -> ``wind_speed`` and
       ``wind_angle_true``. Units K/M/N/S (km/h, m/s, knots, mph).
=====  ==========================================================================

With ``sog``, ``cog`` and ``psi`` the reader also derives ``x_dot``, ``y_dot``, ``u``
and ``v`` over ground (``meta["derived"]``; see :func:`_derive`).

Other sentences (GSV, GSA, AIS ``!AIVDM``, proprietary ``$P...``) are counted in
``meta["ignored"]`` and not used. A sentence with status ``V`` (data invalid) is
not used and counted in ``meta["invalid"]``; empty fields are not used.

Positions
---------
Latitude/longitude become north/east ``x``, ``y`` in metres about the first fix
in the local tangent plane (flat earth) at that fix: the points, taken on the
WGS-84 ellipsoid (the GGA altitude is ignored), go to earth-centred earth-fixed
coordinates and are rotated into north-east-down at the origin (Fossen 2011,
eqs. 2.71 and 2.84); the vertical is dropped. Horizontal distances in the plane
are shorter than along the surface by about ``d^3 / (6 R^2)`` (``R ~ 6.37e6 m``):
5e-7 m at 500 m, 5e-4 m at 5 km; ignoring an antenna height ``h`` scales them by
``h / R`` (4 mm at 500 m for h = 50 m). The plain equirectangular formula
``x = R_M dphi``, ``y = R_N cos(phi0) dlambda`` would be off by ``~ d^2 tan(phi0) / (2R)``
(4 cm at 500 m and 60 deg), which is why it is not used.

Time base (one rule per file, recorded in ``meta["time_base"]``)
----------------------------------------------------------------
Chosen from the first line that holds a sentence:

``tag_block``
    NMEA 4 tag block ``\\c:<unix time>*hh\\`` before the sentence (``c:`` in
    seconds; a value above 1e11 is read as milliseconds). Every line must have one.
``prefix_epoch`` / ``prefix_iso``
    A receive time before the ``$``: epoch seconds (``1700000000.25 $GPGGA...``) or
    ISO 8601 (``2026-11-22T02:30:00.250Z,$GPGGA...``; a time without zone is taken
    as UTC). Every line must have one.
``sentence_utc``
    Otherwise the UTC time in RMC, GGA and ZDA. Sentences without a time are
    stamped with the time of the last fix (**coarse**: at most one fix interval
    late; several samples of a channel within one fix keep only the last). Lines
    before the first fix are not used (``meta["before_first_fix"]``); midnight is
    crossed when the time of day falls by more than 12 h.

A time that goes back from one line to the next is a bad line. ``t`` starts at
0 at the start of the grid; ``meta["t0_unix"]`` (when the date is known) and
``meta["t0_utc"]`` give the absolute time.

Grid
----
Each channel is interpolated linearly onto ``t0 + k dt`` over the span every
channel covers (``meta["span"]``); ``dt`` is ``resample`` or the median interval
of the fastest channel (to 1 us). Angles that wrap (``psi``, ``cog``, wind angles) are
unwrapped before the interpolation and wrapped back into [0, 2 pi). Inside a gap
of a channel (an interval longer than :data:`NMEA_GAP_FACTOR` = 2.5 of its median
interval, i.e. two or more sentences lost, and longer than ``interpolate_gaps``) the grid values are NaN, so that the validation of
:mod:`shipid.data.validate` reports it; the gaps are listed in ``meta["gaps"]``
with their line numbers.

Bad lines
---------
A sentence with a checksum must match it; one without (``*hh`` missing) is
accepted, as some loggers strip them, and counted in ``meta["no_checksum"]``. A
failed checksum, an unparsable sentence, a field out of range or a line that
is no sentence is one :class:`~shipid.errors.InputError` naming the file, the
channel (or sentence type) and the line. With ``skip_bad=True`` such lines are
skipped and counted per sentence type in ``meta["skipped"]``; more than
:data:`MAX_BAD_FRACTION` of the sentence lines bad is still an error.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from datetime import date, datetime, time, timezone
from decimal import InvalidOperation
from pathlib import Path

import numpy as np
import pynmea2

from shipid.data.validate import GAP_FACTOR, interpolate
from shipid.errors import InputError

#: An interval longer than this many median intervals of its channel is a gap (NaN on the grid
#: unless ``interpolate_gaps`` covers it). 2.5 bridges one lost sentence (an interval of 2), which
#: is counted in ``meta["span"]["bridged_single_losses"]``, but not two in a row.
NMEA_GAP_FACTOR = 2.5

#: Largest fraction of sentence lines that ``skip_bad`` may skip before the file is refused.
MAX_BAD_FRACTION = 0.05

#: WGS-84 semi-major axis [m] and flattening.
WGS84_A = 6378137.0
WGS84_F = 1.0 / 298.257223563
_E2 = WGS84_F * (2.0 - WGS84_F)

#: Sentence types read; everything else is ignored.
HANDLED = ("GGA", "RMC", "ZDA", "HDT", "HDG", "ROT", "RSA", "RPM", "VTG", "VHW", "MWV")

#: Channels that are compass-like angles in [0, 2 pi): unwrapped for interpolation.
ANGLE_CHANNELS = ("psi", "psi_magnetic", "cog", "wind_dir_rel", "wind_angle_true")

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
_TAG = re.compile(r"^\\([^\\]*)\\")
_ADDRESS = re.compile(r"^[$!]([A-Z0-9]{5})[,*]")
_NMEA_START = re.compile(r"^\s*(\\|[$!][A-Z0-9]{5}[,*]|[0-9][0-9T:.\-+Z ]{5,39}[,;\s]*[$!][A-Z0-9]{5}[,*])")

CHANNEL_UNITS = {
    "x": "m", "y": "m", "psi": "rad", "psi_magnetic": "rad", "r": "rad/s", "delta": "rad", "n": "1/s",
    "sog": "m/s", "cog": "rad", "U": "m/s", "wind_speed_rel": "m/s", "wind_dir_rel": "rad",
    "wind_speed": "m/s", "wind_angle_true": "rad",
    "x_dot": "m/s", "y_dot": "m/s", "u": "m/s", "v": "m/s",
}


def looks_like_nmea(head: bytes) -> bool:
    """True when the first non-empty lines of ``head`` look like NMEA sentences.

    A line counts when it starts with ``$``, ``!``, a tag block ``\\``, or a time
    stamp followed by ``$``/``!`` and a five-character address; the first three
    non-empty lines must all count.
    """
    text = head.decode("latin-1")
    lines = [s for s in re.split(r"\r\n|\r|\n", text) if s.strip()][:3]
    return bool(lines) and all(_NMEA_START.match(s) for s in lines)


# --------------------------------------------------------------------------- reading
@dataclass
class _Samples:
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


class _Bad(Exception):
    def __init__(self, kind: str, message: str, channel: str | None = None):
        super().__init__(message)
        self.kind = kind
        self.message = message
        self.channel = channel


def _num(msg, attr: str, kind: str, channel: str | None) -> float | None:
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
        raise _Bad(kind, f"field '{attr}' is not a number: '{str(raw)[:20]}'", channel) from None
    if not math.isfinite(value):
        raise _Bad(kind, f"field '{attr}' is not finite", channel)
    return value


def _field(msg, attr: str) -> str:
    try:
        return str(msg.data[[f[1] for f in msg.fields].index(attr)]).strip()
    except (ValueError, IndexError):
        return ""


def _in_range(value: float, lo: float, hi: float, kind: str, what: str, channel: str | None) -> float:
    if not lo <= value <= hi:
        raise _Bad(kind, f"{what} {value:g} out of range [{lo:g}, {hi:g}]", channel)
    return value


def _latlon(msg, kind: str) -> tuple[float, float] | None:
    lat, lat_dir = _field(msg, "lat"), _field(msg, "lat_dir")
    lon, lon_dir = _field(msg, "lon"), _field(msg, "lon_dir")
    if not lat or not lon:
        return None
    try:
        lat_d, lat_m = float(lat[:2]), float(lat[2:])
        lon_d, lon_m = float(lon[:3]), float(lon[3:])
    except ValueError:
        raise _Bad(kind, f"position '{lat},{lon}' is not ddmm.mmm,dddmm.mmm", "x") from None
    if lat_dir not in ("N", "S") or lon_dir not in ("E", "W"):
        raise _Bad(kind, f"hemisphere '{lat_dir}'/'{lon_dir}' is not N/S and E/W", "x")
    if not (0 <= lat_m < 60 and 0 <= lon_m < 60 and 0 <= lat_d <= 90 and 0 <= lon_d <= 180):
        raise _Bad(kind, f"position '{lat},{lon}' out of range", "x")
    phi = (lat_d + lat_m / 60.0) * (-1 if lat_dir == "S" else 1)
    lam = (lon_d + lon_m / 60.0) * (-1 if lon_dir == "W" else 1)
    if abs(phi) > 90 or abs(lam) > 180:
        raise _Bad(kind, f"position {phi:g}, {lam:g} deg out of range", "x")
    return phi, lam


def _time_of_day(msg) -> float | None:
    ts = _field(msg, "timestamp")
    if not ts:
        return None
    if not re.fullmatch(r"\d{6}(\.\d+)?", ts):
        raise _Bad(msg.sentence_type, f"UTC time '{ts[:12]}' is not hhmmss.ss", "t")
    try:
        tod = msg.timestamp
    except (ValueError, TypeError, IndexError):
        raise _Bad(msg.sentence_type, f"UTC time '{ts[:12]}' is not hhmmss.ss", "t") from None
    if not isinstance(tod, time):
        raise _Bad(msg.sentence_type, f"UTC time '{ts[:12]}' is not hhmmss.ss", "t")
    return tod.hour * 3600 + tod.minute * 60 + tod.second + tod.microsecond * 1e-6


def _sentence_date(msg) -> date | None:
    try:
        if msg.sentence_type == "RMC" and _field(msg, "datestamp"):
            # pynmea2 hands back the raw text when it cannot convert, and strptime reads
            # '2211' as 2 Feb 2011: insist on ddmmyy
            d = msg.datestamp
            if not re.fullmatch(r"\d{6}", _field(msg, "datestamp")) or not isinstance(d, date):
                raise ValueError
            return d
        if msg.sentence_type == "ZDA" and _field(msg, "year"):
            return date(int(msg.year), int(msg.month), int(msg.day))
    except (ValueError, TypeError):
        raise _Bad(msg.sentence_type, "date is not ddmmyy or out of range", "t") from None
    return None


def _values(msg, stype: str, out: dict, counts: dict) -> None:
    """Channel values of one sentence (SI units) into ``out``: name -> value."""
    def invalid() -> None:
        counts["invalid"][stype] = counts["invalid"].get(stype, 0) + 1

    if stype in ("GGA", "RMC"):
        if stype == "GGA":
            q = _field(msg, "gps_qual")
            if q in ("", "0"):
                invalid()
                return
        elif _field(msg, "status") != "A":
            invalid()
            return
        pos = _latlon(msg, stype)
        if pos is not None:
            out["lat"], out["lon"] = pos
        if stype == "RMC":
            sog = _num(msg, "spd_over_grnd", stype, "sog")
            cog = _num(msg, "true_course", stype, "cog")
            if sog is not None:
                out["sog"] = _in_range(sog, 0, MAX_SPEED_KN, stype, "speed over ground [kn]", "sog") * _KNOT
            if cog is not None:
                out["cog"] = math.radians(_in_range(cog, 0, 360, stype, "course [deg]", "cog")) % (2 * math.pi)
    elif stype == "VTG":
        cog = _num(msg, "true_track", stype, "cog")
        kn = _num(msg, "spd_over_grnd_kts", stype, "sog")
        kmh = _num(msg, "spd_over_grnd_kmph", stype, "sog")
        if _field(msg, "faa_mode") == "N":
            invalid()
            return
        if cog is not None:
            out["cog"] = math.radians(_in_range(cog, 0, 360, stype, "course [deg]", "cog")) % (2 * math.pi)
        if kn is not None:
            out["sog"] = _in_range(kn, 0, MAX_SPEED_KN, stype, "speed over ground [kn]", "sog") * _KNOT
        elif kmh is not None:
            out["sog"] = _in_range(kmh / 1.852, 0, MAX_SPEED_KN, stype, "speed over ground [kn]", "sog") * _KNOT
    elif stype == "HDT":
        h = _num(msg, "heading", stype, "psi")
        if h is not None:
            out["psi"] = math.radians(_in_range(h, 0, 360, stype, "heading [deg]", "psi")) % (2 * math.pi)
    elif stype == "HDG":
        h = _num(msg, "heading", stype, "psi")
        if h is None:
            return
        _in_range(h, 0, 360, stype, "heading [deg]", "psi")
        dev = _num(msg, "deviation", stype, "psi")
        var = _num(msg, "variation", stype, "psi")
        for val, d, what in ((dev, _field(msg, "dev_dir"), "deviation"), (var, _field(msg, "var_dir"), "variation")):
            if val is not None:
                _in_range(val, 0, 180, stype, f"{what} [deg]", "psi")
                if d not in ("E", "W"):
                    raise _Bad(stype, f"{what} direction '{d}' is not E or W", "psi")
        dev = 0.0 if dev is None else (dev if _field(msg, "dev_dir") == "E" else -dev)
        name = "psi_hdg"
        if var is None:
            name = "psi_magnetic"
            var = 0.0
        else:
            var = var if _field(msg, "var_dir") == "E" else -var
        out[name] = math.radians(h + dev + var) % (2 * math.pi)
    elif stype in _GATED_ANGLES:      # ROT, RSA: one angle (rate) each, valid only with status A
        status, fld, limit, what, channel, per_s = _GATED_ANGLES[stype]
        if _field(msg, status) != "A":
            invalid()
            return
        v = _num(msg, fld, stype, channel)
        if v is not None:
            out[channel] = math.radians(_in_range(v, -limit, limit, stype, what, channel)) / per_s
    elif stype == "RPM":
        if _field(msg, "status") != "A":
            invalid()
            return
        src, num = _field(msg, "source"), _field(msg, "engine_no")
        if src not in ("S", "E"):
            raise _Bad(stype, f"source '{src}' is not S (shaft) or E (engine)", "n")
        rpm = _num(msg, "speed", stype, "n")
        if rpm is not None:
            out[f"rpm:{src}{num}"] = _in_range(rpm, -MAX_RPM, MAX_RPM, stype, "speed [rpm]", "n") / 60.0
    elif stype == "VHW":
        kn = _num(msg, "water_speed_knots", stype, "U")
        kmh = _num(msg, "water_speed_km", stype, "U")
        if kn is not None:
            out["U"] = _in_range(kn, -MAX_SPEED_KN, MAX_SPEED_KN, stype, "water speed [kn]", "U") * _KNOT
        elif kmh is not None:
            out["U"] = _in_range(kmh / 1.852, -MAX_SPEED_KN, MAX_SPEED_KN, stype, "water speed [kn]", "U") * _KNOT
    elif stype == "MWV":
        if _field(msg, "status") != "A":
            invalid()
            return
        ref = _field(msg, "reference")
        if ref not in ("R", "T"):
            raise _Bad(stype, f"reference '{ref}' is not R (relative) or T (true)", "wind_speed")
        sp_name, dir_name = ("wind_speed_rel", "wind_dir_rel") if ref == "R" else ("wind_speed", "wind_angle_true")
        ang = _num(msg, "wind_angle", stype, dir_name)
        sp = _num(msg, "wind_speed", stype, sp_name)
        unit = _field(msg, "wind_speed_units")
        if ang is not None:
            out[dir_name] = math.radians(_in_range(ang, 0, 360, stype, "wind angle [deg]", dir_name)) % (2 * math.pi)
        if sp is not None:
            if unit not in _WIND_UNITS:
                raise _Bad(stype, f"wind speed unit '{unit}' is not K, M, N or S", sp_name)
            out[sp_name] = _in_range(sp * _WIND_UNITS[unit], 0, 100, stype, "wind speed [m/s]", sp_name)


def _tag_time(tag: str) -> float | None:
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
            raise _Bad("tag", f"tag block checksum does not match ({cs.strip()[:4]} != {want:02X})", "t")
    for part in body.split(","):
        if part.startswith("c:"):
            try:
                c = float(part[2:])
            except ValueError:
                raise _Bad("tag", f"tag block time '{part[:20]}' is not a number", "t") from None
            if not math.isfinite(c) or c < 0:
                raise _Bad("tag", f"tag block time '{part[:20]}' out of range", "t")
            return c / 1000.0 if c > 1e11 else c
    return None


def _prefix_time(prefix: str) -> tuple[str, float] | None:
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


def read_nmea(p: Path, label: str, *, skip_bad: bool = False, resample: float | None = None,
              interpolate_gaps: float | None = None):
    """Read an NMEA 0183 log into the raw table of :mod:`shipid.data.io` (see the module docstring).

    Parameters
    ----------
    p : Path
        The log file.
    label : str
        File name for the messages.
    skip_bad : bool
        Skip bad lines (counted in ``meta["skipped"]``) instead of failing at the first.
    resample : float, optional
        Grid step in seconds (default: median interval of the fastest channel).
    interpolate_gaps : float, optional
        Longest gap in a channel, in seconds, bridged by interpolation.

    Returns
    -------
    shipid.data.io._Table
        Columns ``t`` [s] and the channels in SI units on a uniform grid.

    Raises
    ------
    InputError
        One line naming the file, the channel or sentence type, and the line.
    """
    from shipid.data.io import _decode, _lines, _Table

    if resample is not None and not (np.isfinite(resample) and resample > 0):
        raise InputError(f"--resample must be a positive time step in seconds, not {resample}", file=label)
    raw = p.read_bytes()
    if not raw.strip():
        raise InputError("empty file", file=label)
    text, enc = _decode(raw, label, what="NMEA")
    lines = _lines(text, label)

    base: str | None = None
    samples: dict[str, _Samples] = {}
    counts: dict = {"invalid": {}}
    ignored: dict[str, int] = {}
    skipped: dict[str, int] = {}
    first_bad: str | None = None
    n_sentences = 0
    no_checksum = 0
    before_fix = 0
    last_t: float | None = None
    fix_day = 0.0           # sentence_utc: seconds added for midnight crossings
    last_tod: float | None = None
    day0: date | None = None
    talkers: set[str] = set()

    def bad(lineno: int, err: _Bad) -> None:
        nonlocal first_bad
        msg = f"line {lineno}, {err.kind} sentence: {err.message}" if err.kind not in ("line", "tag", "time") \
            else f"line {lineno}: {err.message}"
        if not skip_bad:
            raise InputError(msg, file=label, channel=err.channel or err.kind)
        skipped[err.kind] = skipped.get(err.kind, 0) + 1
        if first_bad is None:
            first_bad = msg

    for lineno, line in enumerate(lines, start=1):
        s = line.strip()
        if not s:
            continue
        n_sentences += 1
        try:
            # -- time from a tag block or a prefix
            t_line = None
            tag_t = None
            m = _TAG.match(s)
            if m:
                tag_t = _tag_time(m.group(1))
                s = s[m.end():]
            i = min((k for k in (s.find("$"), s.find("!")) if k >= 0), default=-1)
            if i < 0:
                raise _Bad("line", f"not an NMEA sentence: '{_show(s)}'", None)
            prefix, body = s[:i], s[i:]
            pref = _prefix_time(prefix) if prefix.strip() else None
            if base is None:
                base = "tag_block" if tag_t is not None else (pref[0] if pref else "sentence_utc")
            if base == "tag_block":
                if tag_t is None:
                    raise _Bad("time", "no tag-block time '\\c:...\\' (the file's time base is the tag block)", "t")
                t_line = tag_t
            elif base.startswith("prefix"):
                if pref is None or pref[0] != base:
                    raise _Bad("time", f"no {base[7:]} receive time before the sentence: '{_show(prefix)}'", "t")
                t_line = pref[1]
            elif prefix.strip():
                raise _Bad("line", f"text before the sentence: '{_show(prefix)}'", None)
            # -- the sentence
            am = _ADDRESS.match(body)
            if am is None:
                raise _Bad("line", f"not an NMEA sentence: '{_show(body)}'", None)
            address = am.group(1)
            stype = address[2:]
            if body[0] == "!" or address.startswith("P") or stype not in HANDLED:
                key = "AIS" if body[0] == "!" else ("proprietary" if address.startswith("P") else stype)
                ignored[key] = ignored.get(key, 0) + 1
                if t_line is not None:
                    last_t = _advance(last_t, t_line)
                continue
            if "*" not in body:
                no_checksum += 1
            try:
                msg = pynmea2.parse(body, check="*" in body)
            except pynmea2.ChecksumError as err:
                raise _Bad(stype, _first_text(err, "checksum does not match"), stype) from None
            except (pynmea2.ParseError, ValueError, TypeError, AttributeError, IndexError) as err:
                raise _Bad(stype, f"unparsable sentence ({_first_text(err, 'could not parse')})", stype) from None
            talkers.add(address[:2])
            vals: dict = {}
            _values(msg, stype, vals, counts)
            # -- sentence time
            if base == "sentence_utc":
                if stype in ("GGA", "RMC", "ZDA"):
                    tod = _time_of_day(msg)
                    d = _sentence_date(msg)
                    if d is not None and day0 is None:
                        day0 = d
                    if tod is not None:
                        if last_tod is not None and tod < last_tod - 43200.0:
                            fix_day += 86400.0
                        t_fix = fix_day + tod
                        if last_t is not None and t_fix < last_t:
                            raise _Bad(stype, f"UTC time goes back by {last_t - t_fix:.6g} s", "t")
                        last_tod = tod
                        last_t = t_fix
                if last_t is None:
                    before_fix += 1
                    continue
                t_s = last_t
            else:
                if last_t is not None and t_line < last_t:
                    raise _Bad("time", f"time goes back by {last_t - t_line:.6g} s", "t")
                last_t = t_line
                t_s = t_line
        except _Bad as err:
            bad(lineno, err)
            continue
        except (ArithmeticError, InvalidOperation, ValueError, TypeError) as err:  # pynmea2 field conversions
            bad(lineno, _Bad("line", f"unparsable ({type(err).__name__})", None))
            continue
        for name, v in vals.items():
            samples.setdefault(name, _Samples()).add(t_s, v, lineno)

    n_bad = sum(skipped.values())
    if n_bad and n_bad > MAX_BAD_FRACTION * n_sentences:
        raise InputError(f"{n_bad} of {n_sentences} lines bad, more than {MAX_BAD_FRACTION:.0%} even with "
                         f"--skip-bad-sentences; first: {first_bad}", file=label)
    chans, meta = _channels(samples, label)
    t0_abs = None
    if base in ("tag_block", "prefix_epoch", "prefix_iso"):
        t0_abs = 0.0
    elif day0 is not None:
        t0_abs = datetime(day0.year, day0.month, day0.day, tzinfo=timezone.utc).timestamp()
    t, data, names, gaps, span = _grid(chans, label, resample, interpolate_gaps)
    derived = _derive(names, data)
    if derived:
        meta["derived"] = derived
    meta.update({
        "encoding": enc,
        "time_base": base,
        "sentences": n_sentences,
        "talkers": sorted(talkers),
        "skipped": skipped,
        "ignored": ignored,
        "no_checksum": no_checksum,
        "invalid": counts["invalid"],
        "gaps": gaps,
        "span": span,
    })
    if base == "sentence_utc":
        meta["time_base_note"] = ("coarse: time from the UTC of RMC/GGA/ZDA; sentences without a time are "
                                  "stamped with the last fix time")
        meta["before_first_fix"] = before_fix
    if t0_abs is not None:
        meta["t0_unix"] = t0_abs + t[0]
        meta["t0_utc"] = datetime.fromtimestamp(t0_abs + t[0], tz=timezone.utc).isoformat()
    elif base == "sentence_utc":
        meta["t0_utc_time_of_day_s"] = float(t[0] % 86400.0)
    cols = ["t"] + names
    units = ["s"] + [CHANNEL_UNITS[n] for n in names]
    matrix = np.column_stack([span["dt"] * np.arange(t.size)] + data)   # exact steps, not t - t[0]
    return _Table(cols, units, matrix, np.arange(1, t.size + 1), meta)


def _derive(names: list[str], data: list[np.ndarray]) -> dict:
    """Earth-fixed and body velocities over ground from ``sog``/``cog`` (and ``psi``), appended in place.

    ``x_dot = sog cos(cog)``, ``y_dot = sog sin(cog)``; with a heading, ``u = x_dot cos psi
    + y_dot sin psi`` and ``v = -x_dot sin psi + y_dot cos psi`` (Fossen 1994, eq. 2.18).
    These are over ground: they equal the velocities through the water only without current.
    """
    col = dict(zip(names, data))
    out = {}
    if "sog" in col and "cog" in col:
        xd, yd = col["sog"] * np.cos(col["cog"]), col["sog"] * np.sin(col["cog"])
        new = {"x_dot": xd, "y_dot": yd}
        out = {"x_dot": "sog*cos(cog)", "y_dot": "sog*sin(cog)"}
        if "psi" in col:
            c, s = np.cos(col["psi"]), np.sin(col["psi"])
            new.update(u=xd * c + yd * s, v=-xd * s + yd * c)
            out.update(u="x_dot*cos(psi) + y_dot*sin(psi) (over ground)",
                       v="-x_dot*sin(psi) + y_dot*cos(psi) (over ground)")
        for k, v in new.items():
            if k not in col:
                names.append(k)
                data.append(v)
    return out


def _first_text(err: Exception, default: str) -> str:
    """The message of a pynmea2 error (its args nest the text in a tuple with the fields)."""
    args = list(err.args)
    while args:
        a = args.pop(0)
        if isinstance(a, str):
            return a
        if isinstance(a, (tuple, list)):
            args = list(a) + args
    return default


def _advance(last_t, t_line):
    return t_line if last_t is None or t_line > last_t else last_t


def _show(s: str) -> str:
    s = s.strip()
    s = s if len(s) <= 30 else s[:27] + "..."
    return s if s.isprintable() else s.encode("unicode_escape").decode("ascii")


def _channels(samples: dict[str, _Samples], label: str):
    """Pick one source per channel; positions to x, y. Returns name -> (t, v, lines) and meta."""
    meta: dict = {}
    out: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}

    def arr(s: _Samples):
        return np.array(s.t, dtype=np.float64), np.array(s.v, dtype=np.float64), np.array(s.line)

    if "lat" in samples:
        t, lat, ln = arr(samples.pop("lat"))
        _, lon, _ = arr(samples.pop("lon"))
        x, y, origin = flat_earth(lat, lon)
        out["x"], out["y"] = (t, x, ln), (t, y, ln)
        meta["origin"] = origin
        meta["position_approximation"] = ("local tangent plane (north-east) at the first fix, WGS-84 ellipsoid, "
                                          "height ignored; plane vs surface distance error ~ d^3/(6 R^2)")
    if "psi" in samples:
        samples.pop("psi_hdg", None)
        meta["psi_source"] = "HDT"
    elif "psi_hdg" in samples:
        samples["psi"] = samples.pop("psi_hdg")
        meta["psi_source"] = "HDG (heading + deviation + variation)"
    rpm = sorted(k for k in samples if k.startswith("rpm:"))
    if rpm:
        shafts = [k for k in rpm if k[4] == "S"] or rpm
        pick = min(shafts, key=lambda k: (len(k), k))
        samples["n"] = samples[pick]
        meta["rpm_source"] = ("shaft " if pick[4] == "S" else "engine ") + (pick[5:] or "(no number)")
        for k in rpm:
            samples.pop(k)
    for name, s in samples.items():
        out[name] = arr(s)
    if not out:
        raise InputError(f"no usable sentences ({', '.join(HANDLED)}) in the log", file=label)
    return out, meta


def _ecef(lat_deg, lon_deg):
    phi, lam = np.radians(lat_deg), np.radians(lon_deg)
    n = WGS84_A / np.sqrt(1.0 - _E2 * np.sin(phi) ** 2)
    return n * np.cos(phi) * np.cos(lam), n * np.cos(phi) * np.sin(lam), n * (1.0 - _E2) * np.sin(phi)


def flat_earth(lat_deg, lon_deg, lat0: float | None = None, lon0: float | None = None):
    """North/east metres about ``(lat0, lon0)`` (default: the first point) in the local tangent plane.

    Points on the WGS-84 ellipsoid (height 0) go to earth-centred earth-fixed
    coordinates and are rotated into the north-east-down frame at the origin
    (Fossen 2011, eqs. 2.71 and 2.84); the vertical is dropped. See the module
    docstring for the error bound.

    Returns
    -------
    x, y : ndarray
        North and east in metres.
    origin : dict
        ``{"lat": lat0, "lon": lon0}`` in degrees.
    """
    lat = np.asarray(lat_deg, dtype=np.float64)
    lon = np.asarray(lon_deg, dtype=np.float64)
    lat0 = float(lat.flat[0]) if lat0 is None else float(lat0)
    lon0 = float(lon.flat[0]) if lon0 is None else float(lon0)
    phi0, lam0 = math.radians(lat0), math.radians(lon0)
    x0, y0, z0 = _ecef(np.array(lat0), np.array(lon0))
    xe, ye, ze = _ecef(lat, lon)
    dx, dy, dz = xe - x0, ye - y0, ze - z0
    sp, cp, sl, cl = math.sin(phi0), math.cos(phi0), math.sin(lam0), math.cos(lam0)
    north = -sp * cl * dx - sp * sl * dy + cp * dz
    east = -sl * dx + cl * dy
    return north, east, {"lat": lat0, "lon": lon0}


def flat_earth_inverse(x, y, lat0: float, lon0: float, iterations: int = 6):
    """Latitude and longitude in degrees (on the ellipsoid) of north/east metres ``x``, ``y``.

    The inverse of :func:`flat_earth` by fixed-point iteration on the local radii
    (six iterations reach ~1e-9 m within 10 km).
    """
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    phi0 = math.radians(lat0)
    w = 1.0 - _E2 * math.sin(phi0) ** 2
    r_m = WGS84_A * (1.0 - _E2) / w ** 1.5
    r_n = WGS84_A / math.sqrt(w)
    lat = lat0 + np.degrees(x / r_m)
    lon = lon0 + np.degrees(y / (r_n * math.cos(phi0)))
    for _ in range(iterations):
        xa, ya, _ = flat_earth(lat, lon, lat0, lon0)
        lat = lat + np.degrees((x - xa) / r_m)
        lon = lon + np.degrees((y - ya) / (r_n * math.cos(phi0)))
    return lat, lon


def _grid(chans: dict, label: str, resample: float | None, interpolate_gaps: float | None):
    """Interpolate every channel onto one uniform grid over the common span."""
    usable = {}
    dropped = []
    for name, (t, v, ln) in chans.items():
        if t.size >= 2:
            usable[name] = (t, v, ln)
        else:
            dropped.append(name)
    if not usable:
        raise InputError(f"fewer than two samples in every channel ({', '.join(sorted(chans))})", file=label)
    start = max(t[0] for t, _, _ in usable.values())
    end = min(t[-1] for t, _, _ in usable.values())
    if not end > start:
        raise InputError("the channels do not overlap in time (" +
                         ", ".join(f"{k} {t[0]:.6g}..{t[-1]:.6g} s" for k, (t, _, _) in usable.items()) + ")",
                         file=label)
    med = {k: float(np.median(np.diff(t))) for k, (t, _, _) in usable.items()}
    # default step: median interval of the fastest channel, rounded to 1 us (the differences of
    # unix times near 1.7e9 s carry ~2e-7 s of float64 rounding; no logger stamps finer than 1 us)
    dt = float(resample) if resample is not None else max(round(min(med.values()), 6), 1e-6)
    n = int(math.floor((end - start) / dt * (1 + 1e-12) + 1e-9)) + 1
    if n < 2:
        raise InputError(f"the common span {end - start:.6g} s is shorter than one step of {dt:.6g} s", file=label)
    if n > 50_000_000:
        raise InputError(f"grid of {n} samples is too large (step {dt:.6g} s over {end - start:.6g} s)", file=label)
    tg = start + dt * np.arange(n)
    names, data, gaps, bridged_all = [], [], [], {}
    limit_user = 0.0 if interpolate_gaps is None else float(interpolate_gaps)
    for name in sorted(usable):
        t, v, ln = usable[name]
        y = interpolate(tg, t, v, angle=name in ANGLE_CHANNELS)
        if name in ANGLE_CHANNELS:
            y = np.mod(y, 2 * np.pi)
        step = np.diff(t)
        long = np.flatnonzero((step > NMEA_GAP_FACTOR * med[name]) & (step > limit_user))
        bridged = int(np.count_nonzero((step > GAP_FACTOR * med[name]) & (step <= NMEA_GAP_FACTOR * med[name])))
        if bridged:
            bridged_all[name] = bridged
        for k in long:
            inside = (tg > t[k]) & (tg < t[k + 1])
            y[inside] = np.nan
            if inside.any():
                gaps.append({"channel": name, "from_line": int(ln[k]), "to_line": int(ln[k + 1]),
                             "seconds": float(step[k])})
        names.append(name)
        data.append(y)
    span = {"t_start": start, "t_end": end, "dt": dt, "dropped_single_sample": dropped,
            "bridged_single_losses": bridged_all}
    return tg, data, names, gaps, span
