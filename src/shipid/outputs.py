"""Writing output files safely: never clobber without ``force``, always atomically.

A result is first written to a temporary file in the destination folder and then
moved over the target with :func:`os.replace`, which is atomic on POSIX and
Windows: a reader sees either the old file or the complete new one, never half.
The finished file gets the mode a plain ``open(path, "w")`` would give it
(``0o666`` less the process umask, so 0644 under umask 022), not the 0600 of
:func:`tempfile.mkstemp`.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Callable

from shipid.errors import OutputExistsError


def _umask() -> int:
    """The process umask, read without changing it where the OS allows (Linux ``/proc``)."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    old = os.umask(0o022)  # elsewhere: set and restore (process-wide, but only for an instant)
    os.umask(old)
    return old


def atomic_write(path: str | os.PathLike, write: Callable[[Path], None], *, force: bool = False) -> Path:
    """Call ``write(tmp_path)`` and move the finished file onto ``path``.

    Parameters
    ----------
    path : path-like
        Destination.
    write : callable
        Writes the whole output to the temporary path it is given.
    force : bool
        Overwrite an existing ``path``; without it an existing file raises
        :class:`~shipid.errors.OutputExistsError` before anything is written.
    """
    dest = Path(path)
    if dest.exists() and not force:
        raise OutputExistsError(str(path))
    dest.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{dest.name}.", suffix=".tmp", dir=dest.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        write(tmp_path)
        os.chmod(tmp_path, 0o666 & ~_umask())
        os.replace(tmp_path, dest)
    finally:
        if tmp_path.exists():
            tmp_path.unlink()
    return dest


def atomic_write_text(path: str | os.PathLike, text: str, *, force: bool = False) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; see :func:`atomic_write`."""
    return atomic_write(path, lambda p: p.write_text(text, encoding="utf-8"), force=force)
