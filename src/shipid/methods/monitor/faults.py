"""Sensor faults of a live IMU + rudder stream, named and survived before the monitor sees the samples.

:class:`Conditioner` takes samples ``(t, p, a_s, r, delta)`` as they arrive (any order, NaN allowed) and
gives back the uniformly sampled stream that :class:`~shipid.methods.monitor.estimator.MassCMMonitor`
needs, plus one warning line per fault, with its stream time and channel. On a clean stream it is the
identity (every sample passed on unchanged, with its own time), so a live feed and the same file read
directly give the same estimates. The faults and what is done:

* **repeated sample** (a time already received): dropped, counted;
* **out-of-order sample**: put back in order if it is at most ``reorder`` seconds late, else dropped and
  counted (late); repeated and late samples are said as one summary line per ``summary`` seconds of stream;
* **clock jump**: the time tag jumps by more than ``bridge`` seconds (forward, or back beyond the reorder
  horizon) while every checked channel continues the signal (the step to the new sample within
  ``continuity`` standard deviations of the channel's sample-to-sample change): the time is re-based so
  that the stream continues, said once;
* **gap** (samples missing, the signals not continuous): up to ``bridge`` seconds bridged by linear
  interpolation and said; longer, a *break*: the samples before it are passed on, the monitor's filters
  restart after it (:func:`shipid.methods.monitor.session.restart_after_gap`), said once;
* **NaN burst** in a channel: as a gap of that channel (bridged up to ``bridge`` s, else a break);
* **frozen channel**: ``p``, ``a_s`` or ``r`` holds one value for ``frozen`` seconds (a noisy gyro or
  accelerometer never does); its samples from the start of the run are treated as missing, said once
  when found and once when the channel moves again (the rudder is not checked: a held rudder is normal);
* **spike**: a sample of ``p``, ``a_s`` or ``r`` further than ``spike`` standard deviations of the channel's
  sample-to-sample change from the median of its 7 neighbours (Hampel identifier), replaced by
  interpolation, said.

While a channel stays bad the conditioner says, every ``every`` seconds of stream time, that no estimate
can be made (:attr:`Conditioner.no_estimate`); the session prints that instead of a number. Samples are
passed on with a delay of ``bridge + frozen`` seconds plus the reorder horizon (the look-ahead the
decisions need); :meth:`Conditioner.flush` passes on the rest at the end of a stream.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

CHANNELS = ("p", "a_s", "r", "delta")
CHECKED = (0, 1, 2)                 # frozen / spike / continuity checks: p, a_s, r (not the rudder)
_SCALE_MIN_N = 100                  # diffs seen before a channel's scale is trusted
_SCALE_N = 1000                     # memory of the running scale (samples)


@dataclass(frozen=True)
class FaultOptions:
    """Thresholds of :class:`Conditioner` (seconds of stream time, or standard deviations).

    Attributes
    ----------
    bridge : float
        Longest gap or bad run bridged by linear interpolation (s); longer ones break the stream.
    reorder : float
        Samples at most this late are put back in order (s).
    frozen : float
        A checked channel holding one value this long is frozen (s).
    spike : float
        Hampel threshold, in standard deviations of the channel's sample-to-sample change.
    continuity : float
        A time jump is a clock jump when every checked channel's step is within this many standard deviations.
    every : float
        Period of the "cannot estimate" lines (s).
    summary : float
        Repeated and late samples are said in one line per this many seconds of stream (s).
    """

    bridge: float = 1.0
    reorder: float = 0.2
    frozen: float = 1.0
    spike: float = 12.0
    continuity: float = 4.0
    every: float = 10.0
    summary: float = 60.0


class Conditioner:
    """Streaming fault handler (see the module docstring). ``T``: the sample period (s)."""

    def __init__(self, T: float, options: FaultOptions = FaultOptions()):
        self.T, self.o = float(T), options
        self.nr = max(1, int(round(options.reorder / self.T)))
        self.nb = max(1, int(round(options.bridge / self.T)))
        self.nf = max(2, int(round(options.frozen / self.T)))
        self.delay = self.nb + self.nf + 4
        self.base: float | None = None          # time of index 0
        self.offset = 0.0                       # added to incoming times (clock re-basing)
        self.buf: dict[int, tuple] = {}         # stage 1: index -> (t, values) not yet in order
        self.max_k: int | None = None
        self.last_vals: tuple | None = None     # values of the sample at max_k
        self.seen: deque = deque(maxlen=4 * self.nr + 8)
        self.next_k: int | None = None          # next index into stage 2
        self.q: deque = deque()                 # stage 2: [k, t, [values], interpolated?] in order
        self.hist: deque = deque(maxlen=3)      # last rows passed on (for spikes and bridging)
        self.scale_sum = [0.0] * 4
        self.scale_n = [0] * 4
        self.run = [[None, 0, None] for _ in range(4)]      # value, length, start index (frozen check)
        self.frozen_on = [False] * 4
        self.bad_since: float | None = None     # stream time of a break that is still open
        self.bad_what = ""
        self.next_tick: float | None = None
        self.out: list = []                     # ("row", t, values) | ("break", t_resume, text)
        self.warnings: list[str] = []
        self.no_estimate: list[tuple[float, str]] = []
        self.counts = {"repeated": 0, "late": 0, "bad_time": 0, "gaps": 0, "bridged": 0, "clock_jumps": 0,
                       "nan": 0, "frozen": 0, "spikes": 0, "breaks": 0}
        self._summ = {"repeated": 0, "late": 0}
        self._summ_t: float | None = None
        self._summ_from = 0.0

    # ------------------------------------------------------------------ stage 1: time, order, repeats
    def _sd(self, c: int) -> float | None:
        if self.scale_n[c] < _SCALE_MIN_N:
            return None
        return 1.2533 * self.scale_sum[c] / min(self.scale_n[c], _SCALE_N)

    def _continuous(self, vals) -> bool:
        if self.last_vals is None:
            return False
        for c in CHECKED:
            sd = self._sd(c)
            a, b = vals[c], self.last_vals[c]
            if sd is None or not (math.isfinite(a) and math.isfinite(b)) or abs(a - b) > self.o.continuity * sd:
                return False
        return True

    def push(self, t: float, vals) -> None:
        """One sample: stream time ``t`` (s) and ``(p, a_s, r, delta)`` (NaN: missing)."""
        vals = tuple(float(v) for v in vals)
        if not math.isfinite(t):
            self.counts["bad_time"] += 1
            return
        ta = t + self.offset
        if self.base is None:
            self.base, self.max_k, self.next_k = ta, 0, 0
        k = int(round((ta - self.base) / self.T))
        if self.max_k is not None and k in self.seen:
            self.counts["repeated"] += 1
            self._summ["repeated"] += 1
            return
        if k > self.max_k + self.nb + 1 or k < self.next_k - self.nr:
            if self._continuous(vals):
                jump = (k - self.max_k - 1) * self.T
                self.offset -= jump
                self.counts["clock_jumps"] += 1
                self.warnings.append(f"t = {self.base + (self.max_k + 1) * self.T:.6g} s: clock jump of "
                                     f"{jump:+.6g} s in the time tags (every channel continuous); time re-based")
                ta, k = ta - jump, self.max_k + 1
            elif k < self.next_k:
                self.counts["late"] += 1
                self._summ["late"] += 1
                return
        elif k < self.next_k:
            self.counts["late"] += 1
            self._summ["late"] += 1
            return
        self.seen.append(k)
        on_grid = abs(ta - self.base - k * self.T) <= 0.25 * self.T
        self.buf[k] = (ta if on_grid else self.base + k * self.T, vals)
        if k > self.max_k:
            self.max_k, self.last_vals = k, vals
        elif k == self.max_k:
            self.last_vals = vals
        ripe = sorted(j for j in self.buf if j <= self.max_k - self.nr)
        for j in ripe:
            self._stage2(j, *self.buf.pop(j))

    # ------------------------------------------------------------------ stage 2: gaps, NaN, frozen, spikes
    def _stage2(self, k: int, t: float, vals) -> None:
        gap = k - self.next_k
        if gap > self.nb:
            t_gap = self.base + self.next_k * self.T
            self._drain_all()
            self._break(t, f"t = {t_gap:.6g} s: gap of {gap * self.T:.6g} s in the stream (no samples)")
            self.counts["gaps"] += 1
            for r in self.run:
                r[0], r[1] = None, 0
        elif gap > 0:
            self.counts["gaps"] += 1
            self.counts["bridged"] += 1
            t_gap = self.base + self.next_k * self.T
            self.warnings.append(f"t = {t_gap:.6g} s: gap of {gap * self.T:.6g} s in the stream (p, a_s, r, delta); "
                                 "bridged by interpolation")
            for j in range(self.next_k, k):
                self._enter(j, self.base + j * self.T, [math.nan] * 4, gapfill=True)
        self.next_k = k + 1
        self._enter(k, t, list(vals))
        while len(self.q) > self.delay:
            self._pop()

    def _enter(self, k: int, t: float, v: list, gapfill: bool = False) -> None:
        for c in range(4):
            if not gapfill and not math.isfinite(v[c]):
                self.counts["nan"] += 1
        for c in CHECKED:
            x = v[c]
            r = self.run[c]
            if math.isfinite(x) and x == r[0]:
                r[1] += 1
            else:
                if self.frozen_on[c] and math.isfinite(x):
                    self.frozen_on[c] = False
                    self.warnings.append(f"t = {t:.6g} s: channel {CHANNELS[c]} moves again after "
                                         f"{r[1] * self.T:.6g} s frozen")
                r[0], r[1], r[2] = (x, 1, k) if math.isfinite(x) else (None, 0, None)
            if r[1] == self.nf:
                self.frozen_on[c] = True
                self.counts["frozen"] += 1
                self.warnings.append(f"t = {self.base + r[2] * self.T:.6g} s: channel {CHANNELS[c]} frozen at "
                                     f"{r[0]:.6g} (one value for {self.nf * self.T:.6g} s); its samples are "
                                     "treated as missing")
                for row in self.q:
                    if row[0] >= r[2]:
                        row[2][c] = math.nan
            if self.frozen_on[c]:
                v[c] = math.nan
        self.q.append([k, t, v, gapfill])

    def _pop(self) -> None:
        row = self.q[0]
        k, t, v = row[0], row[1], row[2]
        self._spikes(v, t)
        bad = [c for c in range(4) if not math.isfinite(v[c])]
        if bad and self.bad_since is None:
            for c in bad:
                n = 0
                for r in self.q:
                    if math.isfinite(r[2][c]):
                        break
                    n += 1
                if n > self.nb or n == len(self.q) or not self.hist or not math.isfinite(self.hist[-1][2][c]):
                    self._open_break(t, c)
                    break
                self._bridge(c, n)
        self.q.popleft()
        if self.bad_since is not None:
            if all(math.isfinite(x) for x in v) and not any(self.frozen_on):
                self._break(t, f"t = {self.bad_since:.6g} s: {self.bad_what} bad for "
                               f"{t - self.bad_since:.6g} s")
                self.bad_since = None
            else:
                self._tick(t)
                return
        for c in range(4):
            if self.hist and not row[3] and not self.hist[-1][3]:
                d = abs(v[c] - self.hist[-1][2][c])
                self.scale_sum[c] += d - (self.scale_sum[c] / _SCALE_N if self.scale_n[c] >= _SCALE_N else 0.0)
                self.scale_n[c] += 1
        self.hist.append(row)
        self.out.append(("row", t, tuple(v)))
        self._summary(t)

    def _spikes(self, v: list, t: float) -> None:
        if len(self.hist) < 3 or len(self.q) < 4:
            return
        for c in CHECKED:
            sd = self._sd(c)
            x = v[c]
            if sd is None or not math.isfinite(x):
                continue
            nb = [h[2][c] for h in self.hist] + [self.q[j][2][c] for j in (1, 2, 3)]
            if not all(math.isfinite(y) for y in nb):
                continue
            med = sorted(nb + [x])[3]
            if abs(x - med) > self.o.spike * sd:
                self.counts["spikes"] += 1
                self.warnings.append(f"t = {t:.6g} s: spike in channel {CHANNELS[c]} ({x:.6g}, "
                                     f"{abs(x - med) / sd:.3g} std from its neighbours); replaced by interpolation")
                v[c] = math.nan

    def _bridge(self, c: int, n: int) -> None:
        """Channel ``c`` is missing in the first ``n`` rows of the queue: interpolate it linearly."""
        x0, x1 = self.hist[-1][2][c], self.q[n][2][c]
        for j in range(n):
            self.q[j][2][c] = x0 + (x1 - x0) * (j + 1) / (n + 1)
            self.q[j][3] = True

    def _open_break(self, t: float, c: int) -> None:
        self.bad_since = t
        self.hist.clear()               # no spike check or bridge against samples from before the break
        self.bad_what = f"channel {CHANNELS[c]}" + (" (frozen)" if self.frozen_on[c] else "")
        self.next_tick = t + self.o.every
        self.warnings.append(f"t = {t:.6g} s: {self.bad_what} missing for more than {self.o.bridge:g} s; "
                             "no estimate until it is back")

    def _tick(self, t: float) -> None:
        if self.next_tick is not None and t >= self.next_tick - 0.5 * self.T:
            self.no_estimate.append((t, f"t = {t:.6g} s: cannot estimate: {self.bad_what} bad since "
                                        f"t = {self.bad_since:.6g} s"))
            self.next_tick += self.o.every

    def _break(self, t_resume: float, text: str) -> None:
        self.counts["breaks"] += 1
        self.hist.clear()
        self.warnings.append(f"{text}; the monitor's filters restart at t = {t_resume:.6g} s")
        self.out.append(("break", t_resume, text))

    def _summary(self, t: float) -> None:
        if self._summ_t is None:
            self._summ_t, self._summ_from = t + self.o.summary, t
        if t < self._summ_t:
            return
        self._summ_t = t + self.o.summary
        if self._summ["repeated"] or self._summ["late"]:
            self.warnings.append(f"t = {t:.6g} s: {self._summ['repeated']} repeated and {self._summ['late']} "
                                 f"late samples dropped since t = {self._summ_from:.6g} s")
            self._summ = {"repeated": 0, "late": 0}
        self._summ_from = t

    def _drain_all(self) -> None:
        while self.q:
            self._pop()

    def flush(self) -> None:
        """End of the stream: pass on every sample held."""
        for j in sorted(self.buf):
            self._stage2(j, *self.buf.pop(j))
        self._drain_all()
        if self._summ["repeated"] or self._summ["late"]:
            self._summ_t = -math.inf
            self._summary(self.base + (self.next_k - 1) * self.T if self.base is not None else 0.0)

    def take(self) -> tuple[list, list[str], list[tuple[float, str]]]:
        """What was produced since the last call: items, warning lines, "cannot estimate" lines."""
        out, w, ne = self.out, self.warnings, self.no_estimate
        self.out, self.warnings, self.no_estimate = [], [], []
        return out, w, ne


__all__ = ["FaultOptions", "Conditioner", "CHANNELS"]
