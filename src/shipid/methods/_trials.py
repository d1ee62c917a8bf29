"""Argument shapes shared by the methods' ``identify`` entry points: trials as objects or paths."""

from __future__ import annotations

import os
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any, Iterator, Mapping, Sequence

from shipid.io.files import read_trial
from shipid.io.trial import Trial
from shipid.errors import InputError

Trialish = Trial | str | os.PathLike

_READ: ContextVar[list | None] = ContextVar("shipid_trials_read", default=None)


@contextmanager
def reading_log() -> Iterator[list]:
    """Collect every trial :func:`as_trial` reads from a file inside (their repairs become warnings)."""
    log: list = []
    token = _READ.set(log)
    try:
        yield log
    finally:
        _READ.reset(token)


def as_trial(t: Trialish, **read_kwargs) -> Trial:
    """``t`` itself when it is a :class:`Trial`, else the file read with :func:`read_trial`."""
    if isinstance(t, Trial):
        return t
    tr = read_trial(t, **read_kwargs)
    log = _READ.get()
    if log is not None:
        log.append(tr)
    return tr


def as_list(x) -> list:
    """One trial (object or path) as a one-element list; a sequence as a list."""
    if isinstance(x, (Trial, str, os.PathLike)):
        return [x]
    return list(x)


def grouped(trials: Mapping[str, Any], groups: Sequence[str], method: str) -> dict[str, list]:
    """Check a ``{group: trial(s)}`` mapping against the ``groups`` a method takes; lists per group."""
    if not isinstance(trials, Mapping):
        raise InputError(f"{method}: trials must be a mapping {{{', '.join(groups)}}} -> trial(s)")
    norm = {str(k).replace("_", "-"): v for k, v in trials.items()}
    unknown = sorted(set(norm) - set(groups))
    if unknown:
        raise InputError(f"{method}: unknown trial group(s) {', '.join(unknown)}; expected {', '.join(groups)}")
    missing = [g for g in groups if not norm.get(g)]
    if missing:
        raise InputError(f"{method}: no {', '.join(missing)} trials given")
    return {g: as_list(norm[g]) for g in groups}
