"""The raw table every reader returns, and the text decoding the text readers share.

A reader (:mod:`shipid.io.files` for CSV, KVLCC2 and Parquet, :mod:`shipid.io.nmea`
for NMEA 0183) turns a file into a :class:`RawTable`: columns with the units named in
the file, before mapping to standard channels, conversion to SI and validation.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from shipid.errors import InputError


@dataclass
class RawTable:
    """Raw columns as read from a file, before mapping and unit conversion."""

    names: list[str]
    units: list[str | None]
    data: np.ndarray                     # (n_rows, n_cols) float64, NaN where empty
    rows: np.ndarray                     # 1-based data row numbers
    meta: dict = field(default_factory=dict)
    header_cells: list[str] | None = None  # the header cells as written ("Time (ms)"), where there is a header


def decode_text(raw: bytes, label: str, what: str = "CSV") -> tuple[str, str]:
    """Decode a text file's bytes: UTF-8 (BOM dropped), else cp1252; returns (text, encoding).

    Parquet, UTF-16 and binary content are refused with one :class:`~shipid.errors.InputError`
    naming ``label`` and the kind of text expected (``what``).
    """
    if raw.startswith(b"PAR1"):
        raise InputError(f"is a Parquet file, not {what} text (use a .parquet extension or --format parquet)",
                         file=label)
    head = raw[:65536]
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise InputError(f"UTF-16 encoded; save the {what} file as UTF-8", file=label)
    if b"\x00" in head:
        raise InputError(f"binary content (NUL bytes), not {what} text", file=label)
    try:
        return raw.decode("utf-8-sig"), "utf-8"
    except UnicodeDecodeError as err:
        ctrl = sum(1 for b in head if b < 32 and b not in (9, 10, 13))
        if ctrl:
            raise InputError(f"binary content, not {what} text (byte 0x{raw[err.start]:02x} at offset {err.start})",
                             file=label) from None
        return raw.decode("cp1252", errors="replace"), "cp1252"


_NEWLINE = re.compile(r"\r\n|\r|\n")


def split_lines(text: str, label: str) -> list[str]:
    """The text's lines, split at CR/LF only, trailing blank lines dropped.

    ``str.splitlines`` would also split at, and so hide from the readers' control-character
    checks, the characters \\x0b, \\x0c, \\x1c-\\x1e and \\x85. A file with no line left is empty
    (:class:`~shipid.errors.InputError`).
    """
    lines = text.split("\n") if "\r" not in text else _NEWLINE.split(text)     # the same lines, faster
    while lines and not lines[-1].strip():
        lines.pop()
    if not lines:
        raise InputError("empty file", file=label)
    return lines


__all__ = ["RawTable", "decode_text", "split_lines"]
