"""CSV text to a :class:`~shipid.io.table.RawTable`: a compiled reader first, the cell-by-cell check after.

The file format is described in :mod:`shipid.io.files`. Reading has two paths that give
the same numbers:

* **fast**: the data rows (the bytes after the header line) are parsed by pyarrow's
  multi-threaded CSV reader into float64 columns (``pyarrow.csv``; fast_float parsing,
  correctly rounded as Python's ``float()`` is, so the same doubles). It is kept only when
  every row was parsed with the header's field count: an empty cell is the only value it
  may read as missing; any other cell it cannot parse (text, ``1_0``, a blank cell of
  spaces, ``NA``), a row with another field count, a blank line or a quoted file make it
  give up, and
* **checked**: the lines are split and every cell converted with ``float()``; the first bad
  row is reported with the file, the channel and the row (one
  :class:`~shipid.errors.InputError`).

So a good file costs about one ``pandas.read_csv`` of it (``benchmarks/bench_read.py``), and
a bad one the careful path's time, with the same one-line messages as before. A file under
:data:`FAST_MIN_BYTES` is read by the checked path alone unless pyarrow is loaded already (importing
it would cost more than it saves). The columns
come back as one float64 ``(n_rows, n_cols)`` array (Fortran order from the fast path, so that
each column is a contiguous view).
"""

from __future__ import annotations

import csv
import re
import sys
from pathlib import Path

import numpy as np

from shipid.errors import InputError
from shipid.io.csv_dialect import detect_dialect
from shipid.io.table import RawTable, decode_text, split_lines
from shipid.io.units import split_header

_NUMBER_LIKE = re.compile(r"^\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*$")
#: Lines whose characters are checked for control characters before parsing.
CHECK_LINES = 200


_CONTROL = re.compile(r"[\x00-\x08\x0a-\x1f]")


def _check_text(lines: list[str], label: str) -> None:
    for i, line in enumerate(lines[:CHECK_LINES]):
        if _CONTROL.search(line):
            raise InputError("binary content (control characters), not CSV text", file=label,
                             row=i if i else None)


def _head(p: Path, lines: int) -> tuple[bytes, bool]:
    """The first bytes of the file, through its first ``lines`` line ends (or all of it); True when all."""
    out = bytearray()
    with open(p, "rb") as fh:
        while True:
            chunk = fh.read(1 << 16)
            out += chunk
            if not chunk:
                return bytes(out), True
            if out.count(b"\n") + out.count(b"\r") > 2 * lines + 2:
                return bytes(out[:_cut(out, lines)]), False


def _cut(buf: bytearray, lines: int) -> int:
    """Offset just after the ``lines``-th line end (CR, LF or CRLF) of ``buf``."""
    i = 0
    for _ in range(lines):
        n, r = buf.find(b"\n", i), buf.find(b"\r", i)
        j = min(x for x in (n, r) if x >= 0) if (n >= 0 or r >= 0) else len(buf)
        i = j + 2 if buf[j:j + 2] == b"\r\n" else j + 1
    return i


def _clean_end(p: Path) -> bool:
    """True when the file ends in one line end at most (no trailing blank lines, which the checked path drops)."""
    with open(p, "rb") as fh:
        fh.seek(0, 2)
        fh.seek(max(0, fh.tell() - 4096))
        tail = fh.read()
    return tail[len(tail.rstrip()):] in (b"", b"\n", b"\r\n", b"\r")


#: Files smaller than this many bytes take the checked path unless pyarrow is loaded already: importing it costs
#: about what the checked path takes for a 1-MB file (``benchmarks/bench_cli_startup.py``), and 26 MiB.
FAST_MIN_BYTES = 1 << 20


#: Bytes of CSV text pyarrow parses per record batch (:func:`_fast`).
BLOCK_BYTES = 1 << 22


