"""Simulated DP sea trials of Fossen, Sagatun & Sørensen (1996) §4.2 for a DP vessel.

Three decoupled manoeuvres, each run (at least) twice (§4.2, Figs. 5–7):

1. *uncoupled surge*: main propellers p1 = p2 in steps, heading held by the bow tunnel
   thruster (p5) with a PD law, as in the paper;
2. *coupled sway and yaw*: the three tunnel thrusters p3, p4, p5 in independent steps;
   the heading is free to change (the kinematics are nonlinear);
3. *azimuth test*: the azimuth thruster alone (p6, α6 in steps).

The truth is the dimensional LF model of eq. 8 (:func:`shipid.models.dp.lf_dynamics`),
driven by the thrusters (eqs. 1–7) and a generalised disturbance force made of

* a drifting bias: a random walk with intensity ``q_b`` (bis force² per bis time) from a
  random initial value (std ``b0``), the slowly varying ``b_h`` of eq. 37 (body frame),
* optionally an earth-fixed current ``V_c`` entering as ``D J(ψ)ᵀ V_c`` (the ``D ν_c`` term
  of eq. 8; off by default),
* white process noise with intensity ``q_h`` (bis force² · bis time), ``w`` of eq. 8, held
  constant over each sample,

and measured with DGPS-like position noise ``sigma_pos`` and gyro-like heading noise
``sigma_psi``. Inputs and disturbances are held over each sample (zero-order hold), the
state is integrated with RK4 on ``substeps`` sub-steps per sample.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from shipid.io.trial import Trial
from shipid.models import dp
from shipid.models.thrusters import pitch_from_control
from shipid.numerics.integrate import rk4_step

#: Moment arm (in L) of the environmental yaw moment relative to the environmental forces.
YAW_ARM = 0.1
_COMP = np.array([1.0, 1.0, YAW_ARM])

#: The channels of a DP trial file (the CLI's contract).
DP_CHANNELS = ("x", "y", "psi", "p1", "p2", "p3", "p4", "p5", "p6", "alpha6")


@dataclass(frozen=True)
class TrialNoise:
    """Disturbance and sensor-noise levels of the simulated trials (defaults used by the study).

    Attributes
    ----------
    sigma_pos : float
        Position noise (1σ), m (DGPS class).
    sigma_psi : float
        Heading noise (1σ), rad (gyrocompass class; 0.25°).
    q_h : float
        Intensity of the white force noise w_h, bis force² × bis time; 1e-8 gives a force
        of 1e-4/sqrt(dt'') m g per sample, ≈ 10 kN for the supply vessel at 1 Hz.
    q_b : float
        Intensity of the bias random walk b_h, bis force² per bis time; 1e-10 drifts by
        ≈ 2e-4 m g (≈ 12 kN) over a 20-minute trial.
    b0 : float
        Standard deviation of the initial bias, bis force; 3e-4 m g ≈ 18 kN, a mean
        environmental force. The yaw component (and the yaw intensity of ``q_b``, ``q_h``)
        is scaled by :data:`YAW_ARM` (a moment arm of 0.1 L), so the bias moment stays
        within what the bow thruster can hold in the surge trials.
    current_speed : float
        Earth-fixed current speed, m/s (direction drawn at random per trial). Default 0:
        the paper's estimator model (eqs. 35–38) has only the body-fixed bias b_h, which
        cannot follow a current force that turns with the heading in the sway-yaw and
        azimuth trials; see :class:`shipid.methods.dp.estimator.DPOptions.current_states`.
    bias_tau : float or None
        None (default): the bias is the random walk of eq. 37 (intensity ``q_b``). A time in s:
        the bias wanders as a first-order Gauss-Markov process with that correlation time and
        stationary std ``b0`` (``q_b`` unused), a disturbance the estimator's random-walk model
        (eq. 37) does not describe exactly (``shipid study dp-coverage``).
    """

    sigma_pos: float = 0.5
    sigma_psi: float = float(np.deg2rad(0.25))
    q_h: float = 1e-8
    q_b: float = 1e-10
    b0: float = 3e-4
    current_speed: float = 0.0
    bias_tau: float | None = None

    def as_dict(self) -> dict:
        return asdict(self)


def _steps(rng, n: int, dt: float, dur: tuple[float, float], draw) -> np.ndarray:
    """Piecewise-constant sequence on n samples: segments of random length, values from ``draw(i)``."""
    out = np.empty(n)
    k = 0
    i = 0
    while k < n:
        m = max(1, int(round(rng.uniform(*dur) / dt)))
        out[k:k + m] = draw(i)
        k += m
        i += 1
    return out


def simulate_dp_trial(vessel: dp.DPVessel, kind: str, duration: float, seed: int, *, dt: float = 1.0,
                      noise: TrialNoise = TrialNoise(), substeps: int = 2, pattern: str = "random") -> Trial:
    """Simulate one trial of §4.2 (``kind`` = ``"surge"``, ``"sway-yaw"`` or ``"azimuth"``).

    ``pattern`` (sway-yaw only): ``"random"`` (p3, p4, p5 in independent steps), ``"sway"``
    (p3 = p4 = p5: all tunnel thrusters push the same way, mostly sway force) or ``"yaw"``
    (p3 = p4 = −p5: aft and bow push opposite ways, mostly yaw moment). The two single-signal
    patterns are the "different excitation sequences" of §3.2.

    Returns a :class:`Trial` with the channels :data:`DP_CHANNELS` (SI) and, in ``meta``,
    the seed, kind, noise levels, current and true θ.
    """
    rng = np.random.default_rng(seed)
    n = int(round(duration / dt)) + 1
    t = np.arange(n) * dt
    par = dp.lf_params(vessel)
    b = vessel.bis
    P = np.zeros((n, 6))
    alpha = np.full(n, np.pi / 2)
    sign = rng.choice([-1.0, 1.0])
    if kind == "surge":
        lev = _steps(rng, n, dt, (80.0, 160.0), lambda i: sign * (-1) ** i * rng.uniform(0.2, 0.45))
        P[:, 0] = P[:, 1] = lev
    elif kind == "sway-yaw" and pattern == "random":
        for j in (2, 3, 4):
            P[:, j] = _steps(rng, n, dt, (60.0, 150.0), lambda i: rng.uniform(-0.7, 0.7))
    elif kind == "sway-yaw" and pattern in ("sway", "yaw"):
        sgl = _steps(rng, n, dt, (60.0, 150.0), lambda i: rng.uniform(-0.7, 0.7))
        P[:, 2] = P[:, 3] = sgl if pattern == "sway" else -sgl
        P[:, 4] = sgl
    elif kind == "azimuth":
        P[:, 5] = _steps(rng, n, dt, (80.0, 160.0), lambda i: rng.choice([-1, 1]) * rng.uniform(0.3, 0.8))
        alpha = _steps(rng, n, dt, (80.0, 160.0), lambda i: rng.uniform(-np.pi, np.pi))
    else:
        raise ValueError(f"unknown DP trial kind {kind!r}")
    psi0 = rng.uniform(-np.pi, np.pi)
    beta = rng.uniform(-np.pi, np.pi)
    Vc = noise.current_speed * np.array([np.cos(beta), np.sin(beta), 0.0])
    dtb = dt / b.time  # sample interval in bis time
    bias = rng.normal(scale=noise.b0, size=3) * _COMP
    x = np.zeros(9)
    x[2] = psi0
    X = np.empty((n, 9))
    # heading PD for the surge trial (bow tunnel thruster), gains for ω ≈ 0.5 (bis), ζ ≈ 0.8
    m33 = vessel.M[2, 2]
    kp, kd = m33 * 0.25, 2 * 0.8 * 0.5 * m33
    for k in range(n):
        X[k] = x
        if k == n - 1:
            break
        if kind == "surge":
            r_b = x[5] / b.rate
            N_cmd = -kp * np.arctan2(np.sin(x[2] - psi0), np.cos(x[2] - psi0)) - kd * r_b
            P[k, 4] = np.clip(pitch_from_control(N_cmd / (vessel.K[4] * vessel.arms[4])), -1.0, 1.0)
        w_bis = bias + rng.normal(scale=np.sqrt(noise.q_h / dtb), size=3) * _COMP
        tau_c = par.D @ (dp.rotation(x[2]).T @ Vc)
        u = np.concatenate([P[k], [alpha[k]], tau_c + b.tau_from_bis(w_bis)])
        h = dt / substeps
        for s in range(substeps):
            x = rk4_step(dp.lf_dynamics, t[k] + s * h, x, u, par, h)
        if noise.bias_tau is None:
            bias = bias + rng.normal(scale=np.sqrt(noise.q_b * dtb), size=3) * _COMP
        else:
            rho = np.exp(-dt / noise.bias_tau)
            bias = rho * bias + rng.normal(scale=noise.b0 * np.sqrt(1.0 - rho ** 2), size=3) * _COMP
    if kind == "surge":
        P[-1, 4] = P[-2, 4]
    saturated = float(np.mean(np.abs(P[:, 4]) >= 1.0)) if kind == "surge" else 0.0
    chans = {"x": X[:, 0] + rng.normal(scale=noise.sigma_pos, size=n),
             "y": X[:, 1] + rng.normal(scale=noise.sigma_pos, size=n),
             "psi": X[:, 2] + rng.normal(scale=noise.sigma_psi, size=n)}
    for j in range(6):
        chans[f"p{j + 1}"] = P[:, j]
    chans["alpha6"] = alpha
    meta = {"vessel": vessel.name, "manoeuvre": f"dp-{kind}", "seed": seed, "simulated": True, "pattern": pattern,
            "noise": noise.as_dict(), "current": Vc[:2].tolist(),
            "heading_control_saturated_fraction": saturated, "theta_true": vessel.theta.tolist(),
            "source": f"simulated dp {kind} trial (seed {seed})"}
    return Trial(t, chans, meta=meta)


def simulate_dp_trials(vessel: dp.DPVessel, seed: int = 0, *, duration: float = 1200.0, n_per_kind: int = 2,
                       dt: float = 1.0, noise: TrialNoise = TrialNoise()) -> dict[str, list[Trial]]:
    """The six trials of §4.2 (two of each kind), seeded reproducibly from ``seed``.

    Returns ``{"surge": [...], "sway-yaw": [...], "azimuth": [...]}``.
    """
    ss = np.random.SeedSequence(seed)
    kinds = ("surge", "sway-yaw", "azimuth")
    seeds = ss.generate_state(len(kinds) * n_per_kind)
    out: dict[str, list[Trial]] = {}
    for i, kind in enumerate(kinds):
        out[kind] = [simulate_dp_trial(vessel, kind, duration, int(seeds[i * n_per_kind + j]), dt=dt, noise=noise)
                     for j in range(n_per_kind)]
    return out


__all__ = ["DP_CHANNELS", "TrialNoise", "simulate_dp_trial", "simulate_dp_trials"]
