"""Searches of the online monitor (:mod:`shipid.methods.monitor.estimator`) on compressed IV criteria (40)-(41).

:func:`search`: the criterion of Algorithm 1 (Linder et al. 2015, eq. 40) over several datasets, minimised
over chosen entries of ``theta_q`` (moment parameterisation ``q = m z_m``, z_f held) by damped Gauss-Newton
with the complex-step Jacobian of :func:`shipid.models.roll_reduced.discrete_coeffs` (33). :func:`fit_load`:
the loaded condition's load ``(q, zm_bar)`` alone, the ship's coefficients held, with the analytic derivative.
"""

from __future__ import annotations

import math

import numpy as np

from shipid.models.roll_reduced import LOADED, KnownParams, discrete_coeffs, roll_terms

I_Q, I_ZM = 7, 8


def search(moments, lams, known: KnownParams, conds, T: float, theta_q: np.ndarray, free: np.ndarray,
           zm_bound: float, max_iter: int = 40):
    """Minimise (40) over the ``free`` entries of ``theta_q`` (damped Gauss-Newton, complex-step Jacobian).

    Returns ``(theta_q, converged, J)`` with ``J`` the Jacobian of the weighted residuals at the solution.
    """
    Rs = [mo.R / math.sqrt(l) for mo, l in zip(moments, lams)]
    rs = [mo.r / math.sqrt(l) for mo, l in zip(moments, lams)]
    Ts = np.full(len(conds), T)
    idx = np.flatnonzero(free)
    zb = zm_bound

    def fun(x):
        th = theta_q.astype(x.dtype).copy()
        th[idx] = x
        G = discrete_coeffs(th, known, conds, Ts, moment=True)
        return np.concatenate([R @ G[i] - r for i, (R, r) in enumerate(zip(Rs, rs))])

    def jac(x):
        J = np.empty((sum(r.size for r in rs), x.size))
        for j in range(x.size):
            xc = x.astype(complex)
            xc[j] += 1e-30j
            J[:, j] = fun(xc).imag / 1e-30
        return J

    x = theta_q[idx].astype(float).copy()
    izm = list(idx).index(I_ZM) if I_ZM in idx else None
    res = fun(x)
    cost = float(res @ res)
    mu = 1e-4
    converged = False
    J = jac(x)
    for _ in range(max_iter):
        A, gr = J.T @ J, J.T @ res
        D = np.diag(np.maximum(np.diag(A), 1e-300))
        accepted = False
        while mu < 1e12:
            try:
                dx = -np.linalg.solve(A + mu * D, gr)
            except np.linalg.LinAlgError:
                mu *= 10
                continue
            xn = x + dx
            if izm is not None and abs(xn[izm]) > zb:
                mu *= 10
                continue
            rn = fun(xn)
            cn = float(rn @ rn)
            if np.isfinite(cn) and cn <= cost:
                accepted = True
                break
            mu *= 10
        if not accepted:
            converged = bool(np.linalg.norm(gr) <= 1e-8 * (1 + cost))
            break
        small = np.linalg.norm(dx) <= 1e-9 * (1e-9 + np.linalg.norm(x))
        x, res, cost = xn, rn, cn
        mu = max(mu * 0.1, 1e-12)
        J = jac(x)
        if small or cost == 0.0:
            converged = True
            break
    th = theta_q.copy()
    th[idx] = x
    return th, converged, J


def fit_load(mom, lam: float, known: KnownParams, T: float, theta_q: np.ndarray, zm_bound: float):
    """``(q, zm_bar)`` of the loaded condition from its compressed criterion ``mom`` with the ship's coefficients held at ``theta_q``.

    Gauss-Newton on the five residuals ``(R g(q, zm_bar) - r)/sqrt(lam)`` of (40) with the analytic
    derivative of (33): ``A2 = c_A2 + q (zm_bar - zs_bar)`` and ``B = c_B + q`` (22), the rest fixed.
    Returns ``(theta_q, cov)`` (cov of ``(q, zm_bar)``, None when the fit fails).
    """
    kn = known
    tm = roll_terms(theta_q, kn, [LOADED], moment=True)
    q, zm = float(theta_q[I_Q]), float(theta_q[I_ZM])
    cA2 = float(tm["A2"][0]) - q * (zm - kn.zs_bar)
    cB = float(tm["B"][0]) - q
    kp, d, Kr, Kd = (float(tm[k][0]) for k in ("kp", "d", "K_r", "K_delta"))
    w = 1.0 / math.sqrt(lam)
    R, r = mom.R * w, mom.r * w
    TT = T * T

    def g_and_jac(q, zm):
        A2 = cA2 + q * (zm - kn.zs_bar)
        B = cB + q
        den = 2 * d * T + kp * TT + 4 * A2
        g = np.array([2 * kp * TT - 8 * A2, -2 * d * T + kp * TT + 4 * A2, -2 * T * B, 2 * T * Kr,
                      2 * T * Kd]) / den
        dA2 = np.array([zm - kn.zs_bar, q])
        dN = np.outer([-8.0, 4.0, 0.0, 0.0, 0.0], dA2)
        dN[2, 0] -= 2 * T
        return g, (dN - np.outer(g, 4 * dA2)) / den

    x = np.array([q, zm])
    g, dg = g_and_jac(*x)
    res = R @ g - r
    cost = float(res @ res)
    ok = False
    for _ in range(50):
        J = R @ dg
        try:
            dx = -np.linalg.lstsq(J, res, rcond=None)[0]
        except np.linalg.LinAlgError:
            break
        step = 1.0
        while step > 1e-6:
            xn = x + step * dx
            if abs(xn[1]) <= zm_bound:
                gn, dgn = g_and_jac(*xn)
                rn = R @ gn - r
                cn = float(rn @ rn)
                if np.isfinite(cn) and cn <= cost:
                    break
            step *= 0.5
        else:
            ok = bool(np.linalg.norm(J.T @ res) <= 1e-10 * (1.0 + cost))
            break
        small = np.linalg.norm(step * dx) <= 1e-10 * (1e-10 + np.linalg.norm(x))
        x, g, dg, res, cost = xn, gn, dgn, rn, cn
        if small:
            ok = True
            break
    th = theta_q.copy()
    th[[I_Q, I_ZM]] = x
    if not ok:
        return th, None
    J = R @ dg
    try:
        S = np.linalg.inv(J.T @ J)
    except np.linalg.LinAlgError:
        return th, None
    return th, 0.5 * (S + S.T)


__all__ = ["search", "fit_load"]
