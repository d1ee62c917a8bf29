"""The iteration of Algorithm 1 (Linder et al. 2015, steps A and B, eqs. 38–47).

:func:`initial_state` builds the first iteration's moments (step A); :func:`iterate` runs step B: (a) the
search of the criterion (40), (b) residuals (42) and noise models (43), (c) closed-loop instruments (46)–(47),
(d) the convergence rule on the discrete coefficients ``g_i`` of every dataset. :func:`step_compiled` is
steps (b)–(c) of one dataset by the compiled kernels of :mod:`shipid.methods.masscm.step`.
"""

from __future__ import annotations

import numpy as np

from shipid.estimate.arma import ARMA
from shipid.estimate.iv import iv_compress_products_compiled
from shipid.methods.masscm.criterion import (IVState, coeffs, compiled_search, condition_codes, floored_weights,
                                             gauss_newton, held_cold_search, jacobian_cs, kernel_args,
                                             known_constants, linear_initial, residual_function)
from shipid.methods.masscm.data import Dataset, first_row
from shipid.methods.masscm.moments import build_moments, closed_loop_sim, work_arrays
from shipid.methods.masscm.noise import AUTO_HOLD, fit_noise_model, initial_prefilter
from shipid.methods.masscm.noise_bj import FREEZE_AFTER, held_noise_model
from shipid.methods.masscm.options import I_ZF, I_ZM, MassCMOptions
from shipid.methods.masscm.plausibility import implausible_identifiable
from shipid.methods.masscm.search import sim_terms
from shipid.methods.masscm.step import dataset_step
from shipid.models.roll_reduced import KnownParams, from_moment, roll_terms, to_moment

def fused(options: MassCMOptions) -> bool:
    """Whether steps (b)-(c) run as one compiled call per dataset (:mod:`shipid.methods.masscm.step`)."""
    return (options.compute == "fast" and options.prefilter and options.noise_model == "ar"
            and options.ar_order > 0 and options.instruments == "lags")


def step_compiled(ds: Dataset, g_mid: np.ndarray, sim: np.ndarray, th_mid: np.ndarray, i: int,
                   known: KnownParams, y_hat, a_hat, options: MassCMOptions):
    """Steps (b)-(c) of one dataset by :func:`shipid.methods.masscm.step.dataset_step`.

    The same computation as :func:`fit_noise_model` (AR), :func:`closed_loop_sim` and :func:`fir_moments`
    (tests compare them); where the compiled AR fit declines (normal equations not positive definite,
    constant residual) this dataset is done on the reference path. Returns ``(L, lam, sim, moments)``
    with ``sim`` None when the model is unstable (instruments kept). ``sim``: row i of
    :func:`shipid.methods.masscm.search.sim_terms` at ``th_mid`` (the terms of :func:`roll_terms`).
    """
    c = ds.cache
    X, nls = work_arrays(ds, options)
    if "PhiT_c" not in c:
        c["PhiT_c"] = np.ascontiguousarray(ds.Phi.T)
    s = first_row(options)
    status, stable, a, lam, yh, ah, ZtZ, ZtP = dataset_step(
        ds.y, c["PhiT_c"], np.ascontiguousarray(g_mid, dtype=float), s, int(options.ar_order), X, nls,
        ds.r_hat0, ds.delta, sim, y_hat, a_hat)
    if status != 0:                                   # reference path for this dataset
        eps = ds.y - ds.Phi @ g_mid
        L = fit_noise_model(eps[s:], options)
        terms = roll_terms(th_mid, known, [ds.condition], moment=True)
        sim_out = closed_loop_sim(ds, terms, 0, known)
        yh, ah = sim_out if sim_out is not None else (y_hat, a_hat)
        return L, L.lam, sim_out, build_moments([ds], [L], [yh], [ah], options)[0]
    L = ARMA(a, np.ones(1), float(lam))
    return L, float(lam), ((yh, ah) if stable else None), iv_compress_products_compiled(ZtZ, ZtP, ds.y.size - s)


def _physical(theta_q: np.ndarray, known: KnownParams, conds, memo: dict | None) -> bool:
    """Whether the identified roll mode of ``theta_q`` (moment parameterisation) is physical
    (:func:`implausible_identifiable` finds nothing); ``memo`` keeps the judgements by the iterate's bytes."""
    key = theta_q.tobytes()
    if memo is not None and key in memo:
        return memo[key]
    ok = not implausible_identifiable(from_moment(theta_q), known, conds)
    if memo is not None:
        if len(memo) > 4:
            memo.clear()
        memo[key] = ok
    return ok


