"""NMEA 0183 sentences of a live IMU + rudder feed: parsed into samples, and written for a replay.

The quantities of the roll model of Linder et al. (2015) (roll rate ``p``, sway acceleration ``a_s``, yaw
rate ``r``, rudder ``delta``; SI units, the conventions of :mod:`shipid.io.nmea`) come from:

* ``$--XDR`` transducer quadruplets ``type,value,unit,name``; names (any case) ``ROLLRATE`` / ``RATEX`` /
  ``GYROX`` -> p, ``ACCY`` / ``ACCELY`` -> a_s, ``YAWRATE`` / ``RATEZ`` / ``GYROZ`` -> r, ``RUDDER`` -> delta;
  units ``D`` degrees (per second), ``R`` radians (per second), ``M`` m/s^2, ``G`` standard gravities;
  other quadruplets are ignored;
* ``$--ROT`` rate of turn (deg/min, status A) -> r; ``$--RSA`` starboard rudder (deg, status A) -> delta;
* ``$VNYMR``, the ASCII output of VectorNav inertial sensors (yaw, pitch, roll [deg], magnetic [gauss],
  acceleration [m/s^2], angular rate [rad/s], body axes x forward, y starboard, z down): gyro x -> p,
  acceleration y -> a_s, gyro z -> r.

A sentence's time is the ``c:`` field of its tag block (``\\c:<seconds>*hh\\``, IEC 61162-450 / NMEA 4.10),
else the receive time. :class:`Assembler` joins the channels of one time into a sample; a sample still
missing a channel when a newer one is ``horizon`` seconds ahead is passed on with NaN there (lost
sentences, bridged downstream). A line that cannot be used raises :class:`~shipid.io.nmea_fields.BadLine`.
"""

from __future__ import annotations

import math
import re

from shipid.io.nmea_fields import MAX_ROT_DEG_MIN, MAX_RUDDER_DEG, BadLine, tag_time

MAX_LINE = 200                       # characters; a longer line is bad (NMEA allows 82, tag block included ~ 160)
CHANNELS = ("p", "a_s", "r", "delta")
_XDR_NAMES = {"ROLLRATE": "p", "ROLL_RATE": "p", "RATEX": "p", "GYROX": "p", "ACCY": "a_s", "ACC_Y": "a_s",
              "ACCELY": "a_s", "YAWRATE": "r", "YAW_RATE": "r", "RATEZ": "r", "GYROZ": "r", "RUDDER": "delta"}
_ANGLE_UNITS = {"D": math.pi / 180.0, "R": 1.0}
_ACC_UNITS = {"M": 1.0, "G": 9.80665}
_LIMITS = {"p": 10.0, "a_s": 200.0, "r": 10.0, "delta": math.radians(MAX_RUDDER_DEG)}
_TAG = re.compile(r"^\\([^\\]*)\\")
_SENTENCE = re.compile(r"^[$]([A-Z0-9]{5})((?:,[^,*$!\\]*)*)\*([0-9A-Fa-f]{2})$")


def checksum(body: str) -> str:
    """Two hex digits: XOR of the characters between ``$`` and ``*``."""
    c = 0
    for ch in body:
        c ^= ord(ch)
    return f"{c:02X}"


def _num(s: str, stype: str, what: str) -> float | None:
    if s == "":
        return None
    try:
        v = float(s)
    except ValueError:
        raise BadLine(stype, f"{what} '{s[:20]}' is not a number", what) from None
    if not math.isfinite(v):
        raise BadLine(stype, f"{what} is not finite", what)
    return v


def _put(out: dict, ch: str, v: float, stype: str) -> None:
    if abs(v) > _LIMITS[ch]:
        raise BadLine(stype, f"{ch} = {v:.6g} out of range (|{ch}| <= {_LIMITS[ch]:.6g})", ch)
    out[ch] = v


def parse_line(line: str) -> tuple[float | None, dict]:
    """``(tag time or None, {channel: value})`` of one line; ``{}`` for a valid sentence of another kind."""
    s = line.strip()
    if len(s) > MAX_LINE:
        raise BadLine("line", f"line of {len(s)} characters (at most {MAX_LINE})")
    t = None
    m = _TAG.match(s)
    if m:
        t = tag_time(m.group(1))
        s = s[m.end():]
    sm = _SENTENCE.match(s)
    if sm is None:
        raise BadLine("line", "not an NMEA sentence with a checksum")
    address, fields, cs = sm.group(1), sm.group(2)[1:].split(","), sm.group(3).upper()
    if checksum(s[1:s.rindex("*")]) != cs:
        raise BadLine(address[2:], "checksum does not match")
    stype = address[2:] if address != "VNYMR" else "VNYMR"
    out: dict = {}
    if stype == "XDR":
        if len(fields) % 4:
            raise BadLine(stype, f"{len(fields)} fields, not quadruplets (type, value, unit, name)")
        for i in range(0, len(fields), 4):
            _, val, unit, name = fields[i:i + 4]
            ch = _XDR_NAMES.get(name.upper())
            if ch is None:
                continue
            v = _num(val, stype, ch)
            if v is None:
                continue
            scale = (_ACC_UNITS if ch == "a_s" else _ANGLE_UNITS).get(unit.upper())
            if scale is None:
                raise BadLine(stype, f"unit '{unit[:4]}' of {name[:16]} not known", ch)
            _put(out, ch, v * scale, stype)
    elif stype == "ROT":
        if len(fields) < 2:
            raise BadLine(stype, "too few fields")
        v = _num(fields[0], stype, "r")
        if fields[1] == "A" and v is not None:
            if abs(v) > MAX_ROT_DEG_MIN:
                raise BadLine(stype, f"rate of turn {v:g} deg/min out of range", "r")
            out["r"] = math.radians(v) / 60.0
    elif stype == "RSA":
        if len(fields) < 2:
            raise BadLine(stype, "too few fields")
        v = _num(fields[0], stype, "delta")
        if fields[1] == "A" and v is not None:
            _put(out, "delta", math.radians(v), stype)
    elif stype == "VNYMR":
        if len(fields) != 12:
            raise BadLine(stype, f"{len(fields)} fields, not 12")
        vals = [_num(f, stype, "VNYMR") for f in fields]
        for ch, j in (("p", 9), ("a_s", 7), ("r", 11)):
            if vals[j] is not None:
                _put(out, ch, vals[j], stype)
    return t, out


