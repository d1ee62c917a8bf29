"""A packaged vessel through a standard manoeuvre: ``shipid.simulate(vessel, manoeuvre, ...)``."""

from __future__ import annotations

import numpy as np

from shipid.io.trial import Trial
from shipid.simulate.manoeuvres import run_manoeuvre
from shipid.simulate.noise import default_measurement_model
from shipid.simulate.registry import get_ship_model


def simulate_vessel(vessel: str, manoeuvre: str, *, duration: float | None = None, dt: float = 0.1,
                    seed: int = 0, speed: float | None = None, noise: bool = False) -> Trial:
    """Run a packaged vessel through a standard manoeuvre (``shipid simulate VESSEL MANOEUVRE``).

    ``manoeuvre`` as the CLI takes it: ``straight``, ``turning-35[-port]``, ``zigzag-20``,
    ``zigzag-10-5``, ``prbs-10[-T]``, ``dp-surge``, ``dp-sway-yaw``, ``dp-azimuth``. With ``noise`` the
    default measurement model is applied with the random stream ``(seed, 1)``, as the CLI does.
    """
    trial = run_manoeuvre(get_ship_model(vessel), manoeuvre, duration=duration, dt=dt, seed=seed, speed=speed)
    if noise:
        trial = default_measurement_model().apply(trial, np.random.default_rng([seed, 1]), missing_ok=True)
    return trial


__all__ = ["simulate_vessel"]
