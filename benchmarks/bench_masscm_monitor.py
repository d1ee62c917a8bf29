"""Benchmark (issue 18): the online mass / CM monitor on simulated 1800-s streams at 50 Hz.

Streams of :mod:`shipid.simulate.masscm_stream` (fishing vessel, 0.5 deg wave roll, gyro 0.002 rad/s and
accelerometer 0.02 m/s^2 noise, biases 0.001 / 0.01; 300-s nominal and calibration datasets; z_f known),
with a load change at 900 s from 0.4 kg at -0.182 m to 0.7 kg at -0.14 m, and without it.

``study``: Monte Carlo on the campaign engine (run i: SeedSequence([SEED, i]); change and no-change streams
are independent campaigns, seeds SEED and SEED+1): detection delays, false alarms, per-stream coverage of
±2 std of m and zm_bar from 300 s after the change (no change: from 300 s).
``speed``: processor time of the monitor on one 1800-s stream against the named peer, the offline
Algorithm 1 (:func:`shipid.methods.masscm.estimator.estimate_mass_cm`, noise check off) re-run on the 300-s window at
every update, timed on 5 updates and scaled to the 168 updates of the stream; real-time factor.
``memory``: tracemalloc peak while monitoring 600-, 1800- and 3600-s streams (flat = independent of length).
``tradeoff``: window 150 / 300 / 600 s on the same streams (std of the updates, coverage, delay).

The per-stream coverage study with the monitor's standard errors at both noise levels is a product command,
``shipid study monitor-coverage`` (:mod:`shipid.methods.monitor.coverage`); its figures are in
``docs/validation/monitor.md``.

Usage:  python benchmarks/bench_masscm_monitor.py study RUNS [SEED [combined|waves-only [ar|auto [RESELECT]]]]
        python benchmarks/bench_masscm_monitor.py speed | memory | tradeoff [RUNS]
        python benchmarks/bench_masscm_monitor.py --smoke     (speed on a 700-s stream, one peer update)
"""

import json
import sys
import time
import tracemalloc
import warnings

import numpy as np

from shipid.campaign.engine import run_campaign

TASK = "_monitor_study:monitor_run"   # benchmarks/_monitor_study.py (this folder is on sys.path; in-process runs)


def study(runs: int, seed: int, noise: str = "combined", noise_model: str | None = None, reselect: int = 0) -> None:
    extra = {"noise_model": noise_model, "bj_reselect": reselect}
    for label, kw, sd in (("change at 900 s", {"change_at": 900.0, "noise": noise, **extra}, seed),
                          ("no change", {"change_at": None, "noise": noise, **extra}, seed + 1)):
        from _monitor_study import summarise
        res = run_campaign(TASK, runs, seed=sd, kwargs=kw, workers=1, progress=False)
        recs = [r.outputs for r in res.records if r.status == "ok"]
        failed = runs - len(recs)
        s = summarise(recs, kw["change_at"] is not None)
        print(f"{label}, noise {noise}, noise model {noise_model or 'default'} (reselect {reselect}) "
              f"(campaign seed {sd}, {runs} runs, {failed} failed):")
        for r in res.records:
            if r.status != "ok":
                print(f"    failed: {str(getattr(r, 'error', r.status))[:160]}")
        print("  " + json.dumps(s))
        for i, r in enumerate(recs):
            print(f"    run {i}: alarms {r['alarms']} located {r['located']} cov m {r['coverage_m']:.2f} "
                  f"zm {r['coverage_zm']:.2f} maxT before {r['max_T_before']:.1f} cpu {r['cpu_s']:.1f} s")


