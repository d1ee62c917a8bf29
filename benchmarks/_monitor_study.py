"""Monte Carlo study of the online mass / CM monitor (:mod:`shipid.methods.monitor.estimator`).

One run (:func:`monitor_run`, a task of :func:`shipid.campaign.engine.run_campaign`): a fresh stream of
:func:`shipid.simulate.masscm_stream.simulate_stream` (its own nominal and calibration datasets, noise and
load truth, none of which the monitor is told beyond ``known.toml`` and z_f) through the monitor; returns
the alarm times, the detection delay, the located change time, the coverage of the ±2 std intervals of
``m`` and ``zm_bar`` from ``settle`` seconds after the change (or after the start-up when there is no
change) and the processor time. :func:`summarise` aggregates the runs.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import replace

import numpy as np

from shipid.methods.monitor.estimator import MonitorOptions, run_monitor
from shipid.models.roll_reduced import KnownParams
from shipid.models.roll_sim import NoiseSpec
from shipid.simulate.masscm_stream import StreamSpec, simulate_stream, truth_at
from shipid.vessels import load_vessel


def monitor_run(i: int, seed=0, *, change_at: float | None = 900.0, duration: float = 1800.0,
                m1: float = 0.7, zm1: float = -0.14, settle: float = 300.0, window: float = 300.0,
                threshold: float | None = None, vessel: str = "fishing-vessel", noise: str = "combined",
                noise_model: str | None = None, bj_reselect: int = 0) -> dict:
    """One stream through the monitor; see the module docstring.

    ``noise``: ``"combined"`` (0.5 deg wave roll, gyro / accelerometer noise and biases) or ``"waves-only"``
    (the same wave roll, noise-free sensors: the case where the AR(40) prefilter of the offline
    estimator is known to fail, :mod:`shipid.methods.masscm.estimator` "Known limitations").
    ``noise_model``: the monitor's ``masscm.noise_model`` ("ar", or "auto" for the Box-Jenkins prefilter;
    None: the monitor's default); ``bj_reselect``: :class:`MonitorOptions` ``bj_reselect``.
    """

    spec_noise = {"combined": NoiseSpec.combined(), "waves-only": NoiseSpec(wave_roll_deg=0.5)}[noise]
    ss = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence([int(seed), int(i)])
    sim = simulate_stream(StreamSpec(duration=duration, change_at=change_at, m1=m1, zm1=zm1, noise=spec_noise),
                          vessel=vessel, seed=ss)
    kw = {"window": window, "bj_reselect": bj_reselect}
    if threshold is not None:
        kw["threshold"] = threshold
    if noise_model is not None:
        kw["masscm"] = replace(MonitorOptions().masscm, noise_model=noise_model)
    opts = MonitorOptions(**kw)
    z_f = float(load_vessel(vessel).value("general", "z_f"))
    c0, w0 = time.process_time(), time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        ups = run_monitor(sim["nominal"], sim["calibration"], sim["stream"], KnownParams.from_vessel(vessel), z_f,
                          opts)
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    alarms = [u.t for u in ups if u.alarm]
    located = [u.change_at for u in ups if u.alarm]
    t_from = (change_at if change_at is not None else 0.0) + settle
    ok = [u for u in ups if u.m is not None and u.t >= t_from]
    mt, zt = truth_at(sim["truth"], [u.t for u in ok])
    # an update with a non-finite std does not cover (it gives no interval)
    in_m = [bool(np.isfinite(u.m_std)) and abs(u.m - a) <= 2 * u.m_std for u, a in zip(ok, mt)]
    in_z = [bool(np.isfinite(u.zm_bar_std)) and abs(u.zm_bar - a) <= 2 * u.zm_bar_std for u, a in zip(ok, zt)]
    kn = KnownParams.from_vessel(vessel)
    rt = np.asarray(mt) * (np.asarray(zt) + z_f) / (kn.m_c * (kn.zc_bar + z_f))
    in_r = [bool(np.isfinite(u.rho_std)) and abs(u.rho - a) <= 2 * u.rho_std for u, a in zip(ok, rt)]
    pre = [u.statistic for u in ups if u.statistic is not None and (change_at is None or u.t <= change_at)]
    after = [a for a in alarms if change_at is not None and a > change_at]
    return {"alarms": alarms, "located": located,
            "false_alarms": len([a for a in alarms if change_at is None or a <= change_at]),
            "delay": (after[0] - change_at) if after else None,
            "located_first": (located[alarms.index(after[0])] if after else None),
            "coverage_m": float(np.mean(in_m)) if ok else None, "coverage_zm": float(np.mean(in_z)) if ok else None,
            "coverage_rho": float(np.mean(in_r)) if ok else None,
            "n_cov": len(ok),
            "m_std_mean": float(np.mean([u.m_std for u in ok])) if ok else None,
            "zm_std_mean": float(np.mean([u.zm_bar_std for u in ok])) if ok else None,
            "m_err_rms": float(np.sqrt(np.mean([(u.m - a) ** 2 for u, a in zip(ok, mt)]))) if ok else None,
            "zm_err_rms": float(np.sqrt(np.mean([(u.zm_bar - a) ** 2 for u, a in zip(ok, zt)]))) if ok else None, "max_T_before": float(max(pre)) if pre else None,
            "converged_frac": float(np.mean([u.converged for u in ok])) if ok else None,
            "m_last": ok[-1].m if ok else None, "m_last_std": ok[-1].m_std if ok else None,
            "zm_last": ok[-1].zm_bar if ok else None, "zm_last_std": ok[-1].zm_bar_std if ok else None,
            "rho_last": ok[-1].rho if ok else None, "rho_last_std": ok[-1].rho_std if ok else None,
            "rho_true_last": float(rt[-1]) if ok else None, "m_true_last": float(mt[-1]) if ok else None, "zm_true_last": float(zt[-1]) if ok else None,
            "cpu_s": cpu, "wall_s": wall, "stream_s": duration}


def summarise(records: list[dict], change: bool) -> dict:
    """Aggregate :func:`monitor_run` outputs: alarms, delays, per-stream coverage, speed."""
    n = len(records)
    fa = sum(r["false_alarms"] for r in records)
    out = {"runs": n, "false_alarms": fa, "streams_with_false_alarm": sum(r["false_alarms"] > 0 for r in records),
           "hours": n * records[0]["stream_s"] / 3600 if n else 0.0,
           "coverage_m_mean": float(np.mean([r["coverage_m"] for r in records])),
           "coverage_zm_mean": float(np.mean([r["coverage_zm"] for r in records])),
           "coverage_rho_mean": float(np.mean([r["coverage_rho"] for r in records])),
           "streams_coverage_rho_ge_90": sum(r["coverage_rho"] >= 0.9 for r in records),
           "rho_err_last_rms": float(np.sqrt(np.mean([(r["rho_last"] - r["rho_true_last"]) ** 2 for r in records]))),
           "rho_std_last_median": float(np.median([r["rho_last_std"] for r in records])),
           "m_err_last_rms": float(np.sqrt(np.mean([(r["m_last"] - r["m_true_last"]) ** 2 for r in records]))),
           "m_std_last_median": float(np.median([r["m_last_std"] for r in records])),
           "zm_err_last_rms": float(np.sqrt(np.mean([(r["zm_last"] - r["zm_true_last"]) ** 2 for r in records]))),
           "zm_std_last_median": float(np.median([r["zm_last_std"] for r in records])),
           "streams_coverage_m_ge_90": sum(r["coverage_m"] >= 0.9 for r in records),
           "streams_coverage_zm_ge_90": sum(r["coverage_zm"] >= 0.9 for r in records),
           "streams_both_ge_90": sum(r["coverage_m"] >= 0.9 and r["coverage_zm"] >= 0.9 for r in records),
           "max_T_before": float(max(r["max_T_before"] for r in records)),
           "m_std_mean": float(np.mean([r["m_std_mean"] for r in records])),
           "m_err_rms": float(np.sqrt(np.mean([r["m_err_rms"] ** 2 for r in records]))),
           "zm_std_mean": float(np.mean([r["zm_std_mean"] for r in records])),
           "zm_err_rms": float(np.sqrt(np.mean([r["zm_err_rms"] ** 2 for r in records]))),
           "cpu_s_max": float(max(r["cpu_s"] for r in records)), "cpu_s_mean": float(np.mean([r["cpu_s"] for r in records]))}
    if change:
        d = [r["delay"] for r in records if r["delay"] is not None]
        out.update({"detected": len(d), "delay_max": float(max(d)) if d else None,
                    "delay_mean": float(np.mean(d)) if d else None,
                    "detected_within_120": sum(x <= 120 for x in d),
                    "located": [r["located_first"] for r in records]})
    return out


__all__ = ["monitor_run", "summarise"]
