"""Benchmark: the monitor for days — resident memory (RSS) and speed over a long simulated stream at 50 Hz.

The stream is made of one-hour streams of :mod:`shipid.simulate.masscm_stream` (fishing vessel, issue-3
noise, no load change; ``DISTINCT`` of them simulated first, from SeedSequence([SEED, i]), then fed in turn,
each with its time shifted to follow the last, so the time is continuous and the signals restart each hour;
simulating up front keeps the simulator's own allocations out of the RSS measured while monitoring). It is fed in 10-s chunks through
:class:`shipid.methods.monitor.session.MonitorSession` (the fault conditioner, then the monitor), as the
command does; the session's state is saved (pickled, atomically) every ``STATE_EVERY`` updates as with
``--state``. Printed per simulated hour: RSS (``/proc/self/status`` VmRSS, MiB), processor and wall seconds of
the monitor (the simulation not counted), the × real time of the hour, the number of updates, alarms, warnings.
At the end: RSS after the first hour vs the largest later (target: within 10 %), and the speed over the whole
stream against the named peer, real time (target: >= 100 ×).

Usage:  python benchmarks/bench_monitor_soak.py [HOURS [SEED]]      (default 24 hours, seed 500)
        python benchmarks/bench_monitor_soak.py --smoke     (two 600-s "hours": the test suite's smoke run)
"""

import gc
import os
import sys
import tempfile
import time

import numpy as np
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
from known.linder2015 import true_value  # noqa: E402  (the reference values with their provenance)

from shipid.methods.monitor.estimator import MassCMMonitor
from shipid.methods.monitor.session import MonitorSession, save_state
from shipid.models.roll_reduced import KnownParams
from shipid.simulate.masscm_stream import StreamSpec, simulate_stream

STATE_EVERY = 1
DISTINCT = 3


def rss_mib() -> float:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


HOUR = 3600.0


def main(hours: int = 24, seed: int = 500) -> None:
    kn, z_f = KnownParams.from_vessel(), true_value("z_f")
    hours_data = []
    for i in range(min(DISTINCT, hours)):
        sim = simulate_stream(StreamSpec(duration=HOUR, change_at=None), seed=np.random.SeedSequence([seed, i]))
        if i == 0:
            session = MonitorSession(MassCMMonitor(sim["nominal"], sim["calibration"], kn, z_f))
        st = sim["stream"]
        hours_data.append((np.asarray(st.t, dtype=float), [np.asarray(st[c], dtype=float)
                                                           for c in ("p", "a_s", "r", "delta")]))
        del sim, st
    gc.collect()
    state = os.path.join(tempfile.mkdtemp(prefix="shipid-soak-"), "state.bin")
    n_up = n_alarm = n_warn = 0
    cpu_all = wall_all = 0.0
    rows = []
    print(f"{hours} h at 50 Hz ({len(hours_data)} distinct hours in turn), seed {seed}; state saved every {STATE_EVERY} update(s) to {state}")
    print(" hour   RSS MiB   cpu s   wall s   x real time (cpu)   updates  alarms  warnings  state KiB")
    for h in range(hours):
        t0, X = hours_data[h % len(hours_data)]
        t = t0 + HOUR * h
        c0, w0 = time.process_time(), time.perf_counter()
        for a in range(0, t.size, 500):
            s = slice(a, a + 500)
            ups, warns = session.push(t[s], X[0][s], X[1][s], X[2][s], X[3][s])
            n_warn += len(warns)
            for u in ups:
                n_up += 1
                n_alarm += bool(u.alarm)
                if n_up % STATE_EVERY == 0:
                    save_state(session, state)
        cpu, wall = time.process_time() - c0, time.perf_counter() - w0
        cpu_all += cpu
        wall_all += wall
        gc.collect()
        r = rss_mib()
        rows.append(r)
        print(f"{h + 1:5d}  {r:8.1f}  {cpu:6.1f}  {wall:7.1f}   {HOUR / cpu:10.0f}          {n_up:7d}  "
              f"{n_alarm:6d}  {n_warn:8d}  {os.path.getsize(state) / 1024:9.0f}", flush=True)
    ups, warns = session.finish()
    later = max(rows[1:]) if len(rows) > 1 else rows[0]
    print(f"RSS after hour 1: {rows[0]:.1f} MiB; largest later: {later:.1f} MiB "
          f"({100.0 * (later / rows[0] - 1.0):+.1f} %; target within 10 %)")
    print(f"speed: {HOUR * hours:.0f} s of stream in {cpu_all:.0f} s processor / {wall_all:.0f} s wall: "
          f"{HOUR * hours / cpu_all:.0f} x real time (processor), {HOUR * hours / wall_all:.0f} x (wall) "
          "vs the named peer, real time (target >= 100 x)")
    print(f"updates {n_up}, alarms {n_alarm} (no change in the stream), fault warnings {n_warn}, "
          f"counts {session.counts}")


if __name__ == "__main__":
    if "--smoke" in sys.argv[1:]:
        HOUR = 600.0
        main(2)
    else:
        main(*(int(a) for a in sys.argv[1:3]))
