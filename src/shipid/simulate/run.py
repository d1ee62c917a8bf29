"""A packaged vessel through a standard manoeuvre: ``shipid.simulate(vessel, manoeuvre, ...)``."""

from __future__ import annotations

import numpy as np

from shipid.io.trial import Trial
from shipid.simulate.manoeuvres import run_manoeuvre
from shipid.simulate.noise import default_measurement_model
from shipid.simulate.registry import get_ship_model
from shipid.simulate.trials import has_trial_conditions, simulate_measured
from shipid.vessels import load_vessel

#: Sample interval of a vessel whose file names none (``[trials].dt``), s.
DEFAULT_DT = 0.1


def default_dt(vessel: str) -> float:
    """The sample interval of ``vessel``'s trials: its file's ``[trials].dt``, else :data:`DEFAULT_DT`."""
    try:
        v = load_vessel(vessel)
    except Exception:  # noqa: BLE001 - generic models and unknown names: the simulator reports those
        return DEFAULT_DT
    trials = v.sections.get("trials") or {}
    return float(v.value("trials", "dt")) if "dt" in trials else DEFAULT_DT


def simulate_vessel(vessel: str, manoeuvre: str, *, duration: float | None = None, dt: float | None = None,
                    seed: int = 0, speed: float | None = None, noise: bool = False, progress=None) -> Trial:
    """Run a packaged vessel through a standard manoeuvre (``shipid simulate VESSEL MANOEUVRE``).

    ``manoeuvre`` as the CLI takes it: ``straight``, ``turning-35[-port]``, ``zigzag-20``,
    ``zigzag-10-5``, ``prbs-10[-T]``, ``prbs-35-105``, ``dp-surge``, ``dp-sway-yaw``, ``dp-azimuth``.

    A vessel whose file states how its trials are measured (``[trials]``: ESSO OSAKA, Yoon & Rhee 2003
    §5.1) is simulated as those trials are (:func:`shipid.simulate.trials.simulate_measured`): sampled
    every ``[trials].dt`` (1 s), integrated at a fifth of it, in the current of the trial conditions,
    recorded by the sensors of eq. 8 and, with ``noise``, with the noise of eq. 19 (random stream
    ``seed + 1000``) — the records EBM identifies from. Any other vessel is sampled every ``dt``
    (default :func:`default_dt`) and, with ``noise``, gets the default measurement model with the random
    stream ``(seed, 1)``. ``progress(k)`` is called with the integration steps done.
    """
    if has_trial_conditions(vessel):
        return simulate_measured(manoeuvre, duration, seed=seed, dt=dt, noise=noise, vessel=vessel, speed=speed,
                                 progress=progress)
    dt = default_dt(vessel) if dt is None else float(dt)
    trial = run_manoeuvre(get_ship_model(vessel), manoeuvre, duration=duration, dt=dt, seed=seed, speed=speed,
                          progress=progress)
    if noise:
        trial = default_measurement_model().apply(trial, np.random.default_rng([seed, 1]), missing_ok=True)
    return trial


__all__ = ["simulate_vessel", "default_dt", "DEFAULT_DT"]
