"""Joining trials that are parts of one record (e.g. a logger that split a run into files).

The joined record goes through the same door as a file: a gap between the parts is a
time gap (an error unless it is short enough for ``interpolate_gaps``), overlapping
parts are non-increasing time. Nothing is joined silently.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from shipid.io.trial import Trial
from shipid.io.validate import validate_arrays
from shipid.errors import InputError


def concat_trials(trials: Sequence[Trial], *, interpolate_gaps: float | None = None,
                  resample: float | None = None) -> Trial:
    """Join trials end to end and validate the result.

    Parameters
    ----------
    trials : sequence of Trial
        In time order, with the same channels and units.
    interpolate_gaps, resample : float, optional
        As for :func:`shipid.io.validate.validate_arrays`.

    Returns
    -------
    Trial
        ``meta["parts"]`` lists the sources and ``meta["repairs"]`` what was filled.
        Rows in messages are counted through the joined record (row 1 = first row of
        the first part).
    """
    if not trials:
        raise InputError("nothing to join")
    first = trials[0]
    names = first.names
    for tr in trials[1:]:
        if tr.names != names or dict(tr.units) != dict(first.units):
            raise InputError(f"cannot join: channels or units differ from {first.meta.get('source', 'part 1')}",
                             file=str(tr.meta.get("source")) if tr.meta.get("source") else None)
    sources = [str(tr.meta.get("source", f"part {k + 1}")) for k, tr in enumerate(trials)]
    label = " + ".join(sources)
    t = np.concatenate([tr.t for tr in trials])
    chans = {n: np.concatenate([tr[n] for tr in trials]) for n in names}
    t, chans, repairs = validate_arrays(t, chans, file=label, units=first.units,
                                        interpolate_gaps=interpolate_gaps, resample=resample)
    meta = dict(first.meta)
    meta.update({"source": label, "parts": sources,
                 "repairs": [r for tr in trials for r in tr.meta.get("repairs", [])] + repairs})
    return Trial(t, chans, first.units, meta)
