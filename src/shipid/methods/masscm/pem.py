"""Prediction-error (maximum-likelihood) refinement of the mass / CM estimate (Linder et al. 2015).

Beyond the paper: Algorithm 1 (a rudder-instrument IV) leaves information unused that only a full-model
estimator can exploit. This module maximises the exact Gaussian likelihood of the data-generating state-space
model of :mod:`shipid.methods.masscm.crlb_kf` over the three (or more) datasets jointly:

* shared: ``theta`` of (30) with ``z_f`` known (``k, A_x, d, K_r, K_vdot, K_delta, m, zm_bar``);
* per dataset: the free sway and yaw rows ``c_v, c_r`` of (11) (coefficients of ``[phi, v, p, r, delta, tau]``),
  the wave filter ``w, zeta, sigma`` (:func:`~shipid.methods.masscm.crlb_kf.wave_ss`, log-parameterised), the
  three sensor-noise variances (log) and the three biases.

Innovations: the rudder response from rest (first-order hold, :func:`~shipid.methods.masscm.crlb_kf.foh`) plus
the biases is subtracted from ``[p, a_s, r]`` and the remainder whitened by the steady-state Kalman predictor of
the noise model ``s+ = F s + G e``, ``n = H s + J e + v`` (:func:`noise_matrices`; gain from the discrete
Riccati equation with the correlated noise ``E[G e (J e)^T] = G J^T``), compiled with numba. The negative
log-likelihood is ``sum_k (eps_k^T Lam^-1 eps_k + log det Lam) / 2`` (the filter's start from zero instead of the
stationary covariance is an O(1) term against the O(N) likelihood).

Search: Fisher scoring with Levenberg damping (the expected information ``sum psi^T Lam^-1 psi + N/2 tr(Lam^-1
dLam Lam^-1 dLam)``, ``psi`` the innovation sensitivities by forward differences, Ljung 1999 §10.2), steps
accepted only when the likelihood increases. Start: Algorithm 1's ``theta``; the sway and yaw rows from a
least-squares fit of ``v'`` and ``r'`` on the reconstructed states (:mod:`shipid.methods.masscm.refine_start`:
``phi`` and ``v`` integrated from ``p`` and from ``v' = z_s p' + g phi - U r - a_s`` (8)), the biases from the
means, the sensor variances from second differences of the residuals, the wave frequency from the residual
roll-rate spectrum. Stages: the rudder response (rows, biases) with ``theta`` held; everything jointly without
waves; the wave filter and sensor variances with the rest held. The wave structure is kept, and everything fitted
jointly with it, when it raises the log-likelihood by more than :data:`WAVE_LR` per dataset (a likelihood-ratio
test, 3 parameters per dataset).

Standard errors: the inverse of the same information at the optimum (nuisance parameters included, so their
uncertainty propagates); ``rho`` by the delta method. Loud failure: a search that does not converge, an optimum
outside the physical region (``k, A_x, d, m <= 0``, unstable ship), or a model without waves whose innovations are
not white (:func:`whiteness_reason`; e.g. wave roll with noise-free sensors, where the wave model is singular and
the white-noise model is wrong) returns ``ok=False`` with the reason; the caller keeps Algorithm 1's estimate and
warns.
Measured (:mod:`shipid.methods.masscm.coverage`, 300-s records, 100 runs per regime at a fresh seed): spread over
the bound of :mod:`~shipid.methods.masscm.crlb_kf` 0.96 / 0.96 / 1.01 (m / zm_bar / rho) with waves and sensor
noise (Algorithm 1: 1.41 / 1.35 / 1.45) and 0.94 / 0.92 / 1.01 with sensor noise alone, ±2-std coverage 0.94-0.97.
About 5-15 s per three 300-s datasets on one core (three datasets, 71 parameters with waves).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit
from scipy.linalg import solve_discrete_are, solve_discrete_lyapunov

from shipid.numerics.linalg import one_blas_thread
from shipid.numerics.spectral import welch
from shipid.methods.masscm.crlb_kf import FREE, continuous_model, noise_matrices
from shipid.methods.masscm import plausibility
from shipid.methods.masscm.options import I_ZF
from shipid.methods.masscm.refine_start import initial_local
from shipid.methods.masscm.scoring import fisher_scoring, perturbed
from shipid.models.roll_reduced import KnownParams

#: 2 x the log-likelihood gain per dataset above which the wave structure is kept (chi-square, 3 dof: ~1e-5)
WAVE_LR = 25.0
N_TH = len(FREE)
N_LOC = 21        # c_v (6) | c_r (6) | log w, log zeta, log sigma | log var (3) | bias (3)
I_M, I_ZM = FREE.index("m"), FREE.index("zm_bar")
MEAN_LOCAL = list(range(12)) + [18, 19, 20]
WHITE_LAGS, WHITE_P = 20, 1e-4     # whiteness test of the model without waves (Ljung-Box, per channel)
NOISE_LOCAL = list(range(12, 18))


@dataclass(frozen=True)
class PEMOptions:
    """Tuning of the prediction-error refinement (our choices; see the module docstring)."""

    max_iter: int = 40
    tol: float = 1e-3          # converged when the Newton decrement (predicted log-likelihood gain) is below tol
    waves: str = "auto"        # "auto": likelihood-ratio choice; "yes" / "no": force the structure
    rel_step: float = 1e-6     # forward-difference step relative to max(|p|, 0.1)
    start_iter: int = 6        # scoring iterations of the theta-fixed start fits
    nowave_iter: int = 15      # ... and of the joint fit without waves (a start; its convergence is not needed)


@dataclass
class PEMFit:
    """Outcome of :func:`refine`: ``theta`` (names :data:`FREE`), its covariance, ``rho``, diagnostics."""

    ok: bool
    theta: np.ndarray
    cov: np.ndarray
    rho: float
    rho_std: float
    loglik: float
    iterations: int
    waves: bool
    reason: str = ""
    local: list = field(default_factory=list)


@njit(cache=True)
def _innovations(y, delta, Ad, b0, b1, C, dd, bias, F, K, H, out):
    """Innovations of ``y`` (N, 3): rudder response from rest + bias removed, then the Kalman predictor."""
    n = y.shape[0]
    ns = F.shape[0]
    x = np.zeros(4)
    xn = np.zeros(4)
    s = np.zeros(ns)
    sn = np.zeros(ns)
    e = np.zeros(3)
    for k in range(n):
        dk = delta[k]
        dnext = delta[k + 1] if k + 1 < n else dk
        for i in range(3):
            mu = dd[i] * dk + bias[i]
            for j in range(4):
                mu += C[i, j] * x[j]
            hs = 0.0
            for j in range(ns):
                hs += H[i, j] * s[j]
            e[i] = y[k, i] - mu - hs
            out[k, i] = e[i]
        for i in range(4):
            acc = b0[i] * dk + b1[i] * dnext
            for j in range(4):
                acc += Ad[i, j] * x[j]
            xn[i] = acc
        for i in range(ns):
            acc = 0.0
            for j in range(ns):
                acc += F[i, j] * s[j]
            for j in range(3):
                acc += K[i, j] * e[j]
            sn[i] = acc
        for i in range(4):
            x[i] = xn[i]
        for i in range(ns):
            s[i] = sn[i]


def model_vector(theta, loc) -> np.ndarray:
    """The 26-vector of :class:`~shipid.methods.masscm.crlb_kf.DatasetModel` from ``theta`` and a local vector."""
    return np.concatenate([theta, loc[:12], np.exp(loc[12:15]), np.exp(loc[15:18])])


def _gain(F, G, H, J, R):
    """Steady-state predictor gain ``K`` and innovation covariance ``Lam``; raises ``ValueError`` if none."""
    Rt = R + np.outer(J, J)
    if F.shape[0] == 0:
        return np.zeros((0, 3)), Rt
    if np.max(np.abs(np.linalg.eigvals(F))) >= 1.0:
        raise ValueError("unstable model")
    P = solve_discrete_are(F.T, H.T, np.outer(G, G), Rt, s=np.outer(G, J))
    Lam = H @ P @ H.T + Rt
    Lam = 0.5 * (Lam + Lam.T)
    K = np.linalg.solve(Lam, (F @ P @ H.T + np.outer(G, J)).T).T
    return K, Lam


class _Set:
    """One dataset: its data and condition, and the innovations of a parameter vector."""

    def __init__(self, cond, trial, known, z_f):
        self.cond, self.known, self.z_f = cond, known, z_f
        self.y = np.ascontiguousarray(np.column_stack([trial["p"], trial["a_s"], trial["r"]]), dtype=float)
        self.delta = np.ascontiguousarray(trial["delta"], dtype=float)
        self.T = float(trial.dt)
        self.n = self.y.shape[0]

    def innov(self, theta, loc, waves):
        """``(eps (N, 3), Lam)`` or ``None`` where the model is not admissible (unstable, Riccati fails)."""
        p = model_vector(theta, loc)
        try:
            (Ad, B0, B1, C, D), nm = noise_matrices(p, self.known, self.z_f, self.cond, self.T, waves)
            if not np.all(np.isfinite(Ad)) or np.max(np.abs(np.linalg.eigvals(Ad))) >= 1.0:
                return None          # only stable ships are admissible
            K, Lam = _gain(*nm)
            np.linalg.cholesky(Lam)
        except (ValueError, np.linalg.LinAlgError):
            return None
        F, H = np.ascontiguousarray(nm[0]), np.ascontiguousarray(nm[2])
        out = np.empty((self.n, 3))
        _innovations(self.y, self.delta, Ad, np.ascontiguousarray(B0[:, 0]), np.ascontiguousarray(B1[:, 0]),
                     np.ascontiguousarray(C), np.ascontiguousarray(D[:, 0]), loc[18:21].copy(), F,
                     np.ascontiguousarray(K), H, out)
        if not np.all(np.isfinite(out)):
            return None
        return out, Lam


def _nll(eps, Lam):
    L = np.linalg.cholesky(Lam)
    w = np.linalg.solve(L, eps.T)
    return 0.5 * float(np.sum(w * w)) + eps.shape[0] * float(np.sum(np.log(np.diag(L))))


def _objective(sets, theta, locs, waves):
    tot = 0.0
    for s, loc in zip(sets, locs):
        r = s.innov(theta, loc, waves)
        if r is None:
            return np.inf
        tot += _nll(*r)
    return tot


def _free_local(waves):
    """Indices of the local parameters that enter the model with (or without) waves."""
    if waves:
        return list(range(N_LOC))
    return [i for i in range(N_LOC) if i not in (5, 11, 12, 13, 14)]


def score_information(sets, theta, locs, waves, th_idx, fl, rel_step=1e-6):
    """Score (gradient of the log-likelihood) and expected information over ``theta[th_idx]`` and ``loc[fl]``.

    ``g_a = sum eps^T Lam^-1 psi_a + 1/2 sum eps^T Lam^-1 dLam_a Lam^-1 eps - N/2 tr(Lam^-1 dLam_a)`` and
    ``I_ab = sum psi_a^T Lam^-1 psi_b + N/2 tr(Lam^-1 dLam_a Lam^-1 dLam_b)``, ``psi = -d eps/dp`` by forward
    differences (a parameter whose perturbation is not admissible either side is held: zero row).
    """
    nloc = len(fl)
    P = len(th_idx) + nloc * len(sets)
    g, info = np.zeros(P), np.zeros((P, P))
    for d, (s, loc) in enumerate(zip(sets, locs)):
        eps, Lam = s.innov(theta, loc, waves)
        Li = np.linalg.inv(Lam)
        cols = [("t", i) for i in th_idx] + [("l", i) for i in fl]
        gi = list(range(len(th_idx))) + [len(th_idx) + d * nloc + j for j in range(nloc)]
        psi = np.empty((s.n, 3, len(cols)))
        dL = np.empty((len(cols), 3, 3))
        for c, (kind, i) in enumerate(cols):
            r, h = perturbed(lambda t, l: s.innov(t, l, waves), theta, loc, kind, i, rel_step)
            if r is None:
                psi[:, :, c], dL[c] = 0.0, 0.0
                continue
            psi[:, :, c] = -(r[0] - eps) / h
            dL[c] = (r[1] - Lam) / h
        A = Li @ dL
        wps = np.einsum("ij,kjc->kic", Li, psi)
        el = eps @ Li
        gd = np.einsum("ki,kic->c", eps, wps)
        q = 0.5 * np.einsum("ki,cij,kj->c", el, dL, el) - 0.5 * s.n * np.trace(A, axis1=1, axis2=2)
        g[gi] += gd + q
        info[np.ix_(gi, gi)] += np.einsum("kic,kid->cd", psi, wps) + 0.5 * s.n * np.einsum("aij,bji->ab", A, A)
    return g, 0.5 * (info + info.T)


def _scoring(sets, theta, locs, waves, opts: PEMOptions, fix_theta=False, only=None):
    """:func:`~shipid.methods.masscm.scoring.fisher_scoring` of the joint likelihood; returns theta, locs, info,
    loglik, its, converged.

    ``fix_theta`` holds ``theta``; ``only`` (local indices) frees just those local parameters.
    """
    return fisher_scoring(lambda t, l: _objective(sets, t, l, waves),
                          lambda t, l, ti, fl: score_information(sets, t, l, waves, ti, fl, opts.rel_step),
                          theta, locs, _free_local(waves), N_TH, opts.max_iter, opts.tol, fix_theta=fix_theta,
                          only=only)


def _closed_form_variances(s, theta, loc):
    """``loc`` with the sensor variances at their maximum-likelihood value given the rest (model without waves)."""
    loc = loc.copy()
    r = s.innov(theta, loc, False)
    if r is not None:
        loc[15:18] = np.log(np.maximum(np.mean(r[0] ** 2, axis=0), 1e-300))
    return loc


def _wave_start(s: _Set, theta, loc, known: KnownParams) -> np.ndarray:
    """Wave filter start from the no-wave fit's roll-rate innovations: spectral peak, sigma from their variance."""
    r = s.innov(theta, loc, False)
    loc = loc.copy()
    if r is None:
        return loc
    loc[15:18] = np.log(np.maximum(np.var(np.diff(r[0], n=2, axis=0), axis=0) / 6, 1e-12))
    eps = r[0][:, 0]
    f, P = welch(eps, fs=1.0 / s.T, nperseg=min(2048, s.n))     # scipy.signal.welch's numbers, in numpy
    w = 2 * np.pi * f[1 + int(np.argmax(P[1:]))]
    loc[12:15] = np.log([w, 0.1, 1.0])
    loc[14] = wave_log_sigma(s, theta, loc, known, np.var(eps))
    return loc