class Assembler:
    """Channels of one time joined into samples ``(t, (p, a_s, r, delta))`` (see the module docstring).

    Without tag blocks (receive time), a sample is made at each sentence carrying ``p`` with the latest
    value of the other channels."""

    def __init__(self, horizon: float = 0.5, max_pending: int = 256):
        self.horizon, self.max_pending = float(horizon), int(max_pending)
        self.pending: dict[float, dict] = {}
        self.latest: dict = {}
        self.newest: float | None = None
        self.out: list = []
        self.incomplete = 0

    def add(self, t_tag: float | None, t_recv: float, vals: dict) -> None:
        if not vals:
            return
        if t_tag is None:
            self.latest.update(vals)
            if "p" in vals:
                self.out.append((t_recv, tuple(self.latest.get(c, math.nan) for c in CHANNELS)))
            return
        d = self.pending.setdefault(t_tag, {})
        d.update(vals)
        if len(d) == 4:
            del self.pending[t_tag]
            self.out.append((t_tag, tuple(d[c] for c in CHANNELS)))
        if self.newest is None or t_tag > self.newest:
            self.newest = t_tag
        if len(self.pending) > self.max_pending or (self.pending and min(self.pending) < self.newest - self.horizon):
            for k in sorted(self.pending):
                if k >= self.newest - self.horizon and len(self.pending) <= self.max_pending:
                    break
                self._expire(k)

    def _expire(self, k: float) -> None:
        d = self.pending.pop(k)
        self.incomplete += 1
        self.out.append((k, tuple(d.get(c, math.nan) for c in CHANNELS)))

    def flush(self) -> None:
        for k in sorted(self.pending):
            self._expire(k)

    def take(self) -> list:
        out, self.out = self.out, []
        return out


def sample_sentences(t: float, p: float, a_s: float, r: float, delta: float, style: str = "exact") -> list[str]:
    """The lines of one sample, each with a tag block carrying ``t``.

    ``style`` "exact": one XDR in SI units (radians per second, m/s^2, radians; 17 significant digits, so the
    receiver gets the same float64 values); "standard": XDR for p (deg/s) and a_s, ROT (deg/min), RSA (deg)."""
    def tagged(body: str) -> str:
        tag = f"c:{t!r}"
        return f"\\{tag}*{checksum(tag)}\\${body}*{checksum(body)}"

    if style == "exact":
        return [tagged(f"IIXDR,G,{p!r},R,ROLLRATE,G,{a_s!r},M,ACCY,G,{r!r},R,YAWRATE,G,{delta!r},R,RUDDER")]
    return [tagged(f"IIXDR,G,{math.degrees(p)!r},D,ROLLRATE,G,{a_s!r},M,ACCY"),
            tagged(f"HEROT,{math.degrees(r) * 60.0!r},A"),
            tagged(f"IIRSA,{math.degrees(delta)!r},A,,")]


__all__ = ["parse_line", "Assembler", "sample_sentences", "checksum", "CHANNELS", "MAX_LINE"]


def estimate_sentences(u: dict) -> list[str]:
    """NMEA lines of one monitor update (its JSON dict): an XDR with the estimates and their std (load mass
    ``LOAD_MASS`` [kg], its centre ``LOAD_ZM`` [m]; nothing when there is no estimate) and, on an alarm, an
    ALR (alarm 001, "LOAD CHANGED")."""
    out = []
    names = (("m", "K", "LOAD_MASS"), ("m_std", "K", "LOAD_MASS_STD"), ("zm_bar", "M", "LOAD_ZM"),
             ("zm_bar_std", "M", "LOAD_ZM_STD"))
    quads = [f"G,{u[k]:.6g},{unit},{name}" for k, unit, name in names if u.get(k) is not None]
    if quads:
        body = "SIXDR," + ",".join(quads)
        out.append(f"${body}*{checksum(body)}")
    if u.get("alarm"):
        body = f"SIALR,,001,A,V,LOAD CHANGED AT T={u.get('change_at') or 0:.0f} S"
        out.append(f"${body}*{checksum(body)}")
    return out


def replay(t, p, a_s, r, delta, send, speed: float = 10.0, style: str = "exact", clock=None, sleep=None) -> int:
    """Send samples as NMEA lines through ``send(lines)`` (one call, one datagram, per sample), paced at
    ``speed`` times the stream's own time (0: as fast as possible). Returns the number of samples sent."""
    import time as _time
    clock = clock or _time.monotonic
    sleep = sleep or _time.sleep
    start = clock()
    t0 = float(t[0]) if len(t) else 0.0
    for i in range(len(t)):
        if speed > 0:
            due = start + (float(t[i]) - t0) / speed
            wait = due - clock()
            if wait > 0:
                sleep(wait)
        send(sample_sentences(float(t[i]), float(p[i]), float(a_s[i]), float(r[i]), float(delta[i]), style))
    return len(t)


__all__ += ["estimate_sentences", "replay"]
