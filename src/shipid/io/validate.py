"""Validation once, at the door: every trial passes here before any method sees it.

Rules (each failure is one :class:`~shipid.errors.InputError` naming the file, the
channel and the 1-based data row, i.e. the first row after the header is row 1):

1. Required channels are present.
2. Time is finite and strictly increasing. A duplicated timestamp or a step back in
   time is always an error; it is never "repaired".
3. Every value is finite. Empty cells, NaN and ±inf are *missing values*. They are an
   error unless ``interpolate_gaps=S`` is given: then each run of missing values whose
   *gap length* is at most ``S`` seconds is filled by linear interpolation in time,
   and the repair is recorded. The gap length is the time between the last good
   sample before the run and the first good sample after it (one missing sample at
   10 Hz is a 0.2 s gap). Runs at the very start or end of a record cannot be
   interpolated and stay an error. Channels whose SI unit is ``rad`` are interpolated
   on their unwrapped values, so a heading crossing 0/2π is not dragged through π.
4. Time gaps: a time step larger than ``GAP_FACTOR`` (1.5) times the median step is a
   gap. It is an error unless its length is at most ``interpolate_gaps``; then the
   missing samples are inserted on the uniform grid and every channel is interpolated
   linearly (recorded as a repair).
5. Uniform sampling: every step must equal the median step within a relative
   tolerance ``UNIFORM_RTOL`` = 1e-3. This absorbs the rounding of time stamps written
   with six or more significant digits and the floating-point drift of ``t = k·dt``
   accumulated over hours, but not a logger that jitters by more than 0.1 % of a
   step. Non-uniform sampling is an error unless ``resample=dt`` is given; then all
   channels are linearly interpolated onto ``t0 + k·dt`` (recorded as a repair;
   gaps longer than ``interpolate_gaps`` still stop it).
6. Optional ``trim_empty_rows``: rows at the start or the end of the file in which
   *no* column holds a finite value (e.g. a logger that wrote ",,,,," after it
   stopped) are removed and the removal recorded. Rows in the middle are never
   removed.

Rows are never dropped silently: every change is listed in the ``repairs`` returned
(and stored by the readers in ``trial.meta["repairs"]``).
"""

from __future__ import annotations

from typing import Iterable, Mapping

import numpy as np

from shipid.errors import InputError

#: Relative tolerance on each time step against the median step (see rule 5).
UNIFORM_RTOL = 1e-3
#: A step longer than this many median steps is a time gap (rule 4).
GAP_FACTOR = 1.5


def _runs(bad: np.ndarray) -> list[tuple[int, int]]:
    """Inclusive index ranges ``(i, j)`` of consecutive True values."""
    if not bad.any():
        return []
    b = np.concatenate(([False], bad, [False])).astype(np.int8)
    d = np.diff(b)
    starts = np.flatnonzero(d == 1)
    ends = np.flatnonzero(d == -1) - 1
    return list(zip(starts.tolist(), ends.tolist()))


def _what(value: float) -> str:
    if np.isnan(value):
        return "missing value (empty cell or NaN)"
    return f"infinite value ({value})"


def _fmt(x: float) -> str:
    return f"{x:.6g}"


def interpolate(t_new: np.ndarray, t_old: np.ndarray, x_old: np.ndarray, *, angle: bool = False) -> np.ndarray:
    """Linear interpolation of ``x_old(t_old)`` at ``t_new``; angles on their unwrapped values.

    For an angle the interpolated value keeps the 2π branch of the sample on its
    left, so that samples that were in the record come back unchanged.
    """
    if not angle or x_old.size < 2:
        return np.interp(t_new, t_old, x_old)
    xu = np.unwrap(x_old)
    shift = xu - x_old
    y = np.interp(t_new, t_old, xu)
    idx = np.clip(np.searchsorted(t_old, t_new, side="right") - 1, 0, t_old.size - 1)
    return y - shift[idx]