def _worth_pyarrow(p: Path) -> bool:
    """True when the fast path pays: a file of :data:`FAST_MIN_BYTES` or more, or pyarrow's reader already loaded."""
    return "pyarrow.csv" in sys.modules or p.stat().st_size >= FAST_MIN_BYTES


def _fast(p: Path, ncol: int, sep: str, decimal: str) -> np.ndarray | None:
    """The data rows parsed by pyarrow's CSV reader from the file, or None when it cannot vouch for every cell.

    One thread, 4-MiB blocks (fewer batches to copy than with 256-KiB ones, about 8 % less CPU; their
    memory released after the read), the blocks copied once into one Fortran-order array (each column
    contiguous): about ``pandas.read_csv``'s CPU time (the file is not held in Python). A blank line inside is a row of missing values to it (``ignore_empty_lines=False``), as
    to the checked path; a file with blank lines at its end is left to the checked path.
    """
    try:
        import pyarrow as pa
        import pyarrow.csv as pacsv
    except ImportError:  # pragma: no cover - pyarrow is a dependency
        return None
    if not _clean_end(p):
        return None
    names = [f"c{j}" for j in range(ncol)]
    pool = pa.default_memory_pool()
    batches = []
    try:
        reader = pacsv.open_csv(
            p,
            read_options=pacsv.ReadOptions(column_names=names, skip_rows=1, block_size=BLOCK_BYTES, use_threads=False),
            parse_options=pacsv.ParseOptions(delimiter=sep, quote_char=False, double_quote=False,
                                             escape_char=False, newlines_in_values=False,
                                             ignore_empty_lines=False),
            convert_options=pacsv.ConvertOptions(column_types={c: pa.float64() for c in names},
                                                 null_values=[""], true_values=[], false_values=[],
                                                 strings_can_be_null=False, decimal_point=decimal,
                                                 check_utf8=False),
            memory_pool=pool)
        for batch in reader:
            if batch.num_columns != ncol:
                return None
            batches.append(batch)
    except (pa.ArrowException, ValueError, OSError):
        return None
    n = sum(b.num_rows for b in batches)
    if n == 0:
        return None
    out = np.empty((n, ncol), dtype=np.float64, order="F")   # each column contiguous
    pos = 0
    for batch in batches:
        k = batch.num_rows
        for j in range(ncol):
            out[pos:pos + k, j] = _values(batch.column(j))
        pos += k
    del batches, reader
    pool.release_unused()        # the blocks' memory back to the system, not kept for the next read
    return out


def _values(arr) -> np.ndarray:
    """A float64 Arrow array as numpy, read from its buffers (``Array.to_numpy`` would import pandas);
    nulls (empty cells) are NaN."""
    validity, data = arr.buffers()[:2]
    n, off = len(arr), arr.offset
    vals = np.frombuffer(data, dtype=np.float64, count=off + n)[off:]
    if arr.null_count:
        valid = np.unpackbits(np.frombuffer(validity, dtype=np.uint8), bitorder="little")[off:off + n]
        vals = np.where(valid.astype(bool), vals, np.nan)
    return vals


