"""Cramér–Rao-type lower bounds for the mass / centre-of-mass experiment (Linder et al. 2015, issue 3).

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
:mod:`shipid.analysis.identifiability_masscm`). Bounds on ``zm_bar``, ``rho = m z_m/(m_c z_c)`` and
``m`` follow by the delta method.

Measured (``benchmarks/bench_masscm_efficiency.py``): Algorithm 1 with the AR prefilters reaches
this bound; its spread over noise realisations came out slightly *below* it (ratio ~0.8–0.9 over
24–100 realisations), so read the number as the asymptotic IV bound, not a strict finite-sample floor.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

from shipid.estimate.arma import hannan_rissanen
from shipid.models.roll_reduced import THETA_NAMES, KnownParams, discrete_coeffs, jacobian_complex_step
from shipid.models.roll_sim import NoiseSpec, simulate_datasets
from shipid.vessels import load_vessel

CONDS = ("nominal", "calibration", "loaded")


def _regressors(tr):
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
        y, Phi = _regressors(d[cond])
        g = discrete_coeffs(th, known, [cond], 1.0 / fs)[0]
        eps = (y - Phi @ g)[10:]
        out.append(hannan_rissanen(eps, na=ar_order, nc=0, n_long=ar_order))
    return out


def crlb(vessel="fishing-vessel", *, duration: float = 300.0, fs: float = 50.0,
         delta_amp: float = np.deg2rad(5.0), noise: NoiseSpec = NoiseSpec.issue3(), seed=0,
         n_datasets_per_condition: int = 1) -> dict:
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

    Returns
    -------
    dict
        ``bounds``: for ``zm_bar``, ``rho``, ``m`` and every parameter: ``true``, ``std``, ``rel``;
        ``covariance`` of the 8 free parameters (names in ``names``); ``lam`` per condition.
    """
    known = KnownParams.from_vessel(vessel)
    th = true_theta(vessel)
    free = [i for i, n in enumerate(THETA_NAMES) if n != "z_f"]
    models = noise_models(vessel, fs=fs, noise=noise, seed=seed)
    info = np.zeros((len(free), len(free)))
    T = 1.0 / fs
    for rep in range(n_datasets_per_condition):
        clean = simulate_datasets(vessel, seed=np.random.SeedSequence([int(seed), 2, rep]), duration=duration,
                                  fs=fs, noise=NoiseSpec(), delta_amp=delta_amp)
        for cond, ar in zip(CONDS, models):
            _, Phi = _regressors(clean[cond])

            def g_of(x, cond=cond):
                full = th.astype(x.dtype).copy()
                full[free] = x
                return discrete_coeffs(full, known, [cond], T)[0]
            G = jacobian_complex_step(g_of, th[free])             # (5, 8)
            Pf = lfilter(ar.a, ar.c, Phi, axis=0)[10:]
            Psi = Pf @ G
            info += Psi.T @ Psi / ar.lam
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
            "lam": {c: float(m.lam) for c, m in zip(CONDS, models)},
            "definition": "Fisher information of the rudder-driven regressors, Box–Jenkins form of (35); "
                          "= optimal-IV covariance (Söderström & Stoica 1989 §8.2)"}


__all__ = ["crlb", "noise_models", "true_theta"]