def validate_arrays(
    t,
    channels: Mapping[str, np.ndarray],
    *,
    file: str | None = None,
    rows: Iterable[int] | None = None,
    units: Mapping[str, str] | None = None,
    required: Iterable[str] | None = None,
    interpolate_gaps: float | None = None,
    resample: float | None = None,
    trim_empty_rows: bool = False,
    time_name: str = "t",
    method: str | None = None,
    copy: bool = True,
) -> tuple[np.ndarray, dict[str, np.ndarray], list[dict]]:
    """Check (and, where asked, repair) a time vector and its channels.

    Parameters
    ----------
    t : array_like, shape (n,)
        Time in seconds.
    channels : mapping of str to array_like, each shape (n,)
        Channel values in SI units.
    file : str, optional
        File name for the messages.
    rows : iterable of int, optional
        1-based data-row number of each sample in the file (default ``1..n``).
    units : mapping, optional
        SI unit per channel; channels in ``rad`` are interpolated as angles.
    required : iterable of str, optional
        Channels that must be present.
    interpolate_gaps : float, optional
        Longest gap, in seconds, that may be filled by linear interpolation.
    resample : float, optional
        Interpolate onto a uniform grid with this step (seconds).
    trim_empty_rows : bool
        Remove rows without any finite value at the start and the end.
    time_name : str
        Name of the time channel in the messages.
    method : str, optional
        Who needs the ``required`` channels, for the message.
    copy : bool
        False: return the given float64 arrays themselves where nothing was repaired (a
        reader's fresh arrays, not copied again); a repaired array is always a new one.

    Returns
    -------
    t, channels, repairs
        Validated arrays (float64; copies unless ``copy=False``) and the list of repairs
        made, each a dict with ``kind`` and a one-line ``text``.

    Raises
    ------
    InputError
        At the first problem, naming file, channel and row.
    """
    as_f8 = np.array if copy else np.asarray
    t = as_f8(t, dtype=np.float64)
    chans = {k: as_f8(v, dtype=np.float64) for k, v in channels.items()}
    n = t.size
    rows = (np.arange(1, n + 1) if rows is None else np.asarray(rows, dtype=np.int64) if isinstance(rows, np.ndarray)
            else np.asarray(list(rows), dtype=np.int64))
    units = dict(units or {})
    repairs: list[dict] = []
    if interpolate_gaps is not None and not (np.isfinite(interpolate_gaps) and interpolate_gaps > 0):
        raise InputError(f"--interpolate-gaps must be a positive number of seconds, not {interpolate_gaps}")
    if resample is not None and not (np.isfinite(resample) and resample > 0):
        raise InputError(f"--resample must be a positive time step in seconds, not {resample}")

    # 1. required channels
    for name in required or ():
        if name != time_name and name not in chans:
            who = f"required by {method} but missing" if method else "required channel missing"
            raise InputError(f"{who} (has: {', '.join(chans) or 'none'})",
                             file=file, channel=name)
    for k, v in chans.items():
        if v.shape != t.shape:
            raise InputError(f"has {v.size} samples but time has {t.size}", file=file, channel=k)

    # 6. trim rows that hold nothing at the ends (explicit request only)
    if trim_empty_rows and n:
        empty = ~np.isfinite(t)
        for v in chans.values():
            empty &= ~np.isfinite(v)
        keep = np.ones(n, dtype=bool)
        for i, j in _runs(empty):
            if i == 0 or j == n - 1:
                keep[i:j + 1] = False
                where = "start" if i == 0 else "end"
                repairs.append({"kind": "trimmed_empty_rows", "first_row": int(rows[i]),
                                "last_row": int(rows[j]), "samples": j - i + 1,
                                "text": f"removed {j - i + 1} empty rows {rows[i]}-{rows[j]} at the {where}"})
        if not keep.all():
            t, rows = t[keep], rows[keep]
            chans = {k: v[keep] for k, v in chans.items()}
            n = t.size

    if n == 0:
        raise InputError("no data rows", file=file)
    if n < 2:
        raise InputError("only one data row; a trial needs at least two samples", file=file, row=int(rows[0]))

    # 2a. missing time stamps: interpolated by index (uniform sampling) when allowed
    bad_t = ~np.isfinite(t)
    if bad_t.any():
        for i, j in _runs(bad_t):
            _check_run(i, j, t, None, file, time_name, rows, interpolate_gaps, t[i])
        good = np.flatnonzero(~bad_t)
        idx = np.flatnonzero(bad_t)
        t = t.copy()
        t[idx] = np.interp(idx, good, t[good])
        for i, j in _runs(bad_t):
            repairs.append(_repair_text("interpolated", time_name, rows, i, j, t))

    # 2b. strictly increasing
    d = np.diff(t)
    nonpos = np.flatnonzero(d <= 0)
    if nonpos.size:
        k = int(nonpos[0])
        if d[k] == 0:
            raise InputError(f"duplicated timestamp t={_fmt(t[k + 1])} s (same as row {rows[k]})",
                             file=file, channel=time_name, row=int(rows[k + 1]))
        raise InputError(f"time not increasing: t={_fmt(t[k + 1])} s follows t={_fmt(t[k])} s of row {rows[k]}",
                         file=file, channel=time_name, row=int(rows[k + 1]))

    # 3. missing values in the channels
    for name, v in chans.items():
        bad = ~np.isfinite(v)
        if not bad.any():
            continue
        runs = _runs(bad)
        for i, j in runs:
            _check_run(i, j, t, v, file, name, rows, interpolate_gaps, v[i])
        good = ~bad
        v = chans[name] = v.copy()
        v[bad] = interpolate(t[bad], t[good], v[good], angle=units.get(name) == "rad")
        for i, j in runs:
            repairs.append(_repair_text("interpolated", name, rows, i, j, t))

    # 4./5. gaps and uniform sampling
    dt = float(np.median(d))
    gap = d > GAP_FACTOR * dt
    for k in np.flatnonzero(gap):
        k = int(k)
        length = float(d[k])
        if interpolate_gaps is None or length > interpolate_gaps:
            hint = ("; use --interpolate-gaps S to fill gaps up to S seconds" if interpolate_gaps is None
                    else f"; longer than --interpolate-gaps {_fmt(interpolate_gaps)} s")
            raise InputError(f"time gap of {_fmt(length)} s (t={_fmt(t[k])} s to {_fmt(t[k + 1])} s, "
                             f"sampling interval {_fmt(dt)} s) after row {rows[k]}{hint}",
                             file=file, channel=time_name, row=int(rows[k + 1]))
    off = np.abs(d - dt) > UNIFORM_RTOL * dt
    if resample is None:
        # a gap may be filled only when it spans a whole number of sampling intervals
        m = np.rint(d / dt)
        whole = np.abs(d - m * dt) <= UNIFORM_RTOL * dt
        bad_step = off & ~(gap & whole)
        if bad_step.any():
            k = int(np.flatnonzero(bad_step)[0])
            raise InputError(f"non-uniform sampling: step of {_fmt(d[k])} s after row {rows[k]}, median step "
                             f"{_fmt(dt)} s (relative tolerance {UNIFORM_RTOL:g}); use --resample DT",
                             file=file, channel=time_name, row=int(rows[k + 1]))
        if gap.any():
            pieces = [t[:1]]
            for k in range(d.size):
                if gap[k]:
                    mk = int(m[k])
                    pieces.append(t[k] + d[k] * np.arange(1, mk) / mk)
                    repairs.append({"kind": "filled_time_gap", "channel": time_name,
                                    "first_row": int(rows[k]), "last_row": int(rows[k + 1]),
                                    "samples": mk - 1, "seconds": float(d[k]),
                                    "text": f"time gap of {_fmt(d[k])} s between rows {rows[k]} and {rows[k + 1]}: "
                                            f"{mk - 1} samples interpolated in every channel"})
                pieces.append(t[k + 1:k + 2])
            t_new = np.concatenate(pieces)
            chans = {k_: interpolate(t_new, t, v, angle=units.get(k_) == "rad") for k_, v in chans.items()}
            t = t_new
    else:
        count = int(np.floor((t[-1] - t[0]) / resample + 1e-9)) + 1
        if count < 2:
            raise InputError(f"--resample {_fmt(resample)} s is longer than the record ({_fmt(t[-1] - t[0])} s)",
                             file=file)
        t_new = t[0] + resample * np.arange(count)
        chans = {k_: interpolate(t_new, t, v, angle=units.get(k_) == "rad") for k_, v in chans.items()}
        repairs.append({"kind": "resampled", "channel": time_name, "samples": count, "seconds": float(resample),
                        "text": f"resampled {t.size} samples (median step {_fmt(dt)} s, "
                                f"{int(off.sum())} steps off it) to {count} samples at {_fmt(resample)} s"})
        t = t_new
    return t, chans, repairs


