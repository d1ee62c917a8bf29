"""Per-stream coverage study of the online mass / CM monitor (:mod:`shipid.methods.monitor.estimator`).

A ship has one stream, so the question is not whether the ±2-std bands of the monitor's updates cover the
truth on average over many streams but whether they cover it *within* each stream. Each run (a task of
:func:`shipid.campaign.engine.run_campaign`, seed ``SeedSequence([seed, i])``) simulates a fresh stream with
:func:`shipid.simulate.masscm_stream.simulate_stream`: its own nominal and calibration datasets, rudder, wave
roll and sensor noise, the fishing vessel at 50 Hz, the noise of
:meth:`shipid.models.roll_sim.NoiseSpec.combined` times ``noise_scale`` (every std, bias and the wave roll
scaled alike). With ``change`` the load changes at half the stream from 0.4 kg at -0.182 m to 0.7 kg at
-0.14 m, otherwise it stays at 0.4 kg. The monitor runs with its defaults; it is told neither the noise
levels nor the truth (only the known parameters and ``z_f`` of the vessel file, as a user gives them).

Per stream: the fraction of updates from ``settle`` s after the change (after the stream's start without a
change) whose ±2-std interval holds the truth, for ``m`` and ``zm_bar`` (an update without a finite std does
not cover); the alarm times, the delay of the first alarm after the change, the false alarms (at or before
the change). :func:`summarise` reports the fraction of streams with at least 90 % of their updates covered
(for each quantity and for both), the pooled coverage, the detection delays and the false alarms, the
processor time per stream as a multiple of real time, and ``std_factor_needed``: the factor by which every
reported std would have to grow for the 90 % target to hold in 90 % of the streams (per stream, the 90th
percentile of ``|error| / (2 std)`` over its updates, the larger of ``m`` and ``zm_bar``; over the streams, its
90th percentile).

Measured figures and the commands that produced them: ``docs/validation/monitor.md``.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import fields, replace

import numpy as np

from shipid.campaign.engine import CampaignOptions
from shipid.methods.monitor.estimator import MonitorOptions, run_monitor
from shipid.models.roll_reduced import KnownParams
from shipid.models.roll_sim import NoiseSpec
from shipid.simulate.masscm_stream import StreamSpec, simulate_stream, truth_at
from shipid.vessels import load_vessel

#: Fraction of a stream's updates that must be covered for the stream to count as covered.
STREAM_TARGET = 0.9
_SCALED = ("gyro_std", "acc_std", "gyro_bias", "acc_bias", "wave_roll_deg")


def scaled_noise(scale: float) -> NoiseSpec:
    """:meth:`NoiseSpec.combined` with every noise std, bias and the wave roll std multiplied by ``scale``."""
    base = NoiseSpec.combined()
    return NoiseSpec(**{f.name: getattr(base, f.name) * (scale if f.name in _SCALED else 1.0)
                        for f in fields(NoiseSpec)})


def run_stream(i: int, seed=0, *, change: bool = True, noise_scale: float = 1.0, duration: float = 1800.0,
               settle: float = 300.0, covariance: str = "sandwich", vessel: str = "fishing-vessel") -> dict:
    """One fresh stream through :func:`shipid.methods.monitor.estimator.run_monitor`; see the module docstring."""
    ss = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence([int(seed), int(i)])
    change_at = 0.5 * duration if change else None
    spec = StreamSpec(duration=duration, change_at=change_at, noise=scaled_noise(noise_scale))
    sim = simulate_stream(spec, vessel=vessel, seed=ss)
    z_f = float(load_vessel(vessel).value("general", "z_f"))
    c0 = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        ups = run_monitor(sim["nominal"], sim["calibration"], sim["stream"], KnownParams.from_vessel(vessel), z_f,
                          MonitorOptions(covariance=covariance))
    cpu = time.process_time() - c0
    alarms = [float(u.t) for u in ups if u.alarm]
    t_from = (change_at or 0.0) + settle
    ok = [u for u in ups if u.m is not None and u.t >= t_from]
    mt, zt = truth_at(sim["truth"], [u.t for u in ok])
    z_m = [(u.m - a) / u.m_std if u.m_std and np.isfinite(u.m_std) else float("inf") for u, a in zip(ok, mt)]
    z_z = [(u.zm_bar - a) / u.zm_bar_std if u.zm_bar_std and np.isfinite(u.zm_bar_std) else float("inf")
           for u, a in zip(ok, zt)]
    after = [a for a in alarms if change_at is not None and a > change_at]
    cov = {k: (float(np.mean(np.abs(z) <= 2.0)) if z else None) for k, z in (("m", z_m), ("zm_bar", z_z))}
    q90 = max(float(np.quantile(np.abs(z), 0.9)) for z in (z_m, z_z)) / 2.0 if ok else float("inf")
    return {"change_at": change_at, "t_from": t_from, "updates": len(ok), "std_factor_90": q90,
            "coverage_m": cov["m"], "coverage_zm_bar": cov["zm_bar"],
            "z_m": [float(x) for x in z_m], "z_zm_bar": [float(x) for x in z_z],
            "m_std_mean": float(np.mean([u.m_std for u in ok])) if ok else None,
            "zm_bar_std_mean": float(np.mean([u.zm_bar_std for u in ok])) if ok else None,
            "m_err_rms": float(np.sqrt(np.mean((np.array([u.m for u in ok]) - mt) ** 2))) if ok else None,
            "zm_bar_err_rms": float(np.sqrt(np.mean((np.array([u.zm_bar for u in ok]) - zt) ** 2))) if ok else None,
            "alarms": alarms, "false_alarms": len([a for a in alarms if change_at is None or a <= change_at]),
            "delay": (after[0] - change_at) if after else None,
            "located": next((float(u.change_at) for u in ups if u.alarm and u.t > (change_at or 0.0)), None),
            "cpu_s": cpu, "stream_s": duration}


def summarise(records: list[dict | None]) -> dict:
    """Aggregate :func:`run_stream` outputs (None: a failed run, counted and never covered)."""
    ok = [r for r in records if r is not None and r["updates"] > 0]
    n = len(records)

    def frac(pred):
        return sum(1 for r in ok if pred(r)) / n if n else None
    cov = {q: [r[f"coverage_{q}"] for r in ok] for q in ("m", "zm_bar")}
    zs = {q: np.concatenate([r[f"z_{q}"] for r in ok]) if ok else np.zeros(0) for q in ("m", "zm_bar")}
    out = {"streams": n, "failed": n - len(ok),
           "streams_ge90_m": frac(lambda r: r["coverage_m"] >= STREAM_TARGET),
           "streams_ge90_zm_bar": frac(lambda r: r["coverage_zm_bar"] >= STREAM_TARGET),
           "streams_ge90_both": frac(lambda r: min(r["coverage_m"], r["coverage_zm_bar"]) >= STREAM_TARGET),
           "pooled_m": float(np.mean(np.abs(zs["m"]) <= 2)) if ok else None,
           "pooled_zm_bar": float(np.mean(np.abs(zs["zm_bar"]) <= 2)) if ok else None,
           "worst_m": float(min(cov["m"])) if ok else None, "worst_zm_bar": float(min(cov["zm_bar"])) if ok else None,
           "rms_z_m": float(np.sqrt(np.mean(zs["m"][np.isfinite(zs["m"])] ** 2))) if ok else None,
           "rms_z_zm_bar": float(np.sqrt(np.mean(zs["zm_bar"][np.isfinite(zs["zm_bar"])] ** 2))) if ok else None,
           "std_factor_needed": float(np.quantile([r["std_factor_90"] for r in ok] + [np.inf] * (n - len(ok)),
                                                  STREAM_TARGET)) if n else None,
           "false_alarms": sum(r["false_alarms"] for r in ok),
           "streams_with_false_alarm": sum(r["false_alarms"] > 0 for r in ok),
           "stream_hours": sum(r["stream_s"] for r in ok) / 3600.0,
           "cpu_s_mean": float(np.mean([r["cpu_s"] for r in ok])) if ok else None,
           "realtime_min": float(min(r["stream_s"] / r["cpu_s"] for r in ok)) if ok else None}
    ch = [r for r in ok if r["change_at"] is not None]
    if ch:
        d = [r["delay"] for r in ch if r["delay"] is not None]
        out.update({"detected": len(d), "detected_within_120": sum(x <= 120.0 for x in d),
                    "delay_mean": float(np.mean(d)) if d else None, "delay_max": float(max(d)) if d else None})
    return out


def run_cases(streams: int, noise_scales=(1.0, 0.1), *, duration: float = 1800.0, settle: float = 300.0,
              covariance: str = "sandwich", campaign=None) -> dict:
    """Every case (noise scale x change / no change) as one campaign of ``streams`` runs of :func:`run_stream`.

    Case ``k`` (in the order noise scale, then with / without a change) runs with campaign seed
    ``campaign.seed + k``, so that no two cases share a stream. ``campaign``: a
    :class:`shipid.campaign.engine.CampaignOptions` (seed, workers, store); default in this process.
    Returns the summaries of :func:`summarise` per case with the per-stream coverages, the campaigns'
    failure lines (``failures``) and ``warnings`` (a case whose target is missed is not a warning: it is
    the result).
    """
    campaign = campaign or CampaignOptions(workers=1, progress=False)
    t0 = time.perf_counter()
    cases, failures = [], []
    k = 0
    for scale in noise_scales:
        for change in (True, False):
            kw = {"change": change, "noise_scale": float(scale), "duration": float(duration),
                  "settle": float(settle), "covariance": covariance}
            res = replace(campaign, seed=campaign.seed + k).run("shipid.methods.monitor.coverage:run_stream",
                                                                 streams, kwargs=kw, name="monitor-coverage")
            k += 1
            if res.n_failed:
                failures.append(f"monitor-coverage, noise x{scale:g}, {'change' if change else 'no change'}: "
                                f"{res.n_failed} of {res.n_runs} streams failed (counted as not covered): "
                                f"{res.failed_text()}")
            outs = [r.outputs if r.status == "ok" else None for r in res.records]
            cases.append({"noise_scale": float(scale), "change": change, "seed": campaign.seed + k - 1,
                          "summary": summarise(outs),
                          "per_stream": [None if o is None else
                                         {"coverage_m": o["coverage_m"], "coverage_zm_bar": o["coverage_zm_bar"],
                                          "std_factor_90": o["std_factor_90"], "alarms": o["alarms"],
                                          "cpu_s": round(o["cpu_s"], 3)} for o in outs]})
    return {"streams": streams, "duration": float(duration), "settle": float(settle), "covariance": covariance,
            "seed": campaign.seed, "stream_target": STREAM_TARGET, "cases": cases, "failures": failures,
            "warnings": [], "wall_s": time.perf_counter() - t0}


__all__ = ["STREAM_TARGET", "scaled_noise", "run_stream", "summarise", "run_cases"]
