"""Reading and writing trials: CSV with ``name [unit]`` headers, Parquet, and two real data sets.

Formats
-------
``csv``
    Comma-, semicolon- or tab-separated text (a decimal comma with the latter two;
    :mod:`shipid.io.csv_dialect`, recorded in ``meta["csv_dialect"]``), UTF-8
    (a BOM is accepted; cp1252 is tried when the bytes are not UTF-8), ``\\n``,
    ``\\r\\n`` or ``\\r`` line ends. The first line is the header; every cell is
    ``name [unit]`` (the convention of the Esso Osaka 3 m data set and of what shipid
    writes), ``name (unit)`` (``Time (ms)``, ``Heading (deg)``) or ``name_unit``
    (``speed_kn``; :func:`shipid.io.units.split_header`). A header cell *without* a unit
    is an error unless the unit is supplied by a format profile or by the channel map
    (``'psi=heading[deg]'``). Parsed by pyarrow's CSV reader, with a cell-by-cell
    check where it has any doubt (:mod:`shipid.io.csv_read`). Each following line is one data
    row (row 1 is the first line after the header); blank lines at the very end of
    the file are ignored, any other line must have as many fields as the header.
    Empty cells are missing values (see :mod:`shipid.io.validate`).
``parquet``
    One numeric column per channel; units in the schema metadata key
    ``shipid.units`` (JSON ``{name: unit}``), or in column names ``name [unit]``.
    :func:`write_trial` also stores the trial metadata under ``shipid.meta``.
``esso``
    A CSV of the Esso Osaka 3 m free-running data set (Wakita et al. 2022): the
    columns are mapped onto standard names (:data:`PROFILES`). Chosen automatically
    for a ``.csv`` whose header holds ``x_position_mid`` and ``psi_hat``.
``kvlcc2``
    An HSVA KVLCC2 ``.dat`` zig-zag (SIMMAN 2008): four header lines (cp1252) and
    twelve whitespace-separated columns in the order of ``shared/data/README.md``.
    Heading, yaw rate, rudder and the 8th column (read as roll angle ``phi``; the
    README says "probably", so the assumption is recorded in ``meta``) are in
    degrees. Body velocities are derived from the earth-fixed ones:
    ``u = ẋ cos ψ + ẏ sin ψ``, ``v = −ẋ sin ψ + ẏ cos ψ`` (Fossen 1994, eq. 2.18 with
    z down). Chosen automatically for ``.dat`` files.
``nmea``
    An NMEA 0183 log (:mod:`shipid.io.nmea`): ``.nmea``, or a ``.txt``/``.log``
    whose first lines are sentences (``$``, ``!``, a tag block ``\\`` or a time
    stamp and ``$``); interpolated onto a uniform grid; ``skip_bad`` skips corrupt
    sentences.

Channel maps and problems
-------------------------
``channel_map={"x": "x_position_mid", "u": "u_velo"}`` (or the string
``'x=x_position_mid,u=u_velo'``, see :func:`parse_channel_map`) renames columns onto
standard names (:data:`shipid.io.trial.CHANNELS`); a column keeps its own name when
nothing maps it. A standard channel's unit must have the dimension of its SI unit
(``psi [m]`` is an error). Every problem of a file's columns, and every channel the
caller requires and the file lacks (with the columns that could give it), is reported
in one :class:`~shipid.errors.InputError` (:mod:`shipid.io.mapping`); a value problem
(a bad cell, time not increasing) names its row.
"""

from __future__ import annotations

import io as _io
import json
import os
import re
from pathlib import Path
from typing import Iterable, Mapping

import numpy as np

from shipid.io.csv_read import cell_value, read_csv_table
from shipid.io.mapping import Problems, check_required, described, map_columns, parse_channel_map, speed_from_sog
from shipid.io.nmea import looks_like_nmea, read_nmea
from shipid.io.table import RawTable, split_lines
from shipid.io.trial import Trial
from shipid.io.units import from_si, split_header
from shipid.io.validate import validate_arrays
from shipid.errors import InputError, ShipidError
from shipid.outputs import atomic_write, jsonable

FORMATS = ("csv", "parquet", "esso", "kvlcc2", "nmea")

