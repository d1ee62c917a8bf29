"""CSV dialects: which delimiter, and whether numbers use a decimal comma.

Spreadsheets export trials with ``,``, ``;`` or tab between the cells, and in
European locales with a decimal comma (``0,25``) -- then never with ``,`` as the
delimiter. :func:`detect_dialect` decides from the header line (cells
``name [unit]``) and the data lines, by these rules, in order:

1. Delimiter candidates are ``,``, ``;`` and tab, counted in the header outside
   brackets and quotes. None: the file has one column, read as comma-separated
   (the reader then names a ``|`` delimiter if it sees one). Exactly one: it.
2. Several (``t [s];x, east [m]``): the candidate that splits the header and the
   first 50 data lines into the same number of fields is taken when it is the
   only one that does; otherwise the file is ambiguous (one-line error).
3. Decimal comma only when the delimiter is ``;`` or tab: the data lines hold a
   ``,``. A data part that holds both a decimal comma and a decimal point
   (``1,5`` and ``2.5``, or thousands separators ``1.234,5``) is ambiguous (one-line
   error naming the first line of each).

The result is recorded by the reader in ``meta["csv_dialect"]``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from shipid.errors import InputError

DELIMITERS = {",": "comma", ";": "semicolon", "\t": "tab"}
#: Data lines looked at to resolve a header holding several candidate delimiters.
SAMPLE_LINES = 50

_BRACKETS = re.compile(r"\[[^\]]*\]|\"[^\"]*\"")
_POINT = re.compile(r"\d\.\d|(?<![\w.])\.\d|\d\.(?![\w.])")


@dataclass(frozen=True)
class Dialect:
    """Delimiter and decimal mark of a CSV file."""

    delimiter: str = ","
    decimal: str = "."

    def as_meta(self) -> dict:
        """``{"delimiter": "semicolon", "decimal": ","}`` for ``meta["csv_dialect"]``."""
        return {"delimiter": DELIMITERS[self.delimiter], "decimal": self.decimal}


def detect_dialect(header: str, data_lines: list[str], label: str | None = None) -> Dialect:
    """The dialect of a CSV file from its header line and data lines (rules in the module docstring).

    Parameters
    ----------
    header : str
        The first line.
    data_lines : list of str
        The lines after it.
    label : str, optional
        File name for the messages.

    Raises
    ------
    InputError
        When the delimiter or the decimal mark cannot be told apart.
    """
    bare = _BRACKETS.sub("", header)
    present = [d for d in DELIMITERS if d in bare]
    if not present:
        return Dialect()
    if len(present) == 1:
        delim = present[0]
    else:
        sample = [s for s in data_lines[:SAMPLE_LINES] if s.strip()]
        consistent = [d for d in present
                      if all(len(s.split(d)) == len(bare.split(d)) for s in sample)]
        if len(consistent) != 1:
            names = " and ".join(DELIMITERS[d] for d in present)
            raise InputError(f"cannot tell the delimiter: the header holds both {names} and "
                             f"{'both split' if consistent else 'neither splits'} the rows like the header; "
                             "save the file with one delimiter", file=label)
        delim = consistent[0]
    if delim == ",":
        return Dialect(",", ".")
    comma = next((i for i, s in enumerate(data_lines, start=1) if "," in s), None)
    if comma is None:
        return Dialect(delim, ".")
    point = next((i for i, s in enumerate(data_lines, start=1) if _POINT.search(s)), None)
    if point is not None:
        raise InputError(f"{DELIMITERS[delim]}-separated with a decimal comma (row {comma}) and a decimal point "
                         f"(row {point}): cannot tell which is meant; use one decimal mark", file=label)
    return Dialect(delim, ",")