def left_physical_region(theta_q: np.ndarray, theta_prev_q: np.ndarray, known: KnownParams, conds,
                         memo: dict | None = None) -> bool:
    """Whether a search moved from an iterate whose identified roll mode is physical to one whose is not
    (:func:`shipid.methods.masscm.plausibility.implausible_identifiable`, point values; moment parameterisation).

    (*) Beyond the paper. With noise-free sensors the data obey, besides the roll dynamics (35), a near-exact
    kinematic identity of the IMU (``a_s`` contains ``z_s p'``, so ``y_t - 2 y_{t-1} + y_{t-2}`` is close to
    ``(T/2 z_s)(a_t - a_{t-2})`` for any motion, rudder- or wave-driven); the IV criterion (40) then has a second
    near-zero minimum at ``alpha1 ~ -2, alpha2 ~ 1`` (all physical coefficients -> infinity, no restoring), which
    an iteration can jump to after a prefilter update (seen in wave roll without sensor noise, a few runs in 100).

    ``memo``: a dict the caller keeps between calls (:func:`iterate`: each iterate is judged once, as the new
    iterate and then again as the previous one); None judges both afresh.
    """
    if not np.all(np.isfinite(theta_q)):
        return True
    if not _physical(theta_prev_q, known, conds, memo):
        return False
    return not _physical(theta_q, known, conds, memo)


def search_bounds(free: np.ndarray, prior, options: MassCMOptions) -> tuple[np.ndarray, np.ndarray]:
    """Bounds ``(lo, hi)`` on the free entries of theta (moment parameterisation) of the searches of step B(a)."""
    # (*) trust-region search with the load's centre kept inside |zm_bar| <= zm_bound: outside it the
    # moment parameterisation degenerates (q -> 0 with q*zm_bar finite fits like an extra free A2)
    lo = np.full(int(free.sum()), -np.inf)
    hi = np.full(int(free.sum()), np.inf)
    izm = int(np.sum(free[:I_ZM]))
    lo[izm], hi[izm] = -options.zm_bound, options.zm_bound
    if free[I_ZF] and prior is None:
        # (*) z_f free: the exact-fit family is flat in z_f and leaves the physical region (A_x, k or d
        # negative) on both sides (see shipid.methods.masscm.identifiability); keep the search inside it
        lo[:3] = 0.0
        lo[int(np.sum(free[:I_ZF]))], hi[int(np.sum(free[:I_ZF]))] = -1.0, 1.0
    return lo, hi


def initial_state(prep: list[Dataset], options: MassCMOptions = MassCMOptions()) -> "IVState":
    """IV moments of the first iteration (step A): black-box instruments and the initial prefilter.

    They depend on the data and the options only, not on the initial values, so a Monte Carlo study
    over initial values builds them once (:mod:`shipid.methods.masscm.study`) and passes them to
    :func:`iterate` as ``state0``.
    """
    L = [initial_prefilter(options)] * len(prep)
    y_hats = [ds.y_hat0 for ds in prep]
    a_hats = [ds.a_hat0 for ds in prep]
    return IVState(build_moments(prep, L, y_hats, a_hats, options), np.ones(len(prep)), L,
                  np.array([ds.T for ds in prep]), [ds.condition for ds in prep])


