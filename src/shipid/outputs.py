"""Writing output files safely: never clobber without ``force``, always atomically.

A result is first written to a temporary file in the destination folder and then
moved over the target with :func:`os.replace`, which is atomic on POSIX and
Windows: a reader sees either the old file or the complete new one, never half.
The finished file gets the mode a plain ``open(path, "w")`` would give it
(``0o666`` less the process umask, so 0644 under umask 022), not the 0600 of
:func:`tempfile.mkstemp`.

:func:`json_default` and :func:`jsonable` are the one rule for turning NumPy values,
dataclasses, paths and sets into JSON types, used by every writer of JSON.
"""

from __future__ import annotations

import dataclasses
import json
import os
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Callable

import numpy as np

from shipid.errors import OutputExistsError


def json_default(obj: Any) -> Any:
    """The ``default`` hook of :func:`json.dumps`: one step towards JSON types for what it cannot write.

    NumPy scalars become Python numbers (floats exactly, NaN kept), arrays nested lists, dataclass
    instances dicts, paths strings, sets sorted lists, other mappings dicts.

    Raises
    ------
    TypeError
        For any other type.
    """
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return dataclasses.asdict(obj)
    if isinstance(obj, Path):
        return str(obj)
    if isinstance(obj, (set, frozenset)):
        return sorted(obj)
    if isinstance(obj, Mapping):
        return dict(obj)
    raise TypeError(f"{type(obj).__name__} is not JSON-serialisable")


def _text_default(obj: Any) -> Any:
    try:
        return json_default(obj)
    except TypeError:
        return str(obj)


def jsonable(obj: Any, *, strict: bool = False) -> Any:
    """``obj`` as plain JSON types (dict with string keys, list, str, int, float, bool, None).

    Converted by :func:`json_default`; anything else becomes its ``str`` (``strict=False``) or raises
    ``TypeError`` (``strict=True``). Tuples become lists and mapping keys strings, as in JSON.
    """
    return json.loads(json.dumps(obj, default=json_default if strict else _text_default))


def short_path(p: str) -> str:
    """``p`` relative to the working directory when it lies below it, else its file name."""
    try:
        rel = os.path.relpath(p)
    except ValueError:
        rel = p
    return rel if not rel.startswith("..") else os.path.basename(p.rstrip("/")) or p


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