def _check_run(i, j, t, v, file, name, rows, limit, value) -> None:
    n = t.size
    what = _what(value)
    if limit is None:
        more = f" ({j - i + 1} rows to row {rows[j]})" if j > i else ""
        hint = ("use --trim-empty if whole rows at the ends are empty" if i == 0 or j == n - 1
                else "use --interpolate-gaps S to fill short gaps")
        raise InputError(f"{what}{more}; {hint}", file=file, channel=name, row=int(rows[i]))
    if i == 0 or j == n - 1:
        where = "start" if i == 0 else "end"
        more = f" ({j - i + 1} rows to row {rows[j]})" if j > i else ""
        raise InputError(f"{what} at the {where} of the record{more}; cannot interpolate there",
                         file=file, channel=name, row=int(rows[i]))
    length = float(t[j + 1] - t[i - 1])
    if not np.isfinite(length):
        raise InputError(f"{what} where time is missing too; cannot interpolate",
                         file=file, channel=name, row=int(rows[i]))
    if length > limit:
        raise InputError(f"{what}: gap of {_fmt(length)} s (rows {rows[i]}-{rows[j]}) is longer than "
                         f"--interpolate-gaps {_fmt(limit)} s", file=file, channel=name, row=int(rows[i]))


def _repair_text(kind, name, rows, i, j, t) -> dict:
    length = float(t[j + 1] - t[i - 1])
    return {"kind": kind, "channel": name, "first_row": int(rows[i]), "last_row": int(rows[j]),
            "samples": j - i + 1, "seconds": length,
            "text": f"{name}: {j - i + 1} missing values in rows {rows[i]}-{rows[j]} "
                    f"interpolated over {_fmt(length)} s"}