def wave_log_sigma(s, theta, loc, known: KnownParams, var: float) -> float:
    """Start of the wave filter's ``log sigma`` for dataset ``s``: the roll-rate variance of the wave filter
    ``loc[12:14]`` at unit ``sigma`` (stationary, from the discrete Lyapunov equation) scaled to the excess of the
    residual roll-rate variance ``var`` over the sensor variance ``exp(loc[15])`` (at least a tenth of ``var``);
    shared by this module and :mod:`shipid.methods.masscm.whittle`."""
    _, (F, G, H, J, _R) = noise_matrices(model_vector(theta, loc), known, s.z_f, s.cond, s.T, True)
    var_unit = float(H[0] @ solve_discrete_lyapunov(F, np.outer(G, G)) @ H[0] + J[0] ** 2)
    excess = max(var - np.exp(loc[15]), 0.1 * var)
    return 0.5 * np.log(excess / var_unit)


def whiteness_reason(sets, theta, locs, lags: int = WHITE_LAGS, p: float = WHITE_P) -> str:
    """Empty when the innovations of the model without waves are white, else which are not: :func:`ljung_box_reason`
    of the mean-removed innovations (with coloured noise, e.g. waves and noise-free sensors, the white-noise model
    is wrong and its standard errors are not valid)."""
    def centred(s, loc):
        eps = s.innov(theta, loc, False)[0]
        return eps - eps.mean(axis=0)
    return ljung_box_reason(sets, locs, centred, "innovations", lags, p)


