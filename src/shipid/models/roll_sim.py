"""Synthetic nominal, calibration and loaded datasets of Linder et al. (2015) §5 (and noisy variants).

The ship is the linear model (11) of :mod:`shipid.models.roll`, simulated exactly (zero-order hold)
at 50 Hz for 60 s by default. The paper's study has no disturbances; :class:`NoiseSpec` adds what
the paper left out ("beyond the paper"): white gyro / accelerometer noise, constant sensor
biases (9) and a wave-like coloured roll moment ``tau`` scaled to a chosen roll standard deviation.

Rudder excitation: the paper only shows the nominal rudder signal (Fig. 3). We use a pseudo-random
binary rudder of amplitude ``delta_amp`` that may switch every ``delta_clock`` seconds (an
independent seeded realisation per dataset), which excites the roll mode and the yaw coupling.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shipid.io.trial import Trial
from shipid.numerics.iir_kernels import lfilter
from shipid.models.roll import RollShipParams, imu_outputs, params_from_vessel, simulate_zoh
from shipid.models.roll_reduced import CALIBRATION, LOADED, NOMINAL, bilinear_tf
from shipid.vessels import load_vessel


@dataclass(frozen=True)
class NoiseSpec:
    """Sensor noise, biases (eq. 9) and the wave roll disturbance.

    Attributes
    ----------
    gyro_std : float
        White noise std on the roll- and yaw-rate gyros (rad/s).
    acc_std : float
        White noise std on the tangential accelerometer (m/s^2).
    gyro_bias, acc_bias : float
        Constant biases b_1 = b_3 (rad/s) and b_2 (m/s^2).
    wave_roll_deg : float
        Standard deviation of the roll angle caused by the waves alone (deg); 0 = no waves.
    wave_period : float
        Peak period of the wave moment (s).
    wave_damping : float
        Relative damping of the second-order wave filter (narrow band for small values).
    """

    gyro_std: float = 0.0
    acc_std: float = 0.0
    gyro_bias: float = 0.0
    acc_bias: float = 0.0
    wave_roll_deg: float = 0.0
    wave_period: float = 1.0
    wave_damping: float = 0.1

    @classmethod
    def combined(cls) -> "NoiseSpec":
        """Sensor noise, sensor biases and wave roll together, the disturbances of the IMU outputs (9).

        White noise 0.002 rad/s on the roll- and yaw-rate gyros and 0.02 m/s^2 on the tangential
        accelerometer, biases b_1 = b_3 = 0.001 rad/s and b_2 = 0.01 m/s^2, and a 0.5 deg (std) wave roll:
        the noise of the mass-cm simulated trials, efficiency bounds and coverage (``both``).
        """
        return cls(gyro_std=0.002, acc_std=0.02, gyro_bias=0.001, acc_bias=0.01, wave_roll_deg=0.5)

    @property
    def is_zero(self) -> bool:
        return (self.gyro_std == 0 and self.acc_std == 0 and self.gyro_bias == 0 and self.acc_bias == 0
                and self.wave_roll_deg == 0)


def rudder_prbs(n: int, dt: float, amp: float, clock: float, rng: np.random.Generator,
                rate: float = np.deg2rad(40.0)) -> np.ndarray:
    """Rate-limited pseudo-random binary rudder.

    The command is ``±amp`` with a fresh fair-coin sign every ``clock`` seconds; the rudder follows it
    at most at ``rate`` (rad/s), as a steering gear does. The samples are the breakpoints of a
    piecewise-linear signal (simulated with a first-order hold). A rate limit matters here: the
    reduced model is discretised by the bilinear transform (32), which assumes smooth signals; a
    step rudder puts a jump into ``a_s`` and a large equation error at every switch.
    """
    hold = max(1, int(round(clock / dt)))
    nblk = -(-n // hold)
    signs = np.where(rng.random(nblk) < 0.5, -1.0, 1.0)
    cmd = amp * np.repeat(signs, hold)[:n]
    out = np.empty(n)
    step = rate * dt
    x = 0.0
    for i in range(n):
        out[i] = x
        x += min(max(cmd[i] - x, -step), step)
    return out


def wave_moment(n: int, dt: float, spec: NoiseSpec, rng: np.random.Generator) -> np.ndarray:
    """Unit-scale narrow-band moment: white noise through ``2 z w s / (s^2 + 2 z w s + w^2)`` (Tustin)."""
    w = 2 * np.pi / spec.wave_period
    b, a = bilinear_tf([2 * spec.wave_damping * w, 0.0], [1.0, 2 * spec.wave_damping * w, w * w], dt)
    nburn = int(20 * spec.wave_period / dt)
    e = rng.standard_normal(n + nburn)
    return lfilter(b, a, e)[nburn:]


def simulate_condition(th: RollShipParams, *, duration: float = 60.0, fs: float = 50.0,
                       delta_amp: float = np.deg2rad(5.0), delta_clock: float = 0.5,
                       noise: NoiseSpec = NoiseSpec(), seed=0, condition: str = "") -> Trial:
    """One dataset (a :class:`Trial` with ``t, p, a_s, r, delta`` and the true ``phi``).

    Parameters
    ----------
    th : RollShipParams
        Ship and load of this dataset.
    seed : int or SeedSequence
        Seeds the rudder, waves and sensor noise (three independent streams).
    """
    dt = 1.0 / fs
    n = int(round(duration * fs))
    ss = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
    r_rud, r_wave, r_sens = (np.random.default_rng(s) for s in ss.spawn(3))
    delta = rudder_prbs(n, dt, delta_amp, delta_clock, r_rud)
    tau = np.zeros(n)
    if noise.wave_roll_deg > 0:
        w = wave_moment(n, dt, noise, r_wave)
        Xw, _ = simulate_zoh(th, np.zeros(n), dt, tau=w)
        tau = w * (np.deg2rad(noise.wave_roll_deg) / np.std(Xw[:, 0]))   # linear: rescale to target roll std
    X, Xdot = simulate_zoh(th, delta, dt, tau=tau)
    out = imu_outputs(th, X, Xdot)
    p = out["p"] + noise.gyro_bias + noise.gyro_std * r_sens.standard_normal(n)
    a_s = out["a_s"] + noise.acc_bias + noise.acc_std * r_sens.standard_normal(n)
    r = out["r"] + noise.gyro_bias + noise.gyro_std * r_sens.standard_normal(n)
    t = np.arange(n) * dt
    return Trial(t, {"p": p, "a_s": a_s, "r": r, "delta": delta, "phi": out["phi"]},
                 meta={"vessel": "fishing-vessel", "condition": condition, "simulated": True,
                       "noise": noise.__dict__ if hasattr(noise, "__dict__") else str(noise)})


def simulate_datasets(vessel="fishing-vessel", *, seed=0, duration: float | None = None,
                      fs: float | None = None, noise: NoiseSpec = NoiseSpec(),
                      delta_amp: float | None = None, delta_clock: float | None = None,
                      m: float | None = None, zm_bar: float | None = None) -> dict[str, Trial]:
    """The three datasets of §3.1 / §5: nominal, calibration and loaded.

    Defaults come from the vessel file (``[excitation]``: 60 s at 50 Hz, 5 deg PRBS rudder). Each
    dataset gets its own child of ``SeedSequence(seed)``.
    """
    v = load_vessel(vessel) if isinstance(vessel, str) else vessel
    ex = v.values("excitation")
    kw = dict(duration=ex["duration"] if duration is None else duration,
              fs=ex["fs"] if fs is None else fs,
              delta_amp=ex["delta_amp"] if delta_amp is None else delta_amp,
              delta_clock=ex["delta_clock"] if delta_clock is None else delta_clock, noise=noise)
    ss = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
    children = ss.spawn(3)
    out = {}
    for cond, child in zip((NOMINAL, CALIBRATION, LOADED), children):
        th = params_from_vessel(v, cond)
        if cond == LOADED and (m is not None or zm_bar is not None):
            th = th.loaded(th.m if m is None else m, th.zm_bar if zm_bar is None else zm_bar)
        out[cond] = simulate_condition(th, seed=child, condition=cond, **kw)
    return out


__all__ = ["NoiseSpec", "rudder_prbs", "wave_moment", "simulate_condition", "simulate_datasets"]