def speed(duration: float = 1800.0, k: int = 5) -> None:
    from shipid.io.trial import Trial
    from shipid.methods.masscm.estimator import MassCMOptions, estimate_mass_cm
    from shipid.methods.monitor.estimator import run_monitor
    from shipid.models.roll_reduced import KnownParams
    from shipid.simulate.masscm_stream import StreamSpec, simulate_stream

    kn = KnownParams.from_vessel()
    sim = simulate_stream(StreamSpec() if duration == 1800.0 else
                          StreamSpec(duration=duration, change_at=None), seed=2026)
    c0, w0 = time.process_time(), time.perf_counter()
    ups = run_monitor(sim["nominal"], sim["calibration"], sim["stream"], kn, -0.028)
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    st = sim["stream"]
    n_upd = sum(u.m is not None for u in ups)
    c1 = time.process_time()
    for j in range(k):
        a = 300 + 100 * j
        sl = slice(a * 50, (a + 300) * 50)
        L = Trial(st.t[sl] - st.t[sl][0], {c: st[c][sl] for c in ("p", "a_s", "r", "delta")})
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            estimate_mass_cm([("nominal", sim["nominal"]), ("calibration", sim["calibration"]), ("loaded", L)],
                             kn, z_f=-0.028, noise_check=False, options=MassCMOptions())
    peer = (time.process_time() - c1) / k * n_upd
    print(f"monitor: {duration:g} s of 50-Hz stream, {n_upd} updates: cpu {cpu:.2f} s, wall {wall:.2f} s "
          f"-> {duration / cpu:.0f}x real time (cpu; target >= 100x)")
    print(f"peer (offline Algorithm 1 on the 300-s window at every update, {k} timed): cpu {peer:.1f} s "
          f"-> monitor is {peer / cpu:.1f}x faster")


def memory() -> None:
    from shipid.methods.monitor.estimator import MassCMMonitor
    from shipid.models.roll_reduced import KnownParams
    from shipid.simulate.masscm_stream import StreamSpec, simulate_stream

    kn = KnownParams.from_vessel()
    for dur in (200.0, 600.0, 1800.0, 3600.0):      # the first (200 s) warms up imports and caches, not shown
        sim = simulate_stream(StreamSpec(duration=dur, change_at=None), seed=7)
        mon = MassCMMonitor(sim["nominal"], sim["calibration"], kn, -0.028)
        mon.keep_updates = False
        st = sim["stream"]
        tracemalloc.start()
        n = 0
        for a in range(0, len(st.t), 500):
            s = slice(a, a + 500)
            n += len(mon.feed(st.t[s], st["p"][s], st["a_s"][s], st["r"][s], st["delta"][s]))
        cur, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        if dur == 200.0:
            continue
        print(f"stream {dur:5.0f} s: {n} updates, traced memory now {cur / 2**20:.2f} MiB, peak {peak / 2**20:.2f} MiB"
              f" (the stream itself, fed in chunks, is not counted)")


def tradeoff(runs: int) -> None:
    from _monitor_study import summarise
    for w in (150.0, 300.0, 600.0):
        for label, kw, sd in (("change", {"change_at": 900.0}, 31), ("no change", {"change_at": None}, 32)):
            res = run_campaign(TASK, runs, seed=sd, kwargs={**kw, "window": w}, workers=1, progress=False)
            recs = [r.outputs for r in res.records if r.status == "ok"]
            s = summarise(recs, kw["change_at"] is not None)
            keep = {k: (round(s[k], 4) if isinstance(s[k], float) else s[k])
                    for k in ("false_alarms", "coverage_m_mean", "coverage_zm_mean", "streams_both_ge_90",
                              "m_std_mean", "m_err_rms", "zm_std_mean", "zm_err_rms", "max_T_before", "delay_max",
                              "delay_mean") if k in s}
            print(f"window {w:4.0f} s, {label}, {runs} runs: {json.dumps(keep)}")


if __name__ == "__main__":
    mode = sys.argv[1] if len(sys.argv) > 1 else "speed"
    if mode == "--smoke":
        speed(700.0, 1)
    elif mode == "study":
        study(int(sys.argv[2]) if len(sys.argv) > 2 else 10, int(sys.argv[3]) if len(sys.argv) > 3 else 100,
              sys.argv[4] if len(sys.argv) > 4 else "combined", sys.argv[5] if len(sys.argv) > 5 else None,
              int(sys.argv[6]) if len(sys.argv) > 6 else 0)
    elif mode == "speed":
        speed()
    elif mode == "memory":
        memory()
    elif mode == "tradeoff":
        tradeoff(int(sys.argv[2]) if len(sys.argv) > 2 else 4)
    else:
        raise SystemExit(__doc__)
