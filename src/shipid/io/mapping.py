"""From a file's columns to standard channels: channel maps, units to SI, and every problem in one message.

A reader's :class:`~shipid.io.table.RawTable` holds columns as the file names them, with
the units of its header. :func:`map_columns` renames them onto the standard channels of
:data:`shipid.io.trial.CHANNELS` (a format profile, then the user's channel map), converts
each to SI and checks that a standard channel's unit has the dimension of its SI unit.
It does not stop at the first bad column: every problem of the file (a column without a
unit, an unknown unit, a unit of the wrong dimension, two columns for one channel, no
time, a channel the method requires and the file lacks) is collected, and
:func:`raise_problems` raises them as one :class:`~shipid.errors.InputError` -- one line,
the problems separated by ``; ``, each missing channel with its SI unit and the columns of
the file that could give it, and a ready ``--channels`` map where the column names make
the choice clear (:data:`SYNONYMS`).

Channel maps
------------
``'x=x_position_mid, psi=Heading, U=Speed'`` (:func:`parse_channel_map`): standard name =
column. The column is named as in the header without its unit (``Heading``), or as the
whole header cell (``Heading (deg)``), or with a unit for a column whose header has none
(``psi=heading [deg]``). The same syntax on every command that reads trials
(``--channels``).

Speeds from NMEA
----------------
An NMEA log gives the speed over ground ``sog`` (RMC/VTG) and, with a speed log, the speed
through the water ``U`` (VHW). When a method requires ``U`` and the file has ``sog`` only,
:func:`speed_from_sog` takes ``U = sog`` and records it in ``meta["repairs"]`` (a warning on
the command line): the two differ by the current.
"""

from __future__ import annotations

from typing import Iterable, Mapping

import numpy as np

from shipid.errors import InputError
from shipid.io.table import RawTable
from shipid.io.trial import CHANNELS
from shipid.io.units import parse_unit, split_header, to_si_view

#: Names users give the standard channels (lower case, ``_``/``-`` read as spaces), for the suggestions.
SYNONYMS: dict[str, tuple[str, ...]] = {
    "t": ("time", "timestamp", "elapsed time", "sec", "seconds"),
    "x": ("x", "north", "northing", "x position", "pos x", "xpos", "position x"),
    "y": ("y", "east", "easting", "y position", "pos y", "ypos", "position y"),
    "psi": ("heading", "hdg", "yaw", "yaw angle", "true heading", "heading true"),
    "u": ("surge", "surge speed", "surge velocity", "u velocity"),
    "v": ("sway", "sway speed", "sway velocity", "v velocity"),
    "r": ("yaw rate", "yawrate", "rot", "rate of turn", "turn rate"),
    "U": ("speed", "stw", "log", "log speed", "speed through water", "water speed", "sog", "speed over ground"),
    "delta": ("rudder", "rudder angle", "rudder position"),
    "n": ("shaft", "shaft speed", "rpm", "revs", "propeller", "propeller speed", "prop", "prop rpm", "engine"),
    "p": ("roll rate",), "phi": ("roll", "roll angle", "heel"),
    "x_dot": ("vx", "vn", "north velocity", "velocity north", "x velocity"),
    "y_dot": ("vy", "ve", "east velocity", "velocity east", "y velocity"),
    "a_s": ("acceleration", "accel", "acc", "tangential acceleration"),
    "wind_speed": ("wind speed", "true wind speed"), "wind_dir": ("wind direction", "true wind direction"),
}


def parse_channel_map(text: str | Mapping[str, str] | None) -> dict[str, str]:
    """Parse ``'x=x_position_mid, u=u_velo'`` into ``{"x": "x_position_mid", "u": "u_velo"}``.

    A value may carry a unit, ``'psi=heading [deg]'``, declaring the unit of a column whose
    header has none. A mapping is returned as a plain dict.

    Raises
    ------
    InputError
        For an entry without ``=`` or with an empty side, or a name given twice.
    """
    if text is None:
        return {}
    if isinstance(text, Mapping):
        return {str(k).strip(): str(v).strip() for k, v in text.items()}
    out: dict[str, str] = {}
    for part in str(text).split(","):
        part = part.strip()
        if not part:
            continue
        if "=" not in part:
            raise InputError(f"channel map entry '{part}' is not NAME=COLUMN")
        name, col = (s.strip() for s in part.split("=", 1))
        if not name or not col:
            raise InputError(f"channel map entry '{part}' is not NAME=COLUMN")
        if name in out:
            raise InputError(f"channel map names '{name}' twice")
        out[name] = col
    return out