#: Column maps of the named format profiles: standard name -> column name in the file.
PROFILES: dict[str, dict[str, str]] = {
    "esso": {
        "t": "t",
        "x": "x_position_mid", "y": "y_position_mid", "psi": "psi_hat",
        "u": "u_velo", "v": "vm_velo", "r": "r_angvelo",
        "n": "n_prop", "delta": "delta_rudder",
        "wind_speed_rel": "wind_velo_relative_mid", "wind_dir_rel": "wind_dir_relative_mid",
        "wind_speed": "wind_velo_true", "wind_dir": "wind_dir_true",
    },
    "kvlcc2": {
        "t": "t", "x": "x0", "y": "y0", "psi": "psi", "x_dot": "dx0/dt", "y_dot": "dy0/dt",
        "r": "r", "phi": "col8", "delta": "delta", "n": "n", "thrust": "thrust", "torque": "torque",
    },
}

#: Column names and units of the HSVA KVLCC2 ``.dat`` files (shared/data/README.md).
KVLCC2_COLUMNS: list[tuple[str, str]] = [
    ("t", "s"), ("x0", "m"), ("y0", "m"), ("psi", "deg"), ("dx0/dt", "m/s"), ("dy0/dt", "m/s"),
    ("r", "deg/s"), ("col8", "deg"), ("delta", "deg"), ("n", "rps"), ("thrust", "N"), ("torque", "N*m"),
]
KVLCC2_HEADER_LINES = 4

#: Folders of the Esso Osaka data set; a run's folder names its manoeuvre.
ESSO_MANOEUVRES = ("turning", "zigzag", "random", "berthing")

_EXTENSIONS = {".csv": "csv", ".txt": "csv", ".parquet": "parquet", ".pq": "parquet", ".dat": "kvlcc2",
               ".nmea": "nmea", ".log": "csv"}  # .txt/.log: NMEA when the content looks like it (shipid.io.nmea)