def ljung_box_reason(sets, locs, residuals, what: str, lags: int = WHITE_LAGS, p: float = WHITE_P) -> str:
    """Empty when the residuals ``residuals(s, loc)`` (N, 3; mean zero) of every dataset are white, else the first
    dataset and channel that is not (named ``what`` in the message).

    Ljung-Box ``Q = N (N + 2) sum_{l <= lags} r_l^2 / (N - l)`` per dataset and channel against the chi-square
    ``1 - p`` quantile with ``lags`` degrees of freedom; shared by this module and
    :mod:`shipid.methods.masscm.whittle`.
    """
    from scipy.stats import chi2  # scipy.stats only where it is called

    crit = float(chi2.ppf(1 - p, lags))
    for s, loc in zip(sets, locs):
        e = residuals(s, loc)
        n = e.shape[0]
        c0 = np.sum(e * e, axis=0)
        r = np.array([np.sum(e[l:] * e[:-l], axis=0) / c0 for l in range(1, lags + 1)])
        Q = n * (n + 2) * np.sum(r ** 2 / (n - np.arange(1, lags + 1))[:, None], axis=0)
        for ch, q in zip(("p", "a_s", "r"), Q):
            if q > crit:
                return (f"{what} of {s.cond} {ch} not white (Ljung-Box Q = {q:.3g} > {crit:.3g}, {lags} lags): "
                        "the model without waves does not fit")
    return ""