def _norm(name: str) -> str:
    return " ".join(name.lower().replace("_", " ").replace("-", " ").split())


def score(std: str, column: str) -> int:
    """How well a column name fits a standard channel: 3 the name itself, 2 a synonym, 1 a synonym in it, else 0."""
    if column == std:
        return 3
    c = _norm(column)
    syn = SYNONYMS.get(std, ())
    if c in syn or (c == std.lower() and std.lower() == std):
        return 2
    words = f" {c} "
    return 1 if any(len(s) >= 3 and f" {s} " in words for s in syn) else 0


class Problems:
    """The problems of one file, collected in order, raised together by :meth:`raise_all`."""

    def __init__(self, label: str):
        self.label = label
        self.items: list[InputError] = []
        self.suggest: dict[str, str] = {}      # standard name -> column, for the --channels hint
        self.missing = False                   # a channel is missing: the message lists the file's columns

    def add(self, message: str, *, channel: str | None = None, row: int | None = None) -> None:
        self.items.append(InputError(message, file=self.label, channel=channel, row=row))

    def channels(self) -> set[str]:
        return {p.channel for p in self.items if p.channel is not None}

    def raise_all(self, has: Iterable[str] = ()) -> None:
        """Nothing when there is no problem; the problem itself when one; else one line listing each."""
        if not self.items:
            return
        hint = ""
        if self.suggest:
            hint = "; try --channels '" + ",".join(f"{k}={v}" for k, v in self.suggest.items()) + "'"
        cols = f"; the file has: {', '.join(has)}" if has and self.missing else ""
        if len(self.items) == 1:
            p = self.items[0]
            raise InputError(p.message + cols + hint, file=p.file, channel=p.channel, row=p.row)
        parts = []
        for p in self.items:
            where = ", ".join(x for x in (f"channel '{p.channel}'" if p.channel is not None else "",
                                          f"row {p.row}" if p.row is not None else "") if x)
            parts.append(f"{where}: {p.message}" if where else p.message)
        raise InputError(f"{len(self.items)} problems: " + "; ".join(parts) + cols + hint, file=self.label)


def _resolve(spec: str, names: list[str], cells: list[str] | None) -> tuple[str | None, str | None]:
    """(column name, unit given in the map) of a channel-map value; (None, None) for no such column."""
    s = spec.strip()
    if s in names:
        return s, None
    if cells and s in cells:
        return names[cells.index(s)], None
    name, unit = split_header(s)      # ValueError for bad brackets: the caller reports it
    if name in names:
        return name, unit
    return None, None