# --------------------------------------------------------------------------- reading
def read_trial(
    path: str | os.PathLike,
    *,
    fmt: str | None = None,
    channel_map: Mapping[str, str] | str | None = None,
    required: Iterable[str] | None = None,
    interpolate_gaps: float | None = None,
    resample: float | None = None,
    vessel: str | None = None,
    manoeuvre: str | None = None,
    trim_empty_rows: bool = False,
    method: str | None = None,
    skip_bad: bool = False,
    validate: bool = True,
) -> Trial:
    """Read a trial file, convert it to SI and validate it.

    Parameters
    ----------
    path : path-like
        CSV, Parquet, Esso Osaka CSV or KVLCC2 ``.dat`` file.
    fmt : {"csv", "parquet", "esso", "kvlcc2"}, optional
        Format; by default from the extension (``.csv``, ``.parquet``/``.pq``, ``.dat``),
        and ``esso`` for a CSV whose header has the Esso Osaka columns.
    channel_map : mapping or str, optional
        Standard name -> column name (:func:`parse_channel_map`), applied on top of the
        format profile.
    required : iterable of str, optional
        Channels the caller needs (checked before the values).
    interpolate_gaps : float, optional
        Fill missing values and time gaps up to this many seconds by linear
        interpolation (recorded in ``trial.meta["repairs"]``).
    resample : float, optional
        Resample onto a uniform grid with this step, in seconds.
    vessel, manoeuvre : str, optional
        Stored in ``trial.meta``.
    trim_empty_rows : bool
        Remove rows without any value at the start and the end of the file (recorded).
    method : str, optional
        Name of the method asking for ``required`` (for the message: "required by ...").
    skip_bad : bool
        NMEA logs only: skip corrupt sentences, counted in ``meta["skipped"]``
        (:func:`shipid.io.nmea.read_nmea`).
    validate : bool
        Check the values (:func:`shipid.io.validate.validate_arrays`: finite, time increasing, no gaps).
        ``False`` hands the samples over as the file has them (NaN, repeated or out-of-order times included),
        for a consumer that names and survives such faults itself (the online monitor's fault handler);
        the columns, units and required channels are checked either way.

    Returns
    -------
    Trial
        Channels in SI units; ``meta`` holds ``source``, ``format``, ``profile``,
        ``units_in`` (the units found in the file), ``columns`` (standard name ->
        column) and ``repairs``.

    Raises
    ------
    InputError
        One line: every problem of the columns and every required channel the file lacks
        (``N problems: ...; ...``, with the columns that could give each missing channel and
        a ``--channels`` map to try), else the first value problem with its channel and row.
    """
    label = os.fspath(path)
    p = Path(path)
    if not p.exists():
        raise InputError("no such file", file=label)
    if p.is_dir():
        raise InputError("is a directory, not a trial file", file=label)
    fmt = _resolve_format(p, fmt, label)
    user_map = parse_channel_map(channel_map)
    try:
        if fmt == "parquet":
            table = _read_parquet(p, label)
        elif fmt == "kvlcc2":
            table = _read_kvlcc2(p, label)
        elif fmt == "nmea":
            table = read_nmea(p, label, skip_bad=skip_bad, resample=resample, interpolate_gaps=interpolate_gaps)
            resample = None  # already on its uniform grid
        else:
            table = read_csv_table(p, label)
    except InputError:
        raise
    except (OSError, MemoryError) as err:
        raise InputError(f"cannot read: {err.strerror or err}", file=label) from None

    profile = None
    if fmt in PROFILES:
        profile = fmt
    elif fmt == "csv" and {"x_position_mid", "psi_hat"} <= set(table.names):
        profile = "esso"
    if profile is not None:
        missing = [c for c in PROFILES[profile].values() if c not in table.names]
        if missing:
            raise InputError(f"not in the {profile} format: column '{missing[0]}' missing "
                             f"(has: {', '.join(table.names)})", file=label)
    problems = Problems(label)
    t, chans, units, units_in, columns, spare = map_columns(
        table, PROFILES.get(profile), set(PROFILES[profile].values()) if profile else set(), user_map, label,
        problems)

    if profile == "kvlcc2" and {"psi", "x_dot", "y_dot"} <= set(chans):
        c, s = np.cos(chans["psi"]), np.sin(chans["psi"])
        chans["u"] = chans["x_dot"] * c + chans["y_dot"] * s
        chans["v"] = -chans["x_dot"] * s + chans["y_dot"] * c
        units["u"] = units["v"] = "m/s"
        table.meta["derived"] = {"u": "x_dot*cos(psi) + y_dot*sin(psi)",
                                 "v": "-x_dot*sin(psi) + y_dot*cos(psi)"}
    derived = speed_from_sog(chans, units, required, method)
    if derived:
        table.meta["derived"] = {**table.meta.get("derived", {}), "U": "sog (speed over ground)"}
    check_required(chans, required, method, spare, problems)
    problems.raise_all(has=described(table, columns))

    if validate:
        t, chans, repairs = validate_arrays(
            t, chans, file=label, rows=table.rows, units=units, required=required,
            interpolate_gaps=interpolate_gaps, resample=resample, trim_empty_rows=trim_empty_rows,
            method=method, copy=False)
    else:
        t, repairs = np.asarray(t, dtype=float), []
        chans = {k: np.asarray(v, dtype=float) for k, v in chans.items()}
    repairs = derived + repairs

    meta: dict = {"source": label, "format": fmt, "profile": profile}
    meta.update(table.meta)
    if vessel is not None:
        meta["vessel"] = vessel
    if manoeuvre is not None:
        meta["manoeuvre"] = manoeuvre
    elif profile == "esso" and p.parent.name in ESSO_MANOEUVRES:
        meta["manoeuvre"] = p.parent.name  # the data set's folders name the manoeuvre
    meta["units_in"] = units_in
    meta["columns"] = columns
    meta["repairs"] = list(table.meta.get("repairs", [])) + repairs
    return Trial(t, chans, units, meta)


def _resolve_format(p: Path, fmt: str | None, label: str) -> str:
    if fmt is not None:
        f = str(fmt).lower()
        if f not in FORMATS:
            raise InputError(f"unknown format '{fmt}' (choose from {', '.join(FORMATS)})", file=label)
        return f
    ext = p.suffix.lower()
    if ext in (".txt", ".log"):
        try:
            with open(p, "rb") as fh:
                if looks_like_nmea(fh.read(4096)):
                    return "nmea"
        except OSError:
            pass
    if ext in _EXTENSIONS:
        return _EXTENSIONS[ext]
    raise InputError(f"cannot tell the format from the extension '{p.suffix}' "
                     f"(use .csv or .parquet, or --format {'|'.join(FORMATS)})", file=label)