def rho_of(theta, known: KnownParams, z_f: float) -> float:
    """``rho = m z_m / (m_c z_c)`` (z about the centre of rotation) of ``theta`` (names :data:`FREE`) and ``z_f``:
    :func:`shipid.methods.masscm.plausibility.rho_of` of the whole theta of (30)."""
    return float(plausibility.rho_of(np.insert(np.asarray(theta, dtype=float), I_ZF, z_f), known))


def physical_reason(theta, sets, locs, waves, objective=None) -> str:
    """Empty when the optimum is physical, else why not (k, A_x, d, m <= 0, or an unstable / failed model);
    ``objective(sets, theta, locs, waves)`` is the negative log-likelihood checked finite (this module's by
    default; :mod:`shipid.methods.masscm.whittle` passes its own)."""
    objective = _objective if objective is None else objective
    for nm in ("k", "A_x", "d", "m"):
        if theta[FREE.index(nm)] <= 0:
            return f"{nm} = {theta[FREE.index(nm)]:.3g} <= 0"
    if waves and any(not (0 < np.exp(l[13]) < 1) for l in locs):
        return "wave damping outside (0, 1)"
    if not np.isfinite(objective(sets, theta, locs, waves)):
        return "likelihood not finite at the optimum"
    for s, l in zip(sets, locs):
        Ac = continuous_model(theta, l[:6], l[6:12], s.known, s.z_f, s.cond)[0]
        if np.max(np.real(np.linalg.eigvals(Ac))) >= 0:
            return f"ship model of dataset {s.cond} unstable at the optimum"
    return ""