def iterate(prep: list[Dataset], known: KnownParams, theta0: np.ndarray, *, z_f: float | None = None,
            z_f_prior: tuple[float, float] | None = None, init: str = "given",
            options: MassCMOptions = MassCMOptions(), state0: "IVState | None" = None,
            jacobian: bool = True) -> dict:
    """Run Algorithm 1 step B on prepared datasets; the core shared by :func:`estimate_mass_cm` and the study.

    The search runs in the load-moment parameterisation ``q = m z_m`` (:data:`THETA_Q_NAMES`), in
    which the model is polynomial; ``theta0`` and the returned ``theta`` are physical (with ``m``),
    ``theta_q`` and ``J`` (Jacobian of the weighted residuals w.r.t. the free entries of ``theta_q``)
    are internal. Returns a plain dict so that Monte Carlo runs stay cheap; :func:`estimate_mass_cm`
    turns it into a :class:`Result`. ``state0``: the result of :func:`initial_state` for the same
    ``prep`` and ``options`` (built here when not given). ``jacobian=False`` skips the final Jacobian
    ``J`` (only the covariance needs it; the Monte Carlo study does not).
    """
    theta = np.asarray(theta0, dtype=float).copy()
    if z_f is not None:
        theta[I_ZF] = float(z_f)
    theta = to_moment(theta)
    free = np.ones(theta.size, dtype=bool)
    if z_f is not None:
        free[I_ZF] = False
    prior = None
    if z_f_prior is not None and z_f is None:
        prior = (float(z_f_prior[0]), float(z_f_prior[1]))
    conds = [ds.condition for ds in prep]
    Ts = np.array([ds.T for ds in prep])
    code = condition_codes(conds, options)          # None: the map (33) by the reference path
    warn: list[str] = []
    y_hats = [ds.y_hat0 for ds in prep]
    a_hats = [ds.a_hat0 for ds in prep]
    state = initial_state(prep, options) if state0 is None else state0
    if init == "linear":
        lin = linear_initial(state, known, float(theta[I_ZF]))
        if np.all(np.isfinite(lin)):
            theta = lin
    elif init != "given":
        raise ValueError("init must be 'given' or 'linear'")
    g_prev = None
    recent: list[np.ndarray] = []          # the last (up to four) iterates, for the relaxation of steps (b)-(c)
    converged = False
    history = []
    dgs: list[float] = []
    j = 0
    fun = None
    lo, hi = search_bounds(free, prior, options)
    lo_in, hi_in = lo.copy(), hi.copy()
    fl, fh = np.isfinite(lo), np.isfinite(hi)
    lo_in[fl] += 1e-6 * np.maximum(1.0, np.abs(lo[fl]))
    hi_in[fh] -= 1e-6 * np.maximum(1.0, np.abs(hi[fh]))
    flat = bool(free[I_ZF] and prior is None)
    free_all = free
    if flat:
        # (*) z_f free without a prior (module docstring, "z_f free"): z_f moves only in the first (cold)
        # search; the warm searches hold it where that search left it (a minimum-norm step: the criterion
        # is exactly flat along the exact-fit family, so its null direction is not moved) and are then the
        # z_f-known searches at that z_f
        izf = int(np.sum(free[:I_ZF]))
        free_held = free.copy()
        free_held[I_ZF] = False
        held = (free_held, np.delete(lo, izf), np.delete(hi, izf), np.delete(lo_in, izf), np.delete(hi_in, izf))
    search_state = state
    physical_memo: dict = {}
    for j in range(1, options.max_iter + 1):
        prev_search, search_state = search_state, state
        if flat and j == 2:
            free, lo, hi, lo_in, hi_in = held
        cold_flat = flat and j == 1
        compiled = options.compute == "fast" and not cold_flat
        # the compiled search needs only the kernel arguments; the Python residual function (closures)
        # is built where it is used: the trf fallback, the reference path and the final Jacobian
        fun = None if compiled else residual_function(state, known, free, theta, prior)[0]
        x0 = np.clip(theta[free], lo_in, hi_in)
        # (*) warm iterations (j >= 2) start next to the minimum: plain Gauss-Newton steps reach it in a
        # few evaluations; the trust-region search is the fallback whenever they do not converge cleanly
        # (the cold search with z_f free stays trf, with the exact Jacobian, on either path)
        x = None
        if compiled:
            # the same searches compiled; the cold start (j = 1) by Levenberg-Marquardt + Gauss-Newton
            # instead of trf (same tolerances; trf remains the fallback)
            x = compiled_search(kernel_args(state, known, free, theta, prior), x0, lo, hi, cold=j == 1)
        elif j > 1:
            x = gauss_newton(fun, fun.jac, x0, lo, hi)
        if x is None:
            if fun is None:
                fun = residual_function(state, known, free, theta, prior)[0]
            from scipy.optimize import least_squares  # the fallback only: scipy.optimize where it is used

            x = least_squares(fun, x0, jac=fun.jac, method="trf", bounds=(lo, hi), xtol=1e-10, ftol=1e-10,
                              gtol=1e-10, max_nfev=2000, x_scale="jac").x
        theta_start = theta
        theta = theta.copy()
        theta[free] = x
        if cold_flat:
            theta = held_cold_search(theta, theta_start, fun, x, state, known, held, prior, options)
        if j >= 2 and left_physical_region(theta, theta_start, known, conds, physical_memo):
            # (*) the search left the physical region (identified roll mode not that of a ship) from a physical
            # iterate: the criterion's second, degenerate minimum (see left_physical_region); the last physical
            # iterate is kept and the iteration stops, not converged, with a warning
            warn.append(f"iteration {j}: the search left the physical region (degenerate minimum of (40)); "
                        f"the estimate of iteration {j - 1} is kept")
            theta, search_state = theta_start, prev_search
            break
        G = coeffs(theta, known, conds, Ts, options, code)
        history.append(from_moment(theta))
        if not np.all(np.isfinite(theta)):
            warn.append(f"iteration {j}: non-finite estimate")
            break
        # identifiable quantities: the discrete coefficients of every dataset
        if g_prev is not None:
            dg = np.max(np.abs(G - g_prev) / np.maximum(np.abs(g_prev), 1e-8))
            dgs.append(float(dg))
            if j >= options.min_iter and dg < options.tol:
                converged = True
                break
        g_prev = G
        # (b) residuals (42) and prefilters (43); (c) closed-loop instruments (46)-(47).
        # (*) Relaxation: from the second iteration on they are built at the mean of the last two
        # iterates, which damps the period-2 cycles that the prefilter feedback can otherwise sustain;
        # an iteration still running at ``cycle_after`` uses the mean of the last four, under which a
        # period-4 cycle (or period-2) cannot persist: its four iterates would give one constant mean.
        recent.append(theta)
        del recent[:-4]
        if options.cycle_after and j >= options.cycle_after and len(recent) == 4:
            th_mid = np.mean(recent, axis=0)
        else:
            th_mid = theta if len(recent) == 1 else 0.5 * (recent[-1] + recent[-2])
        G_mid = coeffs(th_mid, known, conds, Ts, options, code)
        newL, lam = [], []
        if fused(options) and code is not None:
            # the same steps (b)-(c) by one compiled call per dataset (shipid.methods.masscm.step)
            sims = sim_terms(th_mid, code, Ts, known_constants(known))
            moms = []
            for i, ds in enumerate(prep):
                L_i, lam_i, sim, mom = step_compiled(ds, G_mid[i], sims[i], th_mid, i, known, y_hats[i],
                                                      a_hats[i], options)
                newL.append(L_i)
                lam.append(L_i.lam)
                moms.append(mom)
                if sim is None:
                    warn.append(f"iteration {j}: model of dataset {i} ({ds.condition}) unstable; instruments kept")
                else:
                    y_hats[i], a_hats[i] = sim
            state = IVState(moms, floored_weights(lam), newL, Ts, conds)
            continue
        terms = roll_terms(th_mid, known, conds, moment=True)
        for i, ds in enumerate(prep):
            eps = ds.y - ds.Phi @ G_mid[i]
            s = first_row(options)
            if options.prefilter:
                if options.noise_model in ("auto", "bj") and j >= AUTO_HOLD + FREEZE_AFTER:
                    arma = state.L[i]          # (*) the whole noise model kept (noise_bj.FREEZE_AFTER)
                elif options.noise_model in ("auto", "bj") and j >= AUTO_HOLD:   # (*) (c, k) held (noise_bj)
                    arma = held_noise_model(eps[s:], options, state.L[i])
                else:
                    arma = fit_noise_model(eps[s:], options)
                newL.append(arma)
                lam.append(arma.lam)
            else:
                newL.append(None)
                lam.append(float(np.mean(eps[s:] ** 2)))
            sim = closed_loop_sim(ds, terms, i, known)
            if sim is None:
                warn.append(f"iteration {j}: model of dataset {i} ({ds.condition}) unstable; instruments kept")
            else:
                y_hats[i], a_hats[i] = sim
        state = IVState(build_moments(prep, newL, y_hats, a_hats, options), floored_weights(lam), newL, Ts, conds)
    free = free_all
    J = None
    if jacobian and j > 0 and np.all(np.isfinite(theta)):
        fun = residual_function(search_state, known, free, theta, prior)[0]     # the last search's criterion
        J = jacobian_cs(fun, theta[free])
    return {"theta": from_moment(theta), "theta_q": theta, "free": free, "J": J, "converged": converged, "iterations": j,
            "history": np.array(history), "dg": dgs, "state": state, "warnings": warn, "prior": prior}


__all__ = ["fused", "step_compiled", "left_physical_region", "search_bounds", "initial_state", "iterate"]
