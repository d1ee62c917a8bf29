"""Levenberg-damped Fisher scoring of a refinement likelihood (Linder et al. 2015; beyond the paper).

The one search of the maximum-likelihood refinements :mod:`shipid.methods.masscm.pem` (exact time-domain
likelihood) and :mod:`shipid.methods.masscm.whittle` (banded Whittle likelihood), which differ only in the
likelihood, its score and information, and which local parameters a model has. The parameters are the shared
``theta`` (all ``n_theta`` entries, or none) and, per dataset, the entries ``fl`` of its local vector; a step
vector is ``[theta[th_idx], loc_0[fl], loc_1[fl], ...]`` (:func:`apply_step`).

Iteration (Ljung 1999 §10.2): with the expected information ``I`` (symmetrised) and the
score ``g`` scaled to unit diagonal (``In = I / (d d^T)``, ``gn = g / d``, ``d = sqrt(diag I)``), the Newton
decrement ``gn^T In^+ gn / 2`` (the log-likelihood gain a full step predicts) below ``tol`` is convergence;
otherwise the step ``(In + mu I)^-1 gn / d`` is accepted when the negative log-likelihood does not increase
(``mu`` divided by 3, floored at 1e-6), else ``mu`` grows tenfold, up to 12 tries. With no ascent step the search
stops, converged only if the decrement is below ``100 tol``.
"""

from __future__ import annotations

import numpy as np


def perturbed(evaluate, theta, loc, kind: str, i: int, rel_step: float):
    """``(evaluate(theta', loc'), h)`` for the forward difference of entry ``i`` of ``theta`` (``kind == "t"``) or of
    ``loc`` (``"l"``) with step ``h = rel_step max(|p_i|, 0.1)``; where the model is not admissible there
    (``evaluate`` returns ``None``) the step is ``-h``, and ``(None, -h)`` when neither side is."""
    t2, l2 = theta.copy(), loc.copy()
    vec = t2 if kind == "t" else l2
    h = rel_step * max(abs(vec[i]), 0.1)
    vec[i] += h
    r = evaluate(t2, l2)
    if r is None:
        vec[i] -= 2 * h
        r = evaluate(t2, l2)
        h = -h
    return r, h


def apply_step(theta, locs, step, th_idx, fl, nloc):
    """``theta`` and the local vectors ``locs`` moved by ``step`` (layout of the module docstring); copies."""
    t2 = theta.copy()
    t2[th_idx] += step[:len(th_idx)]
    l2 = []
    for d, loc in enumerate(locs):
        l = loc.copy()
        l[fl] += step[len(th_idx) + d * nloc: len(th_idx) + (d + 1) * nloc]
        l2.append(l)
    return t2, l2


def fisher_scoring(objective, score_information, theta, locs, free_local, n_theta: int, max_iter: int, tol: float,
                   *, fix_theta: bool = False, only=None):
    """Levenberg-damped Fisher scoring (module docstring) from ``theta`` and the local vectors ``locs``.

    Parameters
    ----------
    objective : callable
        ``objective(theta, locs) -> float``, the negative log-likelihood (``inf`` where not admissible).
    score_information : callable
        ``score_information(theta, locs, th_idx, fl) -> (g, I)``: score of the log-likelihood and expected
        information over ``theta[th_idx]`` and each dataset's ``loc[fl]``.
    free_local : list of int
        The local parameters of the model; ``only`` (local indices) frees just those of them.
    n_theta : int
        Length of ``theta``; ``fix_theta`` holds it.
    max_iter, tol : int, float
        Iteration limit and the Newton-decrement convergence threshold.

    Returns
    -------
    tuple
        ``(theta, locs, information (None if the start is not admissible), loglik, iterations, converged)``.
    """
    fl = [i for i in free_local if only is None or i in only]
    th_idx = [] if fix_theta else list(range(n_theta))
    nloc = len(fl)
    P = len(th_idx) + nloc * len(locs)
    theta, locs = theta.copy(), [l.copy() for l in locs]
    f = objective(theta, locs)
    if not np.isfinite(f):
        return theta, locs, None, -np.inf, 0, False
    mu, conv, it = 1e-3, False, 0
    info = None
    for it in range(1, max_iter + 1):
        g, info = score_information(theta, locs, th_idx, fl)
        info = 0.5 * (info + info.T)
        dg = np.sqrt(np.maximum(np.diag(info), 1e-300))
        In = info / np.outer(dg, dg)
        gn = g / dg
        decrement = 0.5 * float(gn @ np.linalg.lstsq(In, gn, rcond=None)[0])   # predicted gain of a full step
        if decrement < tol:
            conv = True
            break
        accepted = False
        for _ in range(12):
            try:
                step = np.linalg.solve(In + mu * np.eye(P), gn) / dg
            except np.linalg.LinAlgError:
                mu *= 10
                continue
            t2, l2 = apply_step(theta, locs, step, th_idx, fl, nloc)
            f2 = objective(t2, l2)
            if np.isfinite(f2) and f2 <= f:
                theta, locs, f = t2, l2, f2
                mu = max(mu / 3, 1e-6)
                accepted = True
                break
            mu *= 10
        if not accepted:                     # no ascent step: converged only if the gain left is negligible
            conv = decrement < 100 * tol
            break
    return theta, locs, info, -f, it, conv


__all__ = ["fisher_scoring", "apply_step", "perturbed"]