def refine(datasets, known: KnownParams, z_f: float, theta_free, options: PEMOptions = PEMOptions()) -> PEMFit:
    """Maximum-likelihood refinement of ``theta_free`` (names :data:`FREE`, e.g. Algorithm 1's estimate).

    ``datasets`` are ``(condition, Trial)`` pairs with ``p, a_s, r, delta``. Returns a :class:`PEMFit`;
    ``ok=False`` (with ``reason``) when the search did not converge or ended outside the physical region.
    """
    sets = [_Set(c, tr, known, z_f) for c, tr in datasets]
    theta = np.asarray(theta_free, dtype=float).copy()
    with np.errstate(all="ignore"), one_blas_thread():
        locs = [initial_local(s, theta, known, lambda l, s=s: s.innov(theta, l, False) is not None)
                for s in sets]
        quick = PEMOptions(max_iter=options.start_iter, tol=options.tol, rel_step=options.rel_step)
        # (1) the rudder response (sway/yaw rows, biases) with theta and the sensor weights held
        _, lo0, _, _, _, _ = _scoring(sets, theta, locs, False, quick, fix_theta=True, only=MEAN_LOCAL)
        lo0 = [_closed_form_variances(s, theta, l) for s, l in zip(sets, lo0)]   # (2) white-noise variances
        # (3) everything jointly without waves (an output-error fit when the noise is coloured)
        nw = options if options.waves == "no" else PEMOptions(max_iter=options.nowave_iter, tol=options.tol,
                                                              rel_step=options.rel_step)
        fit = _scoring(sets, theta, lo0, False, nw) + (False,)
        th0, lo0, ll0 = fit[0], fit[1], fit[3]
        if options.waves != "no" and fit[2] is not None:
            # (4) wave filter and sensor variances with the rest held, then everything jointly with waves
            lw = [_wave_start(s, th0, l, known) for s, l in zip(sets, lo0)]
            _, lw, infw, ll1, _, _ = _scoring(sets, th0, lw, True, quick, fix_theta=True, only=NOISE_LOCAL)
            if options.waves == "yes" or (infw is not None and 2 * (ll1 - ll0) > WAVE_LR * len(sets)):
                fw = _scoring(sets, th0, lw, True, options)
                fit = fw[:4] + (fit[4] + fw[4], fw[5], True)
        if not fit[6] and not fit[5] and fit[2] is not None:    # no waves: the joint fit on to convergence
            fr = _scoring(sets, fit[0], fit[1], False, options)
            fit = fr[:4] + (fit[4] + fr[4], fr[5], False)
    return finish(fit, sets, known, z_f, physical_reason, whiteness_reason)


