"""Optimal-IV bound of the mass / CM experiment (Linder et al. 2015, seed 000) in the time domain, with the
Box–Jenkins noise model of :mod:`shipid.methods.masscm.noise_bj`.

What any estimator of (35) that uses the rudder as its only instrument can reach (Söderström & Stoica 1989,
§8.2: the lower bound over all IV choices, attained by the refined IV when the noise model is right):

    I(theta) = sum_i (1/lam_i) sum_t psi_t psi_t^T,   psi_t = (dg_i/dtheta)^T  L_i(q) phi_t^delta,

``phi^delta`` the regressors (37) of the noise-free, rudder-only response, ``L_i = D_i/C_i`` the inverse of the
noise model of the equation error of dataset i and ``lam_i`` its innovation variance. ``C_i/D_i`` is
:func:`~shipid.methods.masscm.noise_bj.noise_model_bj` fitted to the equation error at the true parameters of a
long simulated noise-only record (rudder at zero; ``noise_duration`` s), so the bound is as good as that fit
(AR(40) with the structured unit-circle MA part). Unlike the Whittle form of :func:`shipid.methods.masscm.crlb.crlb`
(``method="spectrum"``), which samples the ratio of two spectra with zeros on or near the unit circle on the DFT
grid, the prefiltering here is exact in time; the first ``transient`` s of the prefiltered regressors are dropped
and the sum rescaled to the record.

Why it matters (coverage study, waves without sensor noise): the Cramér–Rao bound of the data-generating model
(:mod:`shipid.methods.masscm.crlb_kf`) needs a sensor-noise floor there and falls without limit as the floor goes
to 0 (the noise-free channels then determine the wave moment); this bound does not depend on any floor and is
the reference for rudder-instrument IV. Averaged over ``n_rudder`` rudder realisations (the mean information).

**Not a floor.** It is the IV covariance with the *fitted* noise model, an approximation of the optimum from above
where AR(40) cannot follow the equation-error spectrum (the zeros of the roll polynomial A(q), near the unit circle
at the roll resonance, in the gyro-noise part). 300 s, 3 rudders: waves m 0.0251, zm_bar 0.0119, rho 0.0203; issue-3
noise 0.0332 / 0.0153 / 0.0375; sensor noise 0.0111 / 0.0046 / 0.0171 — and there Algorithm 1's Monte Carlo spread is
0.0083 / 0.0035 / 0.0123 (seed 9001, 100 runs), below this number, so with sensor noise the accounting misses
information Algorithm 1 uses. Read it as a scale for rudder-instrument IV in wave roll, not as a bound.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

from shipid.methods.masscm.crlb import CONDS, equation_regressors, true_theta
from shipid.methods.masscm.noise_bj import ma_structure, noise_model_bj
from shipid.methods.masscm.options import MassCMOptions
from shipid.models.roll_reduced import THETA_NAMES, KnownParams, discrete_coeffs, jacobian_complex_step
from shipid.models.roll_sim import NoiseSpec, simulate_datasets


def crlb_iv(vessel="fishing-vessel", *, duration: float = 300.0, fs: float = 50.0, noise: NoiseSpec,
            seed: int = 0, n_rudder: int = 3, noise_duration: float = 1200.0, transient: float = 60.0,
            options: MassCMOptions = MassCMOptions()) -> dict:
    """Optimal-IV bounds on the std of ``m``, ``zm_bar``, ``rho`` (z_f known) with the Box–Jenkins noise model.

    Returns ``{"bounds": {name: {"true", "std", "rel"}}, "noise_models": {cond: (c, k, lam)}, "definition"}``.
    """
    th = true_theta(vessel)
    known = KnownParams.from_vessel(vessel)
    T = 1.0 / fs
    free = [i for i, n in enumerate(THETA_NAMES) if n != "z_f"]
    d = simulate_datasets(vessel, seed=np.random.SeedSequence([int(seed), 1]), duration=noise_duration, fs=fs,
                          noise=noise, delta_amp=0.0)
    models, G = {}, {}
    for cond in CONDS:
        y, Phi = equation_regressors(d[cond])
        g = discrete_coeffs(th, known, [cond], T)[0]
        models[cond] = noise_model_bj((y - Phi @ g)[20:], options)

        def g_of(x, cond=cond):
            full = th.astype(x.dtype).copy()
            full[free] = x
            return discrete_coeffs(full, known, [cond], T)[0]
        G[cond] = jacobian_complex_step(g_of, th[free])
    s = int(round(transient * fs))
    info = np.zeros((len(free), len(free)))
    for rep in range(n_rudder):
        clean = simulate_datasets(vessel, seed=np.random.SeedSequence([int(seed), 2, rep]), duration=duration,
                                  fs=fs, noise=NoiseSpec())
        for cond in CONDS:
            _, Pc = equation_regressors(clean[cond])
            L = models[cond]
            Pf = lfilter(L.a, L.c, Pc - Pc.mean(axis=0), axis=0)[s:]
            Psi = Pf @ G[cond]
            info += (Psi.T @ Psi) / L.lam * (Pc.shape[0] / Pf.shape[0]) / n_rudder
    info = 0.5 * (info + info.T)
    np.linalg.cholesky(info)                      # positive definite, or LinAlgError
    cov = np.linalg.inv(info)
    cov = 0.5 * (cov + cov.T)
    z_f = th[THETA_NAMES.index("z_f")]

    def rho_f(t):
        return t[7] * (t[8] + z_f) / (known.m_c * (known.zc_bar + z_f))
    grad = jacobian_complex_step(lambda x: rho_f(np.concatenate([x[:6], [z_f], x[6:]])), th[free])
    names = [THETA_NAMES[i] for i in free]
    bounds = {n: {"true": float(th[i]), "std": float(np.sqrt(cov[k, k])),
                  "rel": float(np.sqrt(cov[k, k]) / abs(th[i])) if th[i] else float("nan")}
              for k, (i, n) in enumerate(zip(free, names))}
    rv, rs = float(rho_f(th)), float(np.sqrt(grad @ cov @ grad))
    bounds["rho"] = {"true": rv, "std": rs, "rel": rs / abs(rv)}
    return {"bounds": bounds,
            "noise_models": {c: (*ma_structure(m), float(m.lam)) for c, m in models.items()},
            "definition": "optimal-IV bound of the rudder-driven regressors, Box-Jenkins noise model (noise_bj) "
                          "fitted to simulated noise, time domain (Soderstrom & Stoica 1989 §8.2)"}


__all__ = ["crlb_iv"]