def map_columns(table: RawTable, profile_map: Mapping[str, str] | None, profile_cols: set[str],
                user_map: Mapping[str, str], label: str, problems: Problems):
    """Standard channels in SI from a raw table; every problem goes to ``problems`` (nothing raised).

    Returns ``t`` (None without a time column), the channels, their SI units, the units found
    in the file, the column each channel came from, and the columns kept under their own name
    with their SI unit (the candidates for a missing channel).
    """
    names = table.names
    mapping: dict[str, str] = dict(profile_map or {})     # standard name -> column
    map_units: dict[str, str] = {}                         # column -> unit declared in the map
    for std, spec in user_map.items():
        try:
            col_name, col_unit = _resolve(spec, names, table.header_cells)
        except ValueError as err:
            problems.add(f"channel map: {err}", channel=std)
            continue
        if col_name is None:
            problems.add(f"channel map: no column '{spec}' (has: {', '.join(names)})", channel=std)
            continue
        # a user entry replaces any profile entry for the same name or the same column
        mapping = {k: v for k, v in mapping.items() if k != std and v != col_name}
        mapping[std] = col_name
        if col_unit is not None:
            map_units[col_name] = col_unit
    col_to_std: dict[str, str] = {}
    for std, col in mapping.items():
        if col in col_to_std:
            problems.add(f"channel map sends column '{col}' to both '{col_to_std[col]}' and '{std}'")
            continue
        col_to_std[col] = std

    chans: dict[str, np.ndarray] = {}
    units: dict[str, str] = {}
    units_in: dict[str, str] = {}
    columns: dict[str, str] = {}
    spare: dict[str, tuple[str, str]] = {}     # column -> (unit in the file, SI unit): could map to a channel
    t = None
    for j, (col, unit) in enumerate(zip(names, table.units)):
        std = col_to_std.get(col, col)
        if col in map_units:
            try:
                same = unit is None or parse_unit(unit) == parse_unit(map_units[col])
            except InputError:
                same = False
            if not same:
                problems.add(f"channel map gives unit '{map_units[col]}' but the header says '{unit}'", channel=col)
                continue
            unit = map_units[col]
        if unit is None:
            why = "" if col in profile_cols else "; write the header cell as 'name [unit]' or map it as NAME=COLUMN[unit]"
            problems.add(f"no unit in header cell '{col}'{why}", channel=col)
            continue
        if std in chans or (std == "t" and t is not None):
            problems.add(f"two columns give channel '{std}' (rename one with --channels)", channel=std)
            continue
        try:
            si = parse_unit(unit, file=label, channel=col)
        except InputError as err:
            problems.items.append(err)
            continue
        want = CHANNELS.get(std)
        if want is not None and si != want:
            alts = [k for k, v in CHANNELS.items() if v == si]
            also = f" (standard channels in {si}: {', '.join(alts)})" if alts else ""
            problems.add(f"unit '{unit}' is not a unit of {want} as channel '{std}' needs{also}", channel=col)
            spare[col] = (unit, si)
            continue
        values = to_si_view(table.data[:, j], unit)
        units_in[std] = unit
        columns[std] = col
        if std == "t":
            t = values
        else:
            chans[std] = values
            units[std] = si
            if std == col and want is None:
                spare[col] = (unit, si)
    if t is None and "t" not in problems.channels():
        problems.missing = True
        problems.add("no time column 't'; map one with --channels t=COLUMN" + _could_be("t", spare, problems),
                     channel="t")
    elif not chans and not problems.items:
        problems.add("no channels besides time")
    return t, chans, units, units_in, columns, spare


def described(table: RawTable, columns: Mapping[str, str]) -> list[str]:
    """The file's columns for a message: ``Heading [deg]``, or ``t from Time [ms]`` where a map renamed one."""
    std_of = {c: s for s, c in columns.items()}
    out = []
    for col, unit in zip(table.names, table.units):
        u = f" [{unit}]" if unit else ""
        std = std_of.get(col, col)
        out.append(f"{col}{u}" if std == col else f"{std} from {col}{u}")
    return out


def _could_be(std: str, spare: Mapping[str, tuple[str, str]], problems: Problems) -> str:
    """`` (could be column 'Heading' [deg])`` for a missing channel, and the best column into the hint."""
    want = CHANNELS.get(std)
    cands = sorted(((score(std, c), c, u) for c, (u, si) in spare.items() if si == want),
                   key=lambda x: -x[0])
    if not cands:
        return ""
    best = cands[0]
    if best[0] > 0 and best[1] not in problems.suggest.values() and (len(cands) == 1 or cands[1][0] < best[0]):
        problems.suggest[std] = best[1]
    return " (could be " + ", ".join(f"column '{c}' [{u}]" for _, c, u in cands[:4]) + ")"


def check_required(chans: Mapping[str, np.ndarray], required: Iterable[str] | None, method: str | None,
                   spare: Mapping[str, tuple[str, str]], problems: Problems) -> None:
    """A problem for every required channel the file lacks, with its SI unit and the columns that could give it."""
    have = set(chans)
    seen = problems.channels()
    for name in required or ():
        if name == "t" or name in have or name in seen:
            continue
        who = f"required by {method} but missing" if method else "required channel missing"
        unit = CHANNELS.get(name)
        what = f" [{unit}]" if unit else ""
        problems.missing = True
        problems.add(f"{who}{what}{_could_be(name, spare, problems)}", channel=name)


def speed_from_sog(chans: dict, units: dict, required: Iterable[str] | None, method: str | None) -> list[dict]:
    """``U = sog`` when ``U`` is required and the file has only the speed over ground; the repair recorded."""
    if "U" not in (required or ()) or "U" in chans or "sog" not in chans:
        return []
    chans["U"] = chans["sog"]
    units["U"] = "m/s"
    who = f" (required by {method})" if method else ""
    return [{"kind": "derived", "channel": "U",
             "text": f"U, the speed through the water{who}, taken as the speed over ground sog: the file has "
                     "no speed log; they differ by the current"}]


__all__ = ["SYNONYMS", "Problems", "parse_channel_map", "map_columns", "check_required", "speed_from_sog", "described",
           "score"]