# --- KVLCC2 HSVA .dat ----------------------------------------------------------------------
def _read_kvlcc2(p: Path, label: str) -> RawTable:
    raw = p.read_bytes()
    if not raw.strip():
        raise InputError("empty file", file=label)
    if raw.startswith(b"PAR1") or b"\x00" in raw[:65536]:
        raise InputError("binary content, not an HSVA .dat text file", file=label)
    text = raw.decode("cp1252", errors="replace")
    lines = split_lines(text, label)
    h = KVLCC2_HEADER_LINES
    if len(lines) <= h:
        raise InputError(f"header only: an HSVA .dat file has {h} header lines and then data", file=label)
    ncol = len(KVLCC2_COLUMNS)
    data = np.empty((len(lines) - h, ncol), dtype=np.float64)
    for i, line in enumerate(lines[h:]):
        fields = line.split()
        if len(fields) != ncol:
            raise InputError(f"has {len(fields)} fields, an HSVA KVLCC2 .dat row has {ncol} "
                             f"(line {i + h + 1})", file=label, row=i + 1)
        try:
            data[i] = [float(c) for c in fields]
        except ValueError:
            data[i] = [cell_value(c, label, KVLCC2_COLUMNS[j][0], i + 1) for j, c in enumerate(fields)]
    title = " ".join(lines[2].split())
    facility = {}
    if "HSVA" in lines[0] and "CPMC" in lines[0]:
        # HSVA_SIMMAN_free_running_report.pdf (Cura Hochbaum 2006): the CPMC runs of the large towing tank,
        # 300 m x 18 m x 6 m, "6.0 m water depth, ratio h/T = 13.2 (deep water)"
        facility = {"water_depth": 6.0, "water_depth_source": "HSVA SIMMAN 2008 free running test report: large "
                                                                "towing tank, 6.0 m water depth (h/T 13.2)"}
    meta = {"encoding": "cp1252", **facility,
            "title": " / ".join(" ".join(x.split()) for x in lines[:h] if x.strip()), "manoeuvre": title,
            "assumptions": ["column 8 read as roll angle phi [deg] (shared/data/README.md: 'probably')"],
            "dataset": "kvlcc2_hsva"}
    return RawTable([c for c, _ in KVLCC2_COLUMNS], [u for _, u in KVLCC2_COLUMNS], data,
                  np.arange(1, data.shape[0] + 1), meta)


# --- Parquet ---------------------------------------------------------------------------
def _read_parquet(p: Path, label: str) -> RawTable:
    import pyarrow as pa
    import pyarrow.parquet as pq

    if p.stat().st_size == 0:
        raise InputError("empty file", file=label)
    try:
        table = pq.read_table(p)
    except (pa.ArrowException, OSError, ValueError) as err:
        msg = " ".join(str(err).split())
        msg = re.sub(r"^Could not open Parquet input source '[^']*': ", "", msg).split(". ")[0].rstrip(".")
        raise InputError(f"not a readable Parquet file ({msg[:100]})", file=label) from None
    md = table.schema.metadata or {}
    try:
        units_md = json.loads(md.get(b"shipid.units", b"{}").decode("utf-8"))
        meta_md = json.loads(md.get(b"shipid.meta", b"{}").decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError):
        raise InputError("corrupt shipid metadata in the Parquet schema", file=label) from None
    if table.num_columns == 0:
        raise InputError("no columns", file=label)
    if table.num_rows == 0:
        raise InputError("header only, no data rows", file=label)
    names, units, cols = [], [], []
    for j, col in enumerate(table.column_names):
        try:
            # a unit in the schema metadata keeps the column name whole ('true_N' is not 'true' in N)
            name, unit = (col, units_md[col]) if col in units_md and "[" not in col else split_header(col)
        except ValueError as err:
            raise InputError(str(err), file=label) from None
        if name in names:
            raise InputError(f"duplicate column name (columns {names.index(name) + 1} and {j + 1})",
                             file=label, channel=name)
        arr = table.column(j)
        typ = arr.type
        if pa.types.is_integer(typ) or pa.types.is_floating(typ) or pa.types.is_boolean(typ) \
                or pa.types.is_decimal(typ):
            values = np.array(arr.cast(pa.float64()).to_numpy(zero_copy_only=False), dtype=np.float64)
        elif pa.types.is_string(typ) or pa.types.is_large_string(typ):
            strs = arr.to_pylist()
            values = np.array([np.nan if s is None else cell_value(s, label, name, i + 1)
                               for i, s in enumerate(strs)], dtype=np.float64)
        else:
            raise InputError(f"column of type {typ} is not numeric", file=label, channel=name)
        names.append(name)
        units.append(unit)
        cols.append(values)
    meta = {k: v for k, v in meta_md.items() if k not in ("source", "format", "profile", "units_in", "columns")}
    return RawTable(names, units, np.column_stack(cols), np.arange(1, table.num_rows + 1), meta)