def read_csv_table(p: Path, label: str) -> RawTable:
    """Read a CSV trial file into raw columns (names and units from its header), or raise one InputError."""
    head, whole = _head(p, CHECK_LINES + 1)
    raw = head if whole else None
    if whole and not head.strip():
        raise InputError("empty file", file=label)
    text, enc = decode_text(head, label)
    if not whole and enc != "utf-8":            # decided on the whole file, as the careful path does
        raw = p.read_bytes()
        text, enc = decode_text(raw, label)
    lines = split_lines(text, label)
    _check_text(lines, label)
    header_line = lines[0]
    dialect = detect_dialect(header_line, lines[1:], label)
    if dialect.delimiter != "," and raw is None:
        # a decimal comma is decided on every data line
        raw = p.read_bytes()
        text, enc = decode_text(raw, label)
        lines = split_lines(text, label)
        dialect = detect_dialect(header_line, lines[1:], label)
    sep = dialect.delimiter
    names, units, cells = _header(header_line, sep, '"' in header_line, label)
    if len(lines) < 2:
        raise InputError("header only, no data rows", file=label)
    ncol = len(names)
    meta = {"encoding": enc, "csv_dialect": dialect.as_meta()}
    if ncol > 1 and (raw is None or b'"' not in raw) and _worth_pyarrow(p):
        fast = _fast(p, ncol, sep, dialect.decimal)
        if fast is not None:
            return RawTable(names, units, fast, np.arange(1, fast.shape[0] + 1), meta, header_cells=cells)
    if raw is None:
        raw = p.read_bytes()
        text, enc = decode_text(raw, label)
        lines = split_lines(text, label)
        meta["encoding"] = enc
    data_lines = lines[1:]
    if not data_lines:
        raise InputError("header only, no data rows", file=label)
    data = _checked(data_lines, names, sep, dialect.decimal, '"' in text, label)
    return RawTable(names, units, data, np.arange(1, data.shape[0] + 1), meta, header_cells=cells)


def _header(line: str, sep: str, quoted: bool, label: str) -> tuple[list[str], list, list[str]]:
    header = next(csv.reader([line], delimiter=sep)) if quoted else line.split(sep)
    header = [h.strip() for h in header]
    if len(header) == 1:
        for other, name in ((";", "';'"), ("\t", "tab"), ("|", "'|'")):
            if other in line:
                raise InputError(f"header has one column only: the file seems to be separated by {name}; "
                                 "shipid reads comma-, semicolon- or tab-separated values", file=label)
    if all(_NUMBER_LIKE.match(h) for h in header if h) and any(header):
        raise InputError("no header line: the first line holds numbers; expected 'name [unit]' cells",
                         file=label)
    names, units = [], []
    for k, cell in enumerate(header, start=1):
        if not cell:
            raise InputError(f"empty header cell in column {k}", file=label)
        try:
            name, unit = split_header(cell)
        except ValueError as err:
            raise InputError(str(err), file=label) from None
        if not name:
            raise InputError(f"header cell '{cell}' in column {k} has a unit but no name", file=label)
        if name in names:
            raise InputError(f"duplicate column name (columns {names.index(name) + 1} and {k})",
                             file=label, channel=name)
        names.append(name)
        units.append(unit)
    return names, units, header


def _checked(data_lines: list[str], names: list[str], sep: str, decimal: str, quoted: bool,
             label: str) -> np.ndarray:
    """Every cell converted with ``float()``; the first bad one named by channel and row."""
    if decimal == ",":
        data_lines = [line.replace(",", ".") for line in data_lines]
    ncol = len(names)
    cells = list(csv.reader(data_lines, delimiter=sep)) if quoted else [line.split(sep) for line in data_lines]
    data = np.empty((len(cells), ncol), dtype=np.float64)
    for i, row in enumerate(cells):
        if len(row) != ncol:
            if len(row) == 1 and ncol > 1 and not row[0].strip():
                row = [""] * ncol  # a blank line inside the data: a row of empty cells
            else:
                raise InputError(f"has {len(row)} fields, the header has {ncol}", file=label, row=i + 1)
        try:
            data[i] = [float(c) for c in row]
        except ValueError:
            data[i] = [cell_value(c, label, names[j], i + 1) for j, c in enumerate(row)]
    return data


def cell_value(c: str, label: str, channel: str, row: int) -> float:
    """One cell as a float: empty is NaN; ``1_0`` and text are one :class:`InputError` (file, channel, row)."""
    s = c.strip()
    if not s:
        return np.nan
    if "_" not in s:
        try:
            return float(s)
        except ValueError:
            pass
    shown = s if len(s) <= 30 else s[:27] + "..."
    if not shown.isprintable():
        shown = shown.encode("unicode_escape").decode("ascii")
    raise InputError(f"not a number: '{shown}'", file=label, channel=channel, row=row)


__all__ = ["read_csv_table", "cell_value"]
