"""Where the shared real data sets live (never copied into the repository).

:func:`data_root` looks, in order, at ``$SHIPID_DATA``, at ``../shared/data``
relative to the repository root (the folder holding ``pyproject.toml`` above this
file), and at ``../shared/data`` and ``shared/data`` relative to the current working
directory. Tests that need the data skip cleanly when it returns None.
"""

from __future__ import annotations

import os
from pathlib import Path


def _repo_root() -> Path | None:
    for parent in Path(__file__).resolve().parents:
        if (parent / "pyproject.toml").is_file():
            return parent
    return None


def data_root() -> Path | None:
    """The folder of the shared real data sets, or None when it cannot be found.

    ``$SHIPID_DATA`` wins when it is set; if it names a folder that does not exist,
    None is returned (a wrong setting must not silently fall back to another copy).
    """
    env = os.environ.get("SHIPID_DATA")
    if env:
        p = Path(env).expanduser()
        return p if p.is_dir() else None
    candidates = []
    root = _repo_root()
    if root is not None:
        candidates.append(root.parent / "shared" / "data")
    cwd = Path.cwd()
    candidates += [cwd.parent / "shared" / "data", cwd / "shared" / "data"]
    for c in candidates:
        if c.is_dir():
            return c
    return None
