"""Noise and disturbance generators, and measurement models, all driven by an explicit seed.

Every generator takes ``rng``: a :class:`numpy.random.Generator` or an integer seed
(``None`` is refused: randomness only through an explicit seed).

Coloured processes are linear Gaussian systems ``ẋ = A x + B w``, ``y = C x``
with ``w`` white (unit intensity scaled to give a stated stationary variance of
``y``). They are discretised *exactly* on the sample grid:
``x_{k+1} = Φ x_k + q_k`` with ``Φ = exp(A dt)`` and
``cov(q_k) = Q_d = P − Φ P Φᵀ`` where ``P`` is the stationary covariance
(``A P + P Aᵀ + B Bᵀ = 0``). This identity holds for the exact discretisation
(Van Loan 1978 gives the same Q_d), and it makes the recursion keep ``P``
exactly; the first state is drawn from ``N(0, P)``, so the output is stationary
from the first sample.

* :func:`white_noise` — independent Gaussian samples.
* :func:`gauss_markov` — n-th order Gauss–Markov: n cascaded first-order lags
  ``τ ẋ_{i} = −x_i + x_{i−1}`` driven by white noise (order 1 is the classical
  exponentially correlated process, autocorrelation ``e^{−|s|/τ}``; order 2 has
  ``(1 + |s|/τ) e^{−|s|/τ}``).
* :func:`wave_process` — the narrow-band second-order wave-like process
  ``ẍ + 2ζω₀ẋ + ω₀²x = w`` (the linear wave-response model of Fossen 1994 §6.4 /
  Sælid et al. 1983), used for wave-induced roll or yaw; spectral peak at
  ``ω₀ √(1 − 2ζ²)``.
* :class:`MeasurementModel` — adds white noise, constant biases and drifting
  (random-walk) biases to a Trial's channels.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from shipid.io.trial import Trial


def as_generator(rng: np.random.Generator | int) -> np.random.Generator:
    """A Generator from a Generator or an integer seed; ``None`` is an error."""
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is None or isinstance(rng, bool) or not isinstance(rng, (int, np.integer)):
        raise TypeError("give an explicit seed (int) or numpy.random.Generator")
    return np.random.default_rng(int(rng))


def white_noise(n: int, std: float | np.ndarray, rng: np.random.Generator | int) -> np.ndarray:
    """``n`` samples of zero-mean Gaussian white noise with standard deviation ``std``.

    ``std`` may be an array of shape ``(k,)``, giving an ``(n, k)`` array.
    """
    std = np.asarray(std, dtype=float)
    return as_generator(rng).standard_normal((n, *std.shape)) * std


@dataclass(frozen=True)
class LinearProcess:
    """An exactly discretised stationary linear Gaussian process (see module docstring).

    Attributes
    ----------
    Phi : ndarray (m, m)
        Transition matrix ``exp(A dt)``.
    Qd_sqrt : ndarray (m, m)
        A square root of the discrete process-noise covariance ``Q_d``.
    P : ndarray (m, m)
        Stationary state covariance.
    C : ndarray (m,)
        Output row.
    """

    Phi: np.ndarray
    Qd_sqrt: np.ndarray
    P: np.ndarray
    C: np.ndarray

    @property
    def variance(self) -> float:
        """Stationary variance of the output."""
        return float(self.C @ self.P @ self.C)

    def autocorrelation(self, lags: np.ndarray) -> np.ndarray:
        """Exact output autocorrelation ``C Φ^k P Cᵀ / (C P Cᵀ)`` at integer sample lags."""
        out, M, k_done = [], self.P.copy(), 0
        for k in sorted(int(v) for v in lags):
            while k_done < k:
                M = self.Phi @ M
                k_done += 1
            out.append(float(self.C @ M @ self.C))
        order = np.argsort(np.argsort(np.asarray(lags)))
        return np.asarray(out)[order] / self.variance

    def sample(self, n: int, rng: np.random.Generator | int) -> np.ndarray:
        """``n`` samples of the output, stationary from the first."""
        return self.sample_paths(n, 1, rng)[:, 0]

    def sample_paths(self, n: int, paths: int, rng: np.random.Generator | int) -> np.ndarray:
        """``(n, paths)`` samples: ``paths`` independent realisations, each stationary."""
        g = as_generator(rng)
        m = self.Phi.shape[0]
        x = g.standard_normal((paths, m)) @ _psd_sqrt(self.P).T
        y = np.empty((n, paths))
        PhiT, QT = self.Phi.T, self.Qd_sqrt.T
        for k in range(n):
            y[k] = x @ self.C
            x = x @ PhiT + g.standard_normal((paths, m)) @ QT
        return y


def _psd_sqrt(S: np.ndarray) -> np.ndarray:
    """Symmetric square root of a covariance, tiny negative eigenvalues (round-off) set to zero."""
    S = 0.5 * (S + S.T)
    lam, V = np.linalg.eigh(S)
    if lam.min() < -1e-9 * max(lam.max(), 1e-300):
        raise ValueError(f"covariance is not positive semi-definite (eigenvalue {lam.min():.3g})")
    return (V * np.sqrt(np.clip(lam, 0.0, None))) @ V.T


def linear_process(A: np.ndarray, B: np.ndarray, C: np.ndarray, dt: float,
                   variance: float) -> LinearProcess:
    """Exact discretisation of ``ẋ = A x + B w``, ``y = C x`` scaled to output variance ``variance``.

    ``A`` must be Hurwitz (stable) for a stationary process.
    """
    A = np.atleast_2d(np.asarray(A, dtype=float))
    B = np.asarray(B, dtype=float).reshape(A.shape[0], -1)
    C = np.asarray(C, dtype=float).ravel()
    if not np.all(np.linalg.eigvals(A).real < 0):
        raise ValueError("A must be stable for a stationary process")
    if not (dt > 0 and variance >= 0):
        raise ValueError("need dt > 0 and variance >= 0")
    from scipy.linalg import expm, solve_continuous_lyapunov  # scipy.linalg only where it is called

    P1 = solve_continuous_lyapunov(A, -B @ B.T)       # stationary covariance for unit intensity
    P1 = 0.5 * (P1 + P1.T)
    P = P1 * (variance / float(C @ P1 @ C)) if variance > 0 else np.zeros_like(P1)
    Phi = expm(A * dt)
    Qd = P - Phi @ P @ Phi.T                          # exact: stationarity of the discrete recursion
    return LinearProcess(Phi=Phi, Qd_sqrt=_psd_sqrt(Qd), P=P, C=C)


def gauss_markov_process(tau: float, std: float, dt: float, order: int = 1) -> LinearProcess:
    """The n-th order Gauss–Markov process as a :class:`LinearProcess`.

    Parameters
    ----------
    tau : float
        Time constant of each first-order stage (s); for order 1 this is the
        correlation time (autocorrelation ``e^{-1}`` at lag ``tau``).
    std : float
        Stationary standard deviation of the output.
    dt : float
        Sample interval (s).
    order : int
        Number of cascaded first-order stages (≥ 1).
    """
    if order < 1 or tau <= 0:
        raise ValueError("need order >= 1 and tau > 0")
    A = (np.eye(order, k=-1) - np.eye(order)) / tau   # τ ẋ_i = −x_i + x_{i−1}
    B = np.zeros(order)
    B[0] = 1.0
    C = np.zeros(order)
    C[-1] = 1.0
    return linear_process(A, B, C, dt, std ** 2)


def gauss_markov(n: int, dt: float, tau: float, std: float, rng: np.random.Generator | int,
                 order: int = 1) -> np.ndarray:
    """``n`` samples of a stationary n-th order Gauss–Markov process (see :func:`gauss_markov_process`)."""
    return gauss_markov_process(tau, std, dt, order).sample(n, rng)


def wave_process_model(omega0: float, zeta: float, rms: float, dt: float) -> LinearProcess:
    """The wave-like process ``ẍ + 2ζω₀ẋ + ω₀²x = w`` with output RMS ``rms``.

    Parameters
    ----------
    omega0 : float
        Natural (modal) frequency, rad/s.
    zeta : float
        Relative damping (small: narrow band), 0 < ζ < 1.
    rms : float
        Stationary RMS of ``x``.
    dt : float
        Sample interval (s).
    """
    if omega0 <= 0 or not 0 < zeta < 1:
        raise ValueError("need omega0 > 0 and 0 < zeta < 1")
    A = np.array([[0.0, 1.0], [-omega0 ** 2, -2.0 * zeta * omega0]])
    return linear_process(A, np.array([0.0, 1.0]), np.array([1.0, 0.0]), dt, rms ** 2)


def wave_process(n: int, dt: float, omega0: float, zeta: float, rms: float,
                 rng: np.random.Generator | int) -> np.ndarray:
    """``n`` samples of the wave-like process (see :func:`wave_process_model`)."""
    return wave_process_model(omega0, zeta, rms, dt).sample(n, rng)


@dataclass(frozen=True)
class MeasurementModel:
    """Sensor errors added to a Trial's channels (all in SI units of the channel).

    ``measured = true + bias + drift(t) + white noise`` where ``drift`` is a random
    walk starting at 0 with increments ``N(0, drift_k² dt)``.

    Attributes
    ----------
    noise : mapping channel → standard deviation of white noise
    bias : mapping channel → constant bias
    drift : mapping channel → random-walk intensity (unit/√s)
    """

    noise: Mapping[str, float] = field(default_factory=dict)
    bias: Mapping[str, float] = field(default_factory=dict)
    drift: Mapping[str, float] = field(default_factory=dict)

    def apply(self, trial: Trial, rng: np.random.Generator | int, *,
              missing_ok: bool = False) -> Trial:
        """Return a copy of ``trial`` with the errors added.

        Channels are processed in sorted order so a seed gives the same draws
        whatever the order of the mappings. Channels absent from the trial are an
        error unless ``missing_ok``.
        """
        g = as_generator(rng)
        names = sorted(set(self.noise) | set(self.bias) | set(self.drift))
        if not missing_ok:
            trial.require(names, method="measurement model")
        new = {}
        dt = np.diff(trial.t, prepend=trial.t[0])
        for name in names:
            if name not in trial:
                continue
            y = trial[name].copy()
            y += self.bias.get(name, 0.0)
            if self.drift.get(name, 0.0):
                y += np.cumsum(g.standard_normal(y.size) * self.drift[name] * np.sqrt(dt))
            if self.noise.get(name, 0.0):
                y += g.standard_normal(y.size) * self.noise[name]
            new[name] = y
        out = trial.with_channels(**new)
        meta = dict(out.meta)
        meta["measurement_noise"] = ", ".join(f"{k}:{v:g}" for k, v in sorted(self.noise.items()))
        return Trial(out.t, out.channels, out.units, meta)


#: Default sensor noise for ``shipid simulate --noise`` (SI): DGPS position 0.5 m, gyro
#: compass 0.1 deg, rate gyro 0.05 deg/s, log / DGPS velocity 0.02 m/s, roll 0.1 deg, roll
#: rate 0.05 deg/s, rudder indicator 0.2 deg, accelerometer 0.02 m/s^2. Typical orders of
#: magnitude for the sensors named, chosen by shipid (not from a paper).
DEFAULT_NOISE: dict[str, float] = {
    "x": 0.5, "y": 0.5, "psi": np.deg2rad(0.1), "r": np.deg2rad(0.05), "u": 0.02, "v": 0.02,
    "x_dot": 0.02, "y_dot": 0.02, "U": 0.02, "phi": np.deg2rad(0.1), "p": np.deg2rad(0.05),
    "delta": np.deg2rad(0.2), "a_s": 0.02,
}


def default_measurement_model() -> MeasurementModel:
    """White noise only, :data:`DEFAULT_NOISE` on the channels a trial has."""
    return MeasurementModel(noise=dict(DEFAULT_NOISE))
