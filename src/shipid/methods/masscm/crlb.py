"""Cramér–Rao-type lower bounds for the mass / centre-of-mass experiment (Linder et al. 2015).

Model: each dataset obeys (35) ``y_t = phi_t^T g_i(theta) + v_t`` where ``v_t = H_i(q) e_t`` is the
equation error caused by the waves and the sensor noise, ``e_t`` white with variance ``lam_i``. The
regressors contain ``y``, ``a_s`` and ``r``, which the waves and noise also drive, so the only
excitation independent of ``v`` is the rudder. The bound computed here is the Fisher information
carried by the rudder-driven part of the regressors,

    I(theta) = sum_i (1/lam_i) sum_t psi_t psi_t^T,   psi_t = (dg_i/dtheta)^T  H_i^-1(q) phi_t^delta

(``phi^delta``: the regressors of the noise-free, rudder-only response), i.e. the Gaussian
Cramér–Rao bound of the Box–Jenkins form of (35) with the rudder as the only exogenous signal. It
equals the covariance of the optimal instrumental-variable estimator (Söderström & Stoica 1989,
§8.2, the lower bound over all IV choices), which is what Algorithm 1 with ARMA prefilters (43)
aims at. ``H_i`` and ``lam_i`` are found from a long simulation of the noise alone (rudder at zero)
with a long AR model.

Unknowns: ``theta`` of (30) with ``z_f`` known (it is not identifiable, see
:mod:`shipid.methods.masscm.identifiability`). Bounds on ``zm_bar``, ``rho = m z_m/(m_c z_c)`` and
``m`` follow by the delta method.

``method="kf"`` (default) is not this bound but the Cramér–Rao bound of the data-generating model,
:func:`shipid.methods.masscm.crlb_kf.crlb_kf`; the two forms below stay selectable.

``H_i`` (``method``): ``"spectrum"`` takes the exact spectral density of the equation error at
the true parameters from the transfers of the simulated noise sources (:func:`equation_error_spectrum`:
gyro and accelerometer noise analytically, the wave moment through the exact sampled ship model (11)) and
evaluates the information in Whittle's frequency-domain form; ``"ar"`` (the former bound) fits an AR(40)
to a simulated noise record, which cannot represent the unit-circle zeros of the wave-roll equation error.
The spectrum agrees with simulated noise records (variance and band powers, tests); with white sensor noise
only (no unit-circle zeros) both forms agree to < 1 %; with wave roll the exact form is larger (300 s,
0.5 deg waves, noise-free sensors: m 0.064 vs 0.046; combined wave and sensor noise: 0.076 vs 0.059).

Measured figures, with the commands that regenerate them: ``docs/validation/mass-cm.md``.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

from shipid.estimate.arma import hannan_rissanen
from shipid.models.roll_reduced import THETA_NAMES, KnownParams, discrete_coeffs, jacobian_complex_step
from shipid.models.roll_sim import NoiseSpec, simulate_datasets
from shipid.vessels import load_vessel
from shipid.models.roll import imu_outputs, params_from_vessel, simulate_zoh
from shipid.models.roll_reduced import bilinear_tf
from shipid.methods.masscm.crlb_kf import crlb_kf

CONDS = ("nominal", "calibration", "loaded")


def equation_regressors(tr):
    """The equation-error regression of one dataset: ``y = p`` and the columns ``[-p_{k-1}, -p_{k-2}, Δ²a_s, Δ²r, Δ²δ]``.

    The ARX form of the reduced roll model (Linder et al. 2015, eqs. 22 and 33) whose Fisher information the
    OLS/GLS bounds of :func:`crlb` use; ``Δ²x_k = x_k − x_{k−2}``, zero for the first two samples.
    """
    y, a, r, d = tr["p"], tr["a_s"], tr["r"], tr["delta"]

    def d2(x):
        out = np.zeros_like(x); out[2:] = x[2:] - x[:-2]; return out
    y1 = np.concatenate([[0.0], y[:-1]]); y2 = np.concatenate([[0.0, 0.0], y[:-2]])
    return y, np.column_stack([-y1, -y2, d2(a), d2(r), d2(d)])


def true_theta(vessel="fishing-vessel") -> np.ndarray:
    v = load_vessel(vessel)
    t = v.values("table3_true")
    return np.array([t[n] for n in THETA_NAMES], dtype=float)


def noise_models(vessel="fishing-vessel", *, fs: float = 50.0, noise: NoiseSpec, seed=0,
                 duration: float = 600.0, ar_order: int = 40) -> list:
    """AR models ``(a, lam)`` of the equation error of each dataset from the noise alone (rudder 0)."""
    th = true_theta(vessel)
    known = KnownParams.from_vessel(vessel)
    d = simulate_datasets(vessel, seed=np.random.SeedSequence([int(seed), 1]), duration=duration, fs=fs,
                          noise=noise, delta_amp=0.0)
    out = []
    for cond in CONDS:
        y, Phi = equation_regressors(d[cond])
        g = discrete_coeffs(th, known, [cond], 1.0 / fs)[0]
        eps = (y - Phi @ g)[10:]
        out.append(hannan_rissanen(eps, na=ar_order, nc=0, n_long=ar_order))
    return out


def equation_error_spectrum(vessel="fishing-vessel", *, fs: float = 50.0, noise: NoiseSpec, n_fft: int) -> dict:
    """Exact spectral density of the equation error (35) at the true parameters, per condition.

    The equation error ``v = y - phi^T g`` is linear in the noise sources of
    :func:`shipid.models.roll_sim.simulate_condition` (all independent and white at the input):

    * gyro noise on ``p`` (std ``gyro_std``): ``v = (1 + g_0 q^-1 + g_1 q^-2) n_p``;
    * accelerometer noise (``acc_std``): ``v = -g_2 (1 - q^-2) n_a``; yaw-gyro noise: ``v = -g_3 (1 - q^-2) n_r``;
    * the wave moment (unit white noise through the wave filter of
      :func:`~shipid.models.roll_sim.wave_moment`, scaled so that the stationary roll-angle std is
      ``wave_roll_deg``), through the exact sampled ship model (11) (:func:`~shipid.models.roll.simulate_zoh`)
      and the IMU outputs into (35): its transfer is the DFT of the impulse response, computed by simulation
      over ``n_fft`` samples (long enough for the wave filter and the roll mode to decay).

    Biases add a constant, orthogonal to the mean-removed instruments, and do not enter. Returns per condition
    ``phi_v`` (``n_fft``,) with ``E|V_k|^2 / N = phi_v[k]`` (white noise of variance s^2: ``phi_v = s^2``).
    """

    v = load_vessel(vessel)
    th = true_theta(vessel)
    known = KnownParams.from_vessel(vessel)
    dt = 1.0 / fs
    z = np.exp(-1j * 2 * np.pi * np.fft.fftfreq(n_fft))          # q^-1 on the DFT grid
    out = {}
    for cond in CONDS:
        g = discrete_coeffs(th, known, [cond], dt)[0]
        phi = (noise.gyro_std ** 2 * np.abs(1 + g[0] * z + g[1] * z ** 2) ** 2
               + noise.acc_std ** 2 * np.abs(g[2] * (1 - z ** 2)) ** 2
               + noise.gyro_std ** 2 * np.abs(g[3] * (1 - z ** 2)) ** 2)
        if noise.wave_roll_deg > 0:
            w = 2 * np.pi / noise.wave_period
            b, a = bilinear_tf([2 * noise.wave_damping * w, 0.0], [1.0, 2 * noise.wave_damping * w, w * w], dt)
            imp = np.zeros(n_fft)
            imp[0] = 1.0
            tau = lfilter(b, a, imp)
            ship = params_from_vessel(v, cond)
            X, Xdot = simulate_zoh(ship, np.zeros(n_fft), dt, tau=tau)
            io = imu_outputs(ship, X, Xdot)
            scale = np.deg2rad(noise.wave_roll_deg) / np.sqrt(np.sum(X[:, 0] ** 2))
            # the impulse response starts from rest: two zero samples before it, so that the differences
            # a_t - a_{t-2}, r_t - r_{t-2} of the first two samples are not dropped (``equation_regressors`` sets them to
            # 0, which put a flat floor of ~1e-6 into the spectrum where the wave equation error falls as w^4)
            pad = np.zeros(2)
            tr = {k: np.concatenate([pad, io[k]]) for k in ("p", "a_s", "r")}
            tr["delta"] = np.zeros(n_fft + 2)
            y, Phi = equation_regressors(tr)
            hv = scale * (y - Phi @ g)[2:]
            phi = phi + np.abs(np.fft.fft(hv)) ** 2
        out[cond] = phi
    return out


def crlb(vessel="fishing-vessel", *, duration: float = 300.0, fs: float = 50.0,
         delta_amp: float = np.deg2rad(5.0), noise: NoiseSpec = NoiseSpec.combined(), seed=0,
         n_datasets_per_condition: int = 1, method: str = "kf", nuisance: str = "free-rows") -> dict:
    """Lower bounds on the standard deviations of the estimates (z_f known).

    Parameters
    ----------
    duration, fs : float
        Length (s) and sampling rate (Hz) of each dataset.
    delta_amp : float
        PRBS rudder amplitude (rad).
    noise : NoiseSpec
        Sensor noise and wave roll (biases do not change the bound).
    seed : int
        Seeds the rudder realisation and the noise-model simulation.
    method : {"kf", "spectrum", "ar"}
        ``"kf"`` (default): the Cramér–Rao bound of the data-generating model (the ship (11) with the wave filter,
        sensor noise and biases; exact Kalman-filter likelihood, nuisance sway/yaw rows, noise levels and biases
        eliminated), :func:`shipid.methods.masscm.crlb_kf.crlb_kf`; ``n_datasets_per_condition`` is the number
        of rudder realisations its information is averaged over and ``nuisance`` is passed on.
        ``"spectrum"``: the optimal-IV bound of the rudder-driven regressors, the noise of (35) by its exact spectral density
        (:func:`equation_error_spectrum`) and the information in Whittle's frequency-domain form,
        ``I = G^T [sum_k Re(Phi_k^H Phi_k) / (N phi_v(w_k))] G`` over the DFT ``Phi_k`` of the rudder-driven
        regressors (the ``k = 0`` bin, removed with the means, left out). ``"ar"``: the former bound, ``H_i``
        an AR(40) fit to a simulated noise record, which cannot represent the unit-circle zeros of the
        wave-roll equation error and so understates the information (estimators' spreads reached 0.45-0.9 of it).

    Returns
    -------
    dict
        ``bounds``: for ``zm_bar``, ``rho``, ``m`` and every parameter: ``true``, ``std``, ``rel``;
        ``covariance`` of the 8 free parameters (names in ``names``); ``lam`` per condition.
    """
    known = KnownParams.from_vessel(vessel)
    th = true_theta(vessel)
    free = [i for i, n in enumerate(THETA_NAMES) if n != "z_f"]
    if method not in ("kf", "spectrum", "ar"):
        raise ValueError("method must be 'kf', 'spectrum' or 'ar'")
    if method == "kf":
        return crlb_kf(vessel, duration=duration, fs=fs, delta_amp=delta_amp, noise=noise, seed=seed,
                       n_rudder=n_datasets_per_condition, nuisance=nuisance)
    n = int(round(duration * fs))
    models = noise_models(vessel, fs=fs, noise=noise, seed=seed) if method == "ar" else None
    spec = equation_error_spectrum(vessel, fs=fs, noise=noise, n_fft=n) if method == "spectrum" else None
    info = np.zeros((len(free), len(free)))
    T = 1.0 / fs
    for rep in range(n_datasets_per_condition):
        clean = simulate_datasets(vessel, seed=np.random.SeedSequence([int(seed), 2, rep]), duration=duration,
                                  fs=fs, noise=NoiseSpec(), delta_amp=delta_amp)
        for ci, cond in enumerate(CONDS):
            _, Phi = equation_regressors(clean[cond])

            def g_of(x, cond=cond):
                full = th.astype(x.dtype).copy()
                full[free] = x
                return discrete_coeffs(full, known, [cond], T)[0]
            G = jacobian_complex_step(g_of, th[free])             # (5, 8)
            if method == "ar":
                ar = models[ci]
                Pf = lfilter(ar.a, ar.c, Phi, axis=0)[10:]
                Psi = Pf @ G
                info += Psi.T @ Psi / ar.lam
                continue
            F = np.fft.fft(Phi - Phi.mean(axis=0), axis=0)[1:]        # (n-1, 5)
            w = 1.0 / (Phi.shape[0] * spec[cond][1:])
            M = np.real(F.conj().T @ (F * w[:, None]))
            info += G.T @ (0.5 * (M + M.T)) @ G
    cov = np.linalg.inv(info)
    cov = 0.5 * (cov + cov.T)
    names = [THETA_NAMES[i] for i in free]

    def derived(fun):
        grad = jacobian_complex_step(lambda x: fun(np.concatenate([x[:6], [th[6]], x[6:]])), th[free])
        return float(fun(th)), float(np.sqrt(grad @ cov @ grad))

    z_f = th[6]
    rho_f = lambda t: t[7] * (t[8] + z_f) / (known.m_c * (known.zc_bar + z_f))   # noqa: E731
    bounds = {n: {"true": float(th[i]), "std": float(np.sqrt(cov[k, k])),
                  "rel": float(np.sqrt(cov[k, k]) / abs(th[i])) if th[i] else float("nan")}
              for k, (i, n) in enumerate(zip(free, names))}
    rv, rs = derived(rho_f)
    bounds["rho"] = {"true": rv, "std": rs, "rel": rs / abs(rv)}
    return {"method": "crlb mass-cm", "vessel": vessel, "duration": duration, "fs": fs,
            "delta_amp": delta_amp, "noise": noise.__dict__, "z_f": "known",
            "bounds": bounds, "names": names, "covariance": cov.tolist(),
            "lam": ({c: float(m.lam) for c, m in zip(CONDS, models)} if models is not None else
                    {c: float(np.exp(np.mean(np.log(spec[c][1:])))) for c in CONDS}),
            "method": method,
            "definition": ("Fisher information of the rudder-driven regressors, Box–Jenkins form of (35) with "
                           + ("the exact equation-error spectrum (Whittle form)" if method == "spectrum" else
                              "an AR(40) noise model") + "; = optimal-IV covariance (Söderström & Stoica 1989 §8.2)")}


__all__ = ["crlb", "noise_models", "true_theta", "equation_regressors"]
