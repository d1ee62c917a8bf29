"""Days of running: the session's memory does not grow with the stream's length (slow: hours of stream)."""

import gc
import tracemalloc

import numpy as np
import pytest
from known.linder2015 import true_value

from shipid.methods.monitor.estimator import MassCMMonitor
from shipid.methods.monitor.session import MonitorSession
from shipid.models.roll_reduced import KnownParams
from shipid.simulate.masscm_stream import StreamSpec, simulate_stream

KN = KnownParams.from_vessel()
Z_F = true_value("z_f")


def _soak(duration: float, repeats: int, trace: bool = True):
    """The same simulated stream fed ``repeats`` times, its time shifted each time (continuous time);
    traced memory (after a full garbage collection) after each pass."""
    sim = simulate_stream(StreamSpec(duration=duration, change_at=None), seed=77)
    st = sim["stream"]
    t0 = np.asarray(st.t, dtype=float)
    X = [np.asarray(st[c], dtype=float) for c in ("p", "a_s", "r", "delta")]
    s = MonitorSession(MassCMMonitor(sim["nominal"], sim["calibration"], KN, Z_F))
    del sim
    span = t0[-1] + (t0[1] - t0[0])
    mem, sizes = [], []
    if trace:
        tracemalloc.start()
    try:
        for k in range(repeats):
            t = t0 + k * span
            for a in range(0, t.size, 500):
                sl = slice(a, a + 500)
                s.push(t[sl], X[0][sl], X[1][sl], X[2][sl], X[3][sl])
            gc.collect()                                   # live memory, not cyclic garbage awaiting collection
            mem.append(tracemalloc.get_traced_memory()[0] if trace else 0)
            c = s.cond
            sizes.append((len(s.mon.blocks), len(c.q), len(c.buf), len(c.seen), len(s._gap_starts)))
    finally:
        if trace:
            tracemalloc.stop()
    return s, mem, sizes


def test_buffers_bounded_by_the_window():
    s, mem, sizes = _soak(400.0, 3, trace=False)
    assert s.mon._refs is None                        # the raw references are dropped after the start-up
    assert all(b <= 30 for b, *_ in sizes)            # window / every blocks
    assert all(q <= s.cond.delay + 1 and buf <= s.cond.nr + 1 for _, q, buf, *_ in sizes)
    assert sizes[1] == sizes[2]


@pytest.mark.slow
def test_soak_three_hours_memory_flat():
    """3 h of stream after a warm-up hour (one hour fed four times): traced memory after hours 3 and 4 within
    10 % of hour 2.

    The first hour is a warm-up, not part of the claim: run alone, hours 2 and 3 stay within 10 % of hour 1, but run
    after the rest of the slow suite in one process, hour 2 traced 256 KB (9 %) more than hour 1 and hour 3
    30 KB more than hour 2, a one-time settling whose size depends on what the process did before. The claim
    under test is that memory does not grow with the stream's length once running, which hours 2 to 4 measure;
    the 24-h soak in docs/validation/monitor.md measures the resident set.
    """
    s, mem, sizes = _soak(3600.0, 4)
    assert max(mem[2:]) <= 1.10 * mem[1], mem
    assert sizes[1] == sizes[2] == sizes[3]
