"""Argument shapes shared by the methods' ``identify`` entry points: trials as objects or paths."""

from __future__ import annotations

import os
from typing import Any, Mapping, Sequence

from shipid.io.files import read_trial
from shipid.io.trial import Trial
from shipid.errors import InputError

Trialish = Trial | str | os.PathLike


def as_trial(t: Trialish, **read_kwargs) -> Trial:
    """``t`` itself when it is a :class:`Trial`, else the file read with :func:`read_trial`."""
    return t if isinstance(t, Trial) else read_trial(t, **read_kwargs)


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
