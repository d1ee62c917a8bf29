"""Where the monitor's samples come from: a live NMEA feed on a socket, counted and checked.

:func:`live_samples` turns the lines of a :class:`shipid.io.live.Listener` into chunks of samples
``(t, p, a_s, r, delta)`` (arrays; NaN where a channel was lost) with
:func:`shipid.io.nmea_live.parse_line` and :class:`shipid.io.nmea_live.Assembler`. A line that cannot be
used is counted per datagram and said (the first ``say_first`` of every ``every`` seconds one line each,
then a summary line), never raised. :class:`FeedStats` holds the counts.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from shipid.io.nmea_fields import BadLine
from shipid.io.nmea_live import Assembler, parse_line


@dataclass
class FeedStats:
    """Counts of a live feed: lines used, bad lines (by kind), bad datagrams, samples made."""

    lines: int = 0
    bad_lines: int = 0
    bad_kinds: dict = field(default_factory=dict)
    bad_units: set = field(default_factory=set)     # datagram numbers (UDP) / line numbers (TCP) with a bad line
    samples: int = 0
    incomplete: int = 0                             # samples passed on with a channel lost

    def bad_total(self, listener_counts: dict) -> int:
        """Bad datagrams (UDP) or lines (TCP): unparsable, not text, empty, oversized or flooding."""
        return len(self.bad_units) + sum(listener_counts.get(k, 0) for k in ("oversized", "not_text", "empty",
                                                                              "flood"))


def live_samples(listener, stats: FeedStats, say, *, idle_timeout: float | None = None, chunk: float = 0.5,
                 say_first: int = 5, every: float = 10.0):
    """Chunks ``(t, p, a_s, r, delta)`` of the samples of ``listener``'s lines, about every ``chunk`` s of wall
    time; ``say(text)`` is called with each warning line."""
    asm = Assembler()
    said, suppressed, next_summary = 0, 0, time.monotonic() + every
    last_yield = time.monotonic()
    label = f"{listener.scheme}://{listener.address[0]}:{listener.address[1]}"

    def emit():
        s = asm.take()
        if not s:
            return None
        stats.samples += len(s)
        A = np.array([(t, *v) for t, v in s], dtype=float).T
        return A[0], A[1], A[2], A[3], A[4]

    for item in listener.lines(idle_timeout=idle_timeout):
        line, t_recv, unit = item
        if line is not None:
            stats.lines += 1
            try:
                t_tag, vals = parse_line(line)
            except BadLine as err:
                stats.bad_lines += 1
                stats.bad_kinds[err.kind] = stats.bad_kinds.get(err.kind, 0) + 1
                stats.bad_units.add(unit)
                if said < say_first:
                    said += 1
                    shown = line.strip()[:40].encode("ascii", "backslashreplace").decode()
                    say(f"{label}: bad sentence ({err.kind}: {err.message}): '{shown}'; dropped")
                else:
                    suppressed += 1
            else:
                asm.add(t_tag, t_recv, vals)
        now = time.monotonic()
        if now >= next_summary:
            if suppressed:
                say(f"{label}: {suppressed} more bad sentences dropped in the last {every:g} s "
                    f"({stats.bad_lines} in all)")
            said, suppressed, next_summary = 0, 0, now + every
        if line is None or now - last_yield >= chunk:
            last_yield = now
            out = emit()
            if out is not None:
                yield out
    asm.flush()
    if suppressed:
        say(f"{label}: {suppressed} more bad sentences dropped ({stats.bad_lines} in all)")
    out = emit()
    if out is not None:
        yield out
    stats.incomplete = asm.incomplete


__all__ = ["FeedStats", "live_samples"]