# --------------------------------------------------------------------------- writing
def write_trial(trial: Trial, path: str | os.PathLike, *, units: Mapping[str, str] | None = None,
                force: bool = False, fmt: str | None = None) -> Path:
    """Write a trial as CSV (``name [unit]`` headers) or Parquet, atomically.

    Parameters
    ----------
    trial : Trial
    path : path-like
        ``.csv`` or ``.parquet``/``.pq`` (or give ``fmt``).
    units : mapping, optional
        Units to write channels in instead of SI, e.g. ``{"psi": "deg", "n": "rpm"}``.
    force : bool
        Overwrite an existing file; without it an existing file is an error and nothing
        is written.
    fmt : {"csv", "parquet"}, optional

    Returns
    -------
    Path
        The path written.
    """
    p = Path(path)
    fmt = (fmt or _EXTENSIONS.get(p.suffix.lower(), "")).lower()
    if fmt not in ("csv", "parquet"):
        raise ShipidError(f"{os.fspath(path)}: cannot write format '{fmt or p.suffix}' (use .csv or .parquet)")
    units = dict(units or {})
    unknown = [k for k in units if k != "t" and k not in trial.channels]
    if unknown:
        raise InputError(f"no such channel to write in '{units[unknown[0]]}'", channel=unknown[0])
    cols: dict[str, np.ndarray] = {}
    col_units: dict[str, str] = {}
    t_unit = units.get("t", "s")
    cols["t"] = from_si(trial.t, t_unit, channel="t", si="s")
    col_units["t"] = t_unit
    for name, values in trial.channels.items():
        si = trial.units.get(name, "-")
        u = units.get(name, si)
        cols[name] = from_si(values, u, channel=name, si=si) if u != si else np.asarray(values, dtype=np.float64)
        col_units[name] = u
    if fmt == "csv":
        return atomic_write(p, lambda tmp: _write_csv(tmp, cols, col_units), force=force)
    return atomic_write(p, lambda tmp: _write_parquet(tmp, cols, col_units, trial.meta), force=force)


#: Trial metadata a method reads from a file (Parquet keeps it; CSV cannot): the DGPS antenna ``x_D, y_D`` and
#: speed-log ``y_S`` positions of Yoon & Rhee (2003) eq. 8, in body axes, m.
SENSOR_META = ("x_D", "y_D", "y_S")


def sensor_meta_lost(trial: Trial, path) -> dict[str, float]:
    """The sensor positions (:data:`SENSOR_META`) of ``trial`` that writing it to ``path`` loses: all of those the
    trial states when ``path`` is a CSV file (CSV has no place for metadata), none for Parquet."""
    if Path(path).suffix.lower() != ".csv":
        return {}
    return {k: float(trial.meta[k]) for k in SENSOR_META if k in trial.meta}


def _write_csv(tmp: Path, cols: dict[str, np.ndarray], col_units: dict[str, str]) -> None:
    buf = _io.StringIO()
    buf.write(",".join(f"{k} [{col_units[k]}]" for k in cols) + "\n")
    matrix = np.column_stack(list(cols.values()))
    for row in matrix.tolist():
        buf.write(",".join(map(repr, row)) + "\n")
    tmp.write_text(buf.getvalue(), encoding="utf-8")


def _write_parquet(tmp: Path, cols: dict[str, np.ndarray], col_units: dict[str, str], meta) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.table({k: pa.array(v, type=pa.float64()) for k, v in cols.items()})
    md = {b"shipid.units": json.dumps(col_units).encode("utf-8"),
          b"shipid.meta": json.dumps(jsonable(dict(meta))).encode("utf-8")}
    pq.write_table(table.replace_schema_metadata(md), tmp)
