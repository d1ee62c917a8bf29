"""Prefiltered least squares of the roll regression (35) and its Durbin–Wu–Hausman test against the refined IV.

Linder et al. (2015, seed 000) estimate (35)/(23) by instrumental variables with rudder-only instruments (46)–(47)
because the regressors ``phi_t`` of (37) are correlated with the equation error. This module asks the data whether
that is needed: after Algorithm 1 has converged, :func:`prefiltered_ls` minimises the generalised-least-squares
criterion

    sum_i ||L_i(q) y - L_i(q) Phi_i g_i(theta)||^2 / lam_i

(each dataset's regression prefiltered by the inverse ``L_i = D_i/C_i`` of its fitted Box–Jenkins noise model,
:mod:`shipid.methods.masscm.noise_bj`, held at Algorithm 1's last one), i.e. (40) with the prefiltered measured
regressors as their own instruments. Were the regressors uncorrelated with the prefiltered (white) equation error,
this would be the efficient estimator, and the IV estimate would differ from it by sampling error only.
:func:`hausman` is the Durbin–Wu–Hausman statistic of that hypothesis,

    H = d^T (Cov_IV - Cov_LS)^+ d,   d = theta_LS - theta_IV   ~ chi2(rank) under the null,

on the free physical parameters (``Cov`` by :func:`shipid.methods.masscm.assemble.covariance`; the pseudo-inverse
keeps the positive part of the difference, ``rank`` its size). Under the null ``Cov_IV - Cov_LS >= 0``; a direction
in which the LS variance exceeds twice the IV variance rejects outright (``p = 0``). :func:`choose` takes LS only when the test does not
reject at ``alpha`` and the LS estimate is finite and physical (roll mode of a ship,
:func:`~shipid.methods.masscm.plausibility.implausible_identifiable`); otherwise IV.

What the test finds in this model (measured, ``tests/methods/masscm/test_gls.py`` and the issue-17 report): the
regressor ``a_t - a_{t-2}`` contains the *current* tangential acceleration, ``a_s = v' + z_s p' + g phi - U r``,
and ``p'`` carries the current wave moment, so ``a_t`` is correlated with the current innovation of the equation
error even with noise-free sensors (a simultaneous-equation, not an errors-in-variables, correlation). With
noise-free channels the prefiltered LS criterion is moreover nearly zero along the IMU's kinematic identity
``y_t - 2 y_{t-1} + y_{t-2} ~ (T/2 z_s)(a_t - a_{t-2})`` (see
:func:`~shipid.methods.masscm.iteration.left_physical_region`), and LS runs there (``zm_bar`` to the search bound,
``m`` unbounded). With sensor noise the regressors carry errors in variables. So in the waves, sensors and both
regimes the test rejects and the refined IV stays the estimator; prefiltered LS is not an efficient alternative
for (35) in any of them. The efficient estimator with noise-free channels is the maximum-likelihood one, whose
criterion has, besides the GLS sum of squares of the reconstructed wave innovations, the log-determinant of the
contemporaneous map from the innovation to ``(p, a_s)`` (the direct feedthrough of ``tau`` into ``a_s``); that
needs the reduced form of ``a_s``, i.e. the sway row of the model (a full prediction-error/ML estimator in state
space, as :mod:`shipid.methods.masscm.crlb_kf` assumes with free sway-yaw rows), not a prefiltered regression.

Measured on the tuning seeds (``SeedSequence([100, i])``, 300-s records, the coverage regimes of
:mod:`shipid.methods.masscm.coverage`): waves, 20 runs: the test keeps IV in 20 (LS physical in 1; LS ``zm_bar``
from -0.46 to the bound 2.0, true -0.182; the LS criterion 0.4-14 at its minimum against 2.6e4-4.3e4 at the IV
estimate); sensors, 8 runs: IV in 8 (LS m 0.3957, spread 0.0024: biased by 1.8 spreads, against IV 0.3954,
spread 0.0073; true 0.4); both, 8 runs: IV in 8 (LS m 0.4061, spread 0.0280; IV 0.3844, 0.0237). At the fresh
seed 9101 (the realisations of ``shipid study mass-cm-coverage --seed 9101``; IV with the noise model
re-fitted at every iteration, before :data:`~shipid.methods.masscm.noise_bj.FREEZE_AFTER`): waves 100 of 100 IV (no p-value above
0.05; LS physical in 4; the LS criterion at its minimum below 0.002 of its value at the IV estimate in every run);
sensors 30 of 30 (largest p 2e-85; LS m 0.3972, spread 0.0031, 5 standard errors of the mean below the truth, a
spread 0.38 of the Cramér–Rao bound that only a biased estimator can have); both 30 of 30 (largest p 9e-6; LS m
0.4316, spread 0.0386, against IV 0.4029, 0.0333).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares
from scipy.stats import chi2

from shipid.estimate.iv import iv_compress
from shipid.methods.masscm.assemble import covariance
from shipid.methods.masscm.criterion import IVState, jacobian_cs, residual_function
from shipid.methods.masscm.data import Dataset, first_row
from shipid.methods.masscm.iteration import search_bounds
from shipid.methods.masscm.moments import transient_length
from shipid.methods.masscm.options import I_ZF, MassCMOptions
from shipid.methods.masscm.plausibility import implausible_identifiable
from shipid.models.roll_reduced import KnownParams, from_moment

#: Size of the Durbin–Wu–Hausman test of :func:`choose` (the usual 5 %).
HAUSMAN_ALPHA = 0.05


def ls_moments(prep: list[Dataset], L: list, options: MassCMOptions) -> list:
    """The compressed moments of the prefiltered LS criterion: (41) with ``Z = L Phi`` (the regressors as their
    own instruments); the prefilter start-up is dropped as in :func:`shipid.methods.masscm.moments.build_moments`."""
    s = first_row(options)
    out = []
    for ds, Li in zip(prep, L):
        yf = Li.prefilter(ds.y)[s:] if Li is not None else ds.y[s:]
        Pf = Li.prefilter(ds.Phi)[s:] if Li is not None else ds.Phi[s:]
        k = transient_length(Li, yf.size, options)
        out.append(iv_compress(Pf[k:], yf[k:], Pf[k:]))
    return out


def prefiltered_ls(core: dict, prep: list[Dataset], known: KnownParams,
                   options: MassCMOptions = MassCMOptions()) -> dict:
    """GLS estimate of (35) with Algorithm 1's final noise models held (module docstring).

    ``core``: the output of :func:`shipid.methods.masscm.iteration.iterate` (its last state gives ``L_i`` and
    ``lam_i``; its estimate is the start). The search is scipy's ``trf`` inside the bounds of Algorithm 1's searches
    (:func:`~shipid.methods.masscm.iteration.search_bounds`). Returns a dict like ``core`` (``theta``, ``theta_q``, ``free``, ``J``, ``prior``) with
    ``criterion`` the GLS criterion at the LS and at the IV estimate.
    """
    st = core["state"]
    state = IVState(ls_moments(prep, st.L, options), st.lam, st.L, st.Ts, st.conds)
    free, prior = core["free"], core["prior"]
    th = np.asarray(core["theta_q"], dtype=float).copy()
    fun = residual_function(state, known, free, th, prior)[0]
    lo, hi = search_bounds(free, prior, options)
    x0 = np.clip(th[free], lo + 1e-9, hi - 1e-9)
    x = least_squares(fun, x0, jac=fun.jac, method="trf", bounds=(lo, hi), xtol=1e-10, ftol=1e-10, gtol=1e-10,
                      max_nfev=2000, x_scale="jac").x
    th_ls = th.copy()
    th_ls[free] = x
    J = jacobian_cs(fun, x) if np.all(np.isfinite(x)) else None
    return {"theta": from_moment(th_ls), "theta_q": th_ls, "free": free, "J": J, "prior": prior,
            "criterion": {"ls": float(np.sum(fun(x) ** 2)), "iv": float(np.sum(fun(th[free]) ** 2))}}


def hausman(core_iv: dict, core_ls: dict) -> dict:
    """Durbin–Wu–Hausman statistic of LS against IV on the free physical parameters (module docstring).

    Returns ``statistic``, ``df``, ``p_value`` (``inf`` / ``0`` when a covariance is not finite) and the names.
    """
    c_iv, names, _ = covariance(core_iv)
    c_ls, _, _ = covariance(core_ls)
    idx = [i for i in np.flatnonzero(core_iv["free"]) if not (i == I_ZF and core_iv["prior"] is None)]
    d = np.asarray(core_ls["theta"], dtype=float)[idx] - np.asarray(core_iv["theta"], dtype=float)[idx]
    if not (np.all(np.isfinite(c_iv)) and np.all(np.isfinite(c_ls)) and np.all(np.isfinite(d))):
        return {"statistic": float("inf"), "df": len(idx), "p_value": 0.0, "names": names}
    # scale to the IV standard errors so the rank rule is unit-free
    s = np.sqrt(np.maximum(np.diag(c_iv), 1e-300))
    V = (c_iv - c_ls) / np.outer(s, s)
    w, U = np.linalg.eigh(0.5 * (V + V.T))
    if float(w.min()) < -1.0:
        # under the null LS is the efficient estimator, Cov_IV - Cov_LS >= 0; a direction in which the LS variance
        # exceeds twice the IV variance contradicts it (the test statistic alone would not see it: the positive
        # part may then have rank ~0)
        return {"statistic": float("inf"), "df": len(idx), "p_value": 0.0, "names": names,
                "reason": "LS less precise than IV"}
    keep = w > 1e-10 * max(float(w.max()), 1e-300)
    z = U[:, keep].T @ (d / s)
    stat = float(np.sum(z ** 2 / w[keep]))
    df = int(keep.sum())
    return {"statistic": stat, "df": df, "p_value": float(chi2.sf(stat, df)) if df else 0.0, "names": names}


def choose(core_iv: dict, prep: list[Dataset], known: KnownParams, options: MassCMOptions = MassCMOptions(),
           alpha: float = HAUSMAN_ALPHA) -> dict:
    """``"ls"`` when the Durbin–Wu–Hausman test does not reject at ``alpha`` and the LS estimate is finite and
    physical, else ``"iv"``; returns the choice, the test and the LS fit (``core`` form)."""
    ls = prefiltered_ls(core_iv, prep, known, options)
    test = hausman(core_iv, ls)
    physical = bool(np.all(np.isfinite(ls["theta"]))
                    and not implausible_identifiable(ls["theta"], known, core_iv["state"].conds))
    pick = "ls" if (physical and test["p_value"] > alpha) else "iv"
    return {"choice": pick, "hausman": test, "ls_physical": physical, "ls": ls}


__all__ = ["HAUSMAN_ALPHA", "ls_moments", "prefiltered_ls", "hausman", "choose"]