def finish(fit, sets, known: KnownParams, z_f: float, physical, whiteness) -> PEMFit:
    """The :class:`PEMFit` of a finished search ``fit = (theta, locals, information, loglik, iterations,
    converged, waves)``: the covariance of ``theta`` from the inverse information (checked positive definite,
    symmetrised), ``rho`` by the delta method, and the failure reason (not computable, information not positive
    definite, not converged, ``physical(theta, sets, locals, waves)``, and without waves ``whiteness(sets, theta,
    locals)``); shared by this module and :mod:`shipid.methods.masscm.whittle`."""
    th, lo, info, ll, its, conv, waves = fit
    nan = np.full((N_TH, N_TH), np.nan)
    if info is None:
        return PEMFit(False, th, nan, np.nan, np.nan, ll, its, waves, "likelihood not computable", lo)
    try:
        cov = np.linalg.inv(info)[:N_TH, :N_TH]
        np.linalg.cholesky(cov)
    except np.linalg.LinAlgError:
        return PEMFit(False, th, nan, np.nan, np.nan, ll, its, waves, "information not positive definite", lo)
    cov = 0.5 * (cov + cov.T)
    grad = np.zeros(N_TH)
    grad[I_M] = (th[I_ZM] + z_f) / (known.m_c * (known.zc_bar + z_f))
    grad[I_ZM] = th[I_M] / (known.m_c * (known.zc_bar + z_f))
    reason = "" if conv else f"search not converged in {its} iterations"
    reason = reason or physical(th, sets, lo, waves) or ("" if waves else whiteness(sets, th, lo))
    return PEMFit(not reason, th, cov, rho_of(th, known, z_f), float(np.sqrt(grad @ cov @ grad)), ll, its,
                  waves, reason, lo)


__all__ = ["PEMOptions", "PEMFit", "refine", "finish", "noise_matrices", "model_vector", "rho_of",
           "physical_reason", "WAVE_LR", "ljung_box_reason", "wave_log_sigma", "WHITE_LAGS", "WHITE_P"]
