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
a bad one the careful path's time, with the same one-line messages as before. The columns
come back as one float64 ``(n_rows, n_cols)`` array (Fortran order from the fast path, so that
each column is a contiguous view).
"""

from __future__ import annotations

import csv
import re
from pathlib import Path

import numpy as np

from shipid.errors import InputError
from shipid.io.csv_dialect import detect_dialect
from shipid.io.table import RawTable, decode_text, split_lines
from shipid.io.units import split_header

_NUMBER_LIKE = re.compile(r"^\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*$")
#: Lines whose characters are checked for control characters before parsing.
CHECK_LINES = 200


def _check_text(lines: list[str], label: str) -> None:
    for i, line in enumerate(lines[:CHECK_LINES]):
        if any(ord(ch) < 32 and ch != "\t" for ch in line):
            raise InputError("binary content (control characters), not CSV text", file=label,
                             row=i if i else None)


def _header_end(raw: bytes) -> int:
    """Offset of the first byte after the header line (its CR, LF or CRLF included); -1 without a line end."""
    cut = [i for i in (raw.find(b"\n"), raw.find(b"\r")) if i >= 0]
    if not cut:
        return -1
    i = min(cut)
    return i + 2 if raw[i:i + 2] == b"\r\n" else i + 1


def _count_lines(data: bytes) -> int:
    """Lines in ``data`` (no trailing line end), split at CRLF, CR or LF as :func:`split_lines` does."""
    n = data.count(b"\n") + 1
    if b"\r" in data:
        n += data.count(b"\r") - data.count(b"\r\n")
    return n


def _fast(data: bytes, ncol: int, sep: str, decimal: str) -> np.ndarray | None:
    """The data rows parsed by pyarrow's CSV reader, or None when it cannot vouch for every cell."""
    try:
        import pyarrow as pa
        import pyarrow.csv as pacsv
    except ImportError:  # pragma: no cover - pyarrow is a dependency
        return None
    names = [f"c{j}" for j in range(ncol)]
    try:
        table = pacsv.read_csv(
            pa.py_buffer(data),
            read_options=pacsv.ReadOptions(column_names=names, block_size=1 << 22),
            parse_options=pacsv.ParseOptions(delimiter=sep, quote_char=False, double_quote=False,
                                             escape_char=False, newlines_in_values=False,
                                             ignore_empty_lines=False),
            convert_options=pacsv.ConvertOptions(column_types={c: pa.float64() for c in names},
                                                 null_values=[""], true_values=[], false_values=[],
                                                 strings_can_be_null=False, decimal_point=decimal,
                                                 check_utf8=False))
    except (pa.ArrowException, ValueError, OSError):
        return None
    if table.num_rows != _count_lines(data):   # every line a row (blank ones are refused above): a safeguard
        return None
    out = np.empty((table.num_rows, ncol), dtype=np.float64, order="F")   # each column contiguous
    for j in range(ncol):
        col = table.column(j)
        if col.null_count:
            out[:, j] = col.to_numpy(zero_copy_only=False)     # nulls (empty cells) -> NaN
        else:
            pos = 0
            for chunk in col.chunks:                           # copied once, straight into the block
                k = len(chunk)
                out[pos:pos + k, j] = chunk.to_numpy(zero_copy_only=True)
                pos += k
    return out


def read_csv_table(p: Path, label: str) -> RawTable:
    """Read a CSV trial file into raw columns (names and units from its header), or raise one InputError."""
    raw = p.read_bytes()
    if not raw[:4096].strip() and not raw.strip():
        raise InputError("empty file", file=label)
    end = _header_end(raw)
    head_raw = raw if end < 0 else raw[:end]
    quoted = b'"' in raw
    # the header, the first lines and the dialect from a decoded head; the whole text only when needed
    sample_end = end
    for _ in range(CHECK_LINES):
        if sample_end < 0 or sample_end >= len(raw):
            break
        nxt = _header_end(raw[sample_end:sample_end + 65536])
        sample_end = -1 if nxt < 0 else sample_end + nxt
    text, enc = decode_text(raw if sample_end < 0 else raw[:sample_end], label)
    lines = split_lines(text, label)
    _check_text(lines, label)
    header_line = lines[0]
    sep_guess = detect_dialect(header_line, lines[1:], label)
    if sep_guess.delimiter != "," or sample_end >= 0 and enc != "utf-8":
        # a decimal comma is decided on every data line; a non-UTF-8 head on the whole text
        text, enc = decode_text(raw, label)
        lines = split_lines(text, label)
    dialect = detect_dialect(header_line, lines[1:], label)
    sep = dialect.delimiter
    names, units, cells = _header(header_line, sep, quoted, label)
    if len(lines) < 2:
        raise InputError("header only, no data rows", file=label)
    ncol = len(names)
    meta = {"encoding": enc, "csv_dialect": dialect.as_meta()}
    if not quoted and ncol > 1 and end >= 0:
        data = raw[end:].rstrip(b"\r\n")
        fast = _fast(data, ncol, sep, dialect.decimal) if data else None
        if fast is not None:
            return RawTable(names, units, fast, np.arange(1, fast.shape[0] + 1), meta, header_cells=cells)
    if sample_end >= 0:
        text, enc = decode_text(raw, label)
        lines = split_lines(text, label)
        meta["encoding"] = enc
    data_lines = lines[1:]
    if not data_lines:
        raise InputError("header only, no data rows", file=label)
    data = _checked(data_lines, names, sep, dialect.decimal, quoted, label)
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
