"""NMEA 0183 sea-trial logs as trials.

A log is a text file of NMEA 0183 sentences, one a line. Sentence parsing and
checksums are done by :mod:`pynmea2`; this module picks a time base, turns the
sentences into channels in SI units, and interpolates every channel onto one
uniform time grid, returning the raw table :func:`shipid.io.files.read_trial`
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
not used and counted in ``meta["invalid"]``; empty fields are not used. The fields of
single sentences are read by :mod:`shipid.io.nmea_fields`.

Positions
---------
Latitude/longitude become north/east ``x``, ``y`` in metres about the first fix in the
local tangent plane at that fix (:func:`shipid.io.geodesy.flat_earth`, which states the
error bounds).

Time base (one rule per file, recorded in ``meta["time_base"]``)
----------------------------------------------------------------
Chosen from the first line that holds a sentence:

``tag_block``
    NMEA 4 tag block ``\\c:<unix time>*hh\\`` before the sentence (``c:`` in
    seconds; a value above 1e11 is read as milliseconds). Every line must have one.
``prefix_epoch`` / ``prefix_iso``
    A receive time before the ``$``: epoch seconds (``1700000000.25 $GPGGA...``) or
    ISO 8601 (``YYYY-MM-DDThh:mm:ss.sssZ,$GPGGA...``; a time without zone is taken
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
:mod:`shipid.io.validate` reports it; the gaps are listed in ``meta["gaps"]``
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
from datetime import date, datetime, timezone
from decimal import InvalidOperation
from pathlib import Path

import numpy as np
import pynmea2

from shipid.io.geodesy import flat_earth, flat_earth_inverse
from shipid.io.nmea_fields import (BadLine, Samples, prefix_time, sentence_date, sentence_values, tag_time,
                                     time_of_day)
from shipid.io.table import RawTable, decode_text, split_lines
from shipid.io.validate import GAP_FACTOR, interpolate
from shipid.errors import InputError

#: An interval longer than this many median intervals of its channel is a gap (NaN on the grid
#: unless ``interpolate_gaps`` covers it). 2.5 bridges one lost sentence (an interval of 2), which
#: is counted in ``meta["span"]["bridged_single_losses"]``, but not two in a row.
NMEA_GAP_FACTOR = 2.5

#: Largest fraction of sentence lines that ``skip_bad`` may skip before the file is refused.
MAX_BAD_FRACTION = 0.05


#: Sentence types read; everything else is ignored.
HANDLED = ("GGA", "RMC", "ZDA", "HDT", "HDG", "ROT", "RSA", "RPM", "VTG", "VHW", "MWV")

#: Channels that are compass-like angles in [0, 2 pi): unwrapped for interpolation.
ANGLE_CHANNELS = ("psi", "psi_magnetic", "cog", "wind_dir_rel", "wind_angle_true")

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
def read_nmea(p: Path, label: str, *, skip_bad: bool = False, resample: float | None = None,
              interpolate_gaps: float | None = None):
    """Read an NMEA 0183 log into the raw table of :mod:`shipid.io.files` (see the module docstring).

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
    shipid.io.table.RawTable
        Columns ``t`` [s] and the channels in SI units on a uniform grid.

    Raises
    ------
    InputError
        One line naming the file, the channel or sentence type, and the line.
    """
    if resample is not None and not (np.isfinite(resample) and resample > 0):
        raise InputError(f"--resample must be a positive time step in seconds, not {resample}", file=label)
    raw = p.read_bytes()
    if not raw.strip():
        raise InputError("empty file", file=label)
    text, enc = decode_text(raw, label, what="NMEA")
    lines = split_lines(text, label)

    base: str | None = None
    samples: dict[str, Samples] = {}
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

    def bad(lineno: int, err: BadLine) -> None:
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
                tag_t = tag_time(m.group(1))
                s = s[m.end():]
            i = min((k for k in (s.find("$"), s.find("!")) if k >= 0), default=-1)
            if i < 0:
                raise BadLine("line", f"not an NMEA sentence: '{_show(s)}'", None)
            prefix, body = s[:i], s[i:]
            pref = prefix_time(prefix) if prefix.strip() else None
            if base is None:
                base = "tag_block" if tag_t is not None else (pref[0] if pref else "sentence_utc")
            if base == "tag_block":
                if tag_t is None:
                    raise BadLine("time", "no tag-block time '\\c:...\\' (the file's time base is the tag block)", "t")
                t_line = tag_t
            elif base.startswith("prefix"):
                if pref is None or pref[0] != base:
                    raise BadLine("time", f"no {base[7:]} receive time before the sentence: '{_show(prefix)}'", "t")
                t_line = pref[1]
            elif prefix.strip():
                raise BadLine("line", f"text before the sentence: '{_show(prefix)}'", None)
            # -- the sentence
            am = _ADDRESS.match(body)
            if am is None:
                raise BadLine("line", f"not an NMEA sentence: '{_show(body)}'", None)
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
                raise BadLine(stype, _first_text(err, "checksum does not match"), stype) from None
            except (pynmea2.ParseError, ValueError, TypeError, AttributeError, IndexError) as err:
                raise BadLine(stype, f"unparsable sentence ({_first_text(err, 'could not parse')})", stype) from None
            talkers.add(address[:2])
            vals: dict = {}
            sentence_values(msg, stype, vals, counts)
            # -- sentence time
            if base == "sentence_utc":
                if stype in ("GGA", "RMC", "ZDA"):
                    tod = time_of_day(msg)
                    d = sentence_date(msg)
                    if d is not None and day0 is None:
                        day0 = d
                    if tod is not None:
                        if last_tod is not None and tod < last_tod - 43200.0:
                            fix_day += 86400.0
                        t_fix = fix_day + tod
                        if last_t is not None and t_fix < last_t:
                            raise BadLine(stype, f"UTC time goes back by {last_t - t_fix:.6g} s", "t")
                        last_tod = tod
                        last_t = t_fix
                if last_t is None:
                    before_fix += 1
                    continue
                t_s = last_t
            else:
                if last_t is not None and t_line < last_t:
                    raise BadLine("time", f"time goes back by {last_t - t_line:.6g} s", "t")
                last_t = t_line
                t_s = t_line
        except BadLine as err:
            bad(lineno, err)
            continue
        except (ArithmeticError, InvalidOperation, ValueError, TypeError) as err:  # pynmea2 field conversions
            bad(lineno, BadLine("line", f"unparsable ({type(err).__name__})", None))
            continue
        for name, v in vals.items():
            samples.setdefault(name, Samples()).add(t_s, v, lineno)

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
    return RawTable(cols, units, matrix, np.arange(1, t.size + 1), meta)


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


def _channels(samples: dict[str, Samples], label: str):
    """Pick one source per channel; positions to x, y. Returns name -> (t, v, lines) and meta."""
    meta: dict = {}
    out: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}

    def arr(s: Samples):
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


__all__ = ["read_nmea", "looks_like_nmea", "flat_earth", "flat_earth_inverse", "NMEA_GAP_FACTOR",
           "MAX_BAD_FRACTION", "HANDLED", "ANGLE_CHANNELS", "CHANNEL_UNITS"]
