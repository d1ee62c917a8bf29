"""Errors that reach the user as one line.

Every problem with input data is raised as :class:`InputError`, which carries the
file, the channel and the row where it was found. The command line prints
``str(error)`` on one line and exits with status 2; no traceback is shown.
"""

from __future__ import annotations


class ShipidError(Exception):
    """Base class for errors that the command line reports in one line (exit 2)."""

    exit_code = 2


class InputError(ShipidError):
    """Bad input data, located by file, channel and row.

    Parameters
    ----------
    message : str
        What is wrong, in a few words (``"time not strictly increasing"``).
    file : str or None
        Path of the file as the user gave it.
    channel : str or None
        Channel (column) name.
    row : int or None
        1-based data row (the first row after the header is row 1).
    """

    def __init__(self, message: str, *, file: str | None = None,
                 channel: str | None = None, row: int | None = None):
        self.message = message
        self.file = file
        self.channel = channel
        self.row = row
        super().__init__(self.__str__())

    def __str__(self) -> str:
        where = []
        if self.file is not None:
            where.append(f"{self.file}")
        if self.channel is not None:
            where.append(f"channel '{self.channel}'")
        if self.row is not None:
            where.append(f"row {self.row}")
        prefix = ": ".join([", ".join(where)]) if where else ""
        text = f"{prefix}: {self.message}" if prefix else self.message
        return " ".join(text.split())  # always one line

    def located(self, *, file: str | None = None) -> "InputError":
        """Return a copy with the file filled in where it was missing."""
        return InputError(self.message, file=self.file or file,
                          channel=self.channel, row=self.row)


class OutputExistsError(ShipidError):
    """An output file exists and ``--force`` was not given."""

    def __init__(self, path: str):
        super().__init__(f"{path}: output file exists (use --force to overwrite)")


class ConvergenceError(ShipidError):
    """An iterative estimator did not converge and the caller asked for strictness."""
