"""The criterion (40)–(41) of Algorithm 1 (Linder et al. 2015) and the searches of step B(a).

``theta_j = argmin sum_i ||R_i g_i(theta) - r_i||^2 / lam_i`` with ``R_i``, ``r_i`` the compressed IV moments
of dataset i and ``g_i`` the map (33) of :mod:`shipid.models.roll_reduced`, in the load-moment
parameterisation ``q = m z_m``. The map and its Jacobian are evaluated by the kernel
:func:`shipid.methods.masscm.search.g_and_jac` (tested against :func:`shipid.models.roll_reduced.discrete_coeffs`)
for real arguments (compiled in :func:`coeffs` on the fast path; run by the interpreter,
:data:`~shipid.methods.masscm.search.g_and_jac_py`, in the residual functions, the same numbers) and by :func:`~shipid.models.roll_reduced.discrete_coeffs` itself for the complex step of the
covariance. Searches: scipy's ``trf`` (reference), an undamped Gauss–Newton for warm starts
(:func:`gauss_newton`), the compiled searches of :mod:`shipid.methods.masscm.search` (:func:`compiled_search`),
and the initial-value-free linear start (:func:`linear_initial`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from shipid.methods.masscm.options import I_ZF, MassCMOptions
from shipid.methods.masscm.search import g_and_jac, g_and_jac_py, gauss_newton as gauss_newton_compiled, known_array, \
    levenberg_marquardt
from shipid.models.roll_reduced import CALIBRATION, LOADED, NOMINAL, KnownParams, discrete_coeffs

@dataclass
class IVState:
    """The moments of one iteration: compressed IV moments, innovation variances (weights), prefilters."""

    moments: list
    lam: np.ndarray
    L: list
    Ts: np.ndarray
    conds: list


CONDITION_CODES = {NOMINAL: 0, CALIBRATION: 1, LOADED: 2}


def condition_codes(conds, options: MassCMOptions) -> np.ndarray | None:
    """The condition codes of the compiled kernels (:data:`CONDITION_CODES`) when the fast path evaluates the
    map (33) for these conditions, else None (:func:`coeffs`)."""
    if options.compute == "fast" and all(c in CONDITION_CODES for c in conds):
        return np.array([CONDITION_CODES[c] for c in conds], dtype=np.int64)
    return None


def coeffs(theta, known: KnownParams, conds, Ts, options: MassCMOptions, code: np.ndarray | None = None) -> np.ndarray:
    """``discrete_coeffs(theta, known, conds, Ts, moment=True)`` (33); compiled (same formulas) when fast.

    ``code``: :func:`condition_codes` of ``conds`` made once by a caller that evaluates the map many times."""
    if code is None:
        code = condition_codes(conds, options)
    if code is not None:
        return g_and_jac(np.asarray(theta, dtype=float), code, np.asarray(Ts, dtype=float), known_constants(known),
                         False)[0]
    return discrete_coeffs(theta, known, conds, Ts, moment=True)


def residual_function(state: IVState, known: KnownParams, free: np.ndarray, theta_fixed: np.ndarray, prior):
    """The weighted residuals ``lam_i^-1/2 (R_i g_i(theta) - r_i)`` of (40), stacked, as a function of the free
    entries ``x`` of theta (moment parameterisation), with the row ``(z_f - mean)/std`` of a prior.

    Returns ``(fun, full)``: ``fun(x)`` the residuals, ``fun.jac(x)`` their exact Jacobian and ``full(x)`` the
    whole theta. Real ``x``: the map (33) and its Jacobian by :func:`shipid.methods.masscm.search.g_and_jac`
    run by the interpreter (:data:`~shipid.methods.masscm.search.g_and_jac_py`: the same numbers, and the numpy
    path of the estimator never starts numba, whose first call costs about 40 MB and 0.3 s); complex ``x`` (complex-step derivatives of the covariance):
    :func:`shipid.models.roll_reduced.discrete_coeffs`, the reference of that kernel.
    """
    w = 1.0 / np.sqrt(state.lam)
    Rs = np.stack([mo.R for mo in state.moments]) * w[:, None, None]     # (n, 5, 5), weighted
    rs = np.stack([mo.r for mo in state.moments]) * w[:, None]
    code = np.array([CONDITION_CODES[c] for c in state.conds], dtype=np.int64)
    Ts = np.asarray(state.Ts, dtype=float)
    kc = known_constants(known)

    def full(x):
        th = theta_fixed.astype(x.dtype if np.iscomplexobj(x) else float).copy()
        th[free] = x
        return th

    def fun(x):
        th = full(x)
        if np.iscomplexobj(th):
            G = discrete_coeffs(th, known, state.conds, Ts, moment=True)
        else:
            G = g_and_jac_py(th, code, Ts, kc, False)[0]
        res = (np.einsum("nij,nj->ni", Rs, G) - rs).ravel()
        if prior is not None:
            res = np.concatenate([res, np.atleast_1d((th[I_ZF] - prior[0]) / prior[1])])
        return res

    def jac(x):
        """Exact Jacobian of ``fun`` (analytic, :func:`shipid.methods.masscm.search.g_and_jac`, interpreted)."""
        th = full(x)
        dG = g_and_jac_py(th, code, Ts, kc, True)[1][:, :, free]    # (n, 5, n_free)
        J = np.einsum("nij,njk->nik", Rs, dG).reshape(-1, dG.shape[-1])
        if prior is not None:
            row = np.zeros((1, J.shape[1]))
            row[0, int(np.sum(free[:I_ZF]))] = 1.0 / prior[1]
            J = np.vstack([J, row])
        return J

    fun.jac = jac
    fun.kernel_args = kernel_args(state, known, free, theta_fixed, prior)
    return fun, full


def kernel_args(state: IVState, known: KnownParams, free: np.ndarray, theta_fixed: np.ndarray, prior) -> tuple:
    """The residuals of :func:`residual_function` as arguments of the compiled kernels
    (:func:`shipid.methods.masscm.search.residual`): the same weighted ``R_i``, ``r_i``."""
    w = 1.0 / np.sqrt(state.lam)
    Rs = np.stack([mo.R for mo in state.moments]) * w[:, None, None]
    rs = np.stack([mo.r for mo in state.moments]) * w[:, None]
    code = np.array([CONDITION_CODES[c] for c in state.conds], dtype=np.int64)
    pr = (np.array([1.0, prior[0], prior[1], float(np.sum(free[:I_ZF]))]) if prior is not None
          else np.array([0.0, 0.0, 1.0, 0.0]))
    return (np.flatnonzero(free).astype(np.int64), np.asarray(theta_fixed, dtype=float).copy(), Rs, rs, code,
            np.asarray(state.Ts, dtype=float), known_constants(known), pr)


@functools.lru_cache(maxsize=16)
def known_constants(known: KnownParams) -> np.ndarray:
    a = known_array(known)
    a.flags.writeable = False                # shared by every call: read-only
    return a


def compiled_search(args: tuple, x0: np.ndarray, lo: np.ndarray, hi: np.ndarray, cold: bool) -> np.ndarray | None:
    """Step B(a) by the compiled kernels of :mod:`shipid.methods.masscm.search`, or None (caller: ``trf``).

    Warm iterations: the Gauss-Newton of :func:`gauss_newton`. Cold start (first iteration): a bounded
    Levenberg-Marquardt search to the tolerances of the ``trf`` search (``xtol = ftol = gtol = 1e-10``;
    a second try with strong initial damping when the first ends against a bound), then the same
    Gauss-Newton as a polish where it confirms the minimum. A search that does not converge returns None
    and the caller runs ``trf`` from ``x0``.
    """
    x = np.asarray(x0, dtype=float)
    if cold:
        # from the same start: first with little damping; if that ends against the |zm_bar| bound
        # (a stationary point on the bound face, ~6 % of Table-3 starts), once more with strong initial
        # damping (shorter first steps), which reaches the interior minimum in those cases
        for mu0 in (1e-3, 1e2):
            status, xl, _nfev = levenberg_marquardt(x, lo, hi, *args, 500, 1e-10, 1e-10, 1e-10, mu0)
            if status == 1:
                break
        if status != 1:
            return None
        # converged to the trf tolerances; a Gauss-Newton polish is kept when it confirms a minimum (it
        # refuses when the cost no longer resolves the remaining step, as at a stop on ftol)
        ok, xg = gauss_newton_compiled(xl, lo, hi, *args, 20, 1e-10, 1e-9)
        return xg if ok else xl
    ok, x = gauss_newton_compiled(x, lo, hi, *args, 20, 1e-10, 1e-9)
    return x if ok else None


def floored_weights(lam) -> np.ndarray:
    """The innovation variances lambda_i of the datasets as the weights of (40), floored at 1e-12 of the
    largest so that a (numerically) perfect fit of one dataset cannot make its weight infinite; all ones
    when every lambda is zero (noise-free data fitted exactly)."""
    lam = np.asarray(lam, dtype=float)
    return np.maximum(lam, 1e-12 * max(lam.max(), 1e-300)) if lam.max() > 0 else np.ones_like(lam)


def held_cold_search(theta: np.ndarray, theta_start: np.ndarray, fun, x: np.ndarray, state: "IVState",
                      known: KnownParams, held: tuple, prior, options: MassCMOptions) -> np.ndarray:
    """Second stage of the cold search with z_f free (no prior): the z_f-known cold search at the z_f
    where the free (trf) search stopped, from the original start; the lower criterion value wins.

    The criterion (40) is exactly flat along the exact-fit family, so its minimum over the other eight
    parameters at any fixed z_f (inside the physical range reached by the free search) is the global one;
    the free search, pressed against the physical bounds ``k, A_x, d >= 0`` or ``|zm_bar| <= zm_bound``,
    can stop in a degenerate local minimum instead (the "smooth signal" ``y_t ~ 2 y_{t-1} - y_{t-2}``,
    A2 -> large, or the load moment -> 0). The same search as with z_f known (compiled or trf, from the
    same start) does not.
    """
    free_h, lo_h, hi_h, lo_in_h, hi_in_h = held
    th_fix = theta_start.copy()
    th_fix[I_ZF] = theta[I_ZF]
    x0 = np.clip(th_fix[free_h], lo_in_h, hi_in_h)
    x2 = None
    if options.compute == "fast":
        x2 = compiled_search(kernel_args(state, known, free_h, th_fix, prior), x0, lo_h, hi_h, cold=True)
    fun2 = residual_function(state, known, free_h, th_fix, prior)[0]
    if x2 is None:
        from scipy.optimize import least_squares  # the fallback only: scipy.optimize where it is used

        x2 = least_squares(fun2, x0, jac=fun2.jac, method="trf", bounds=(lo_h, hi_h), xtol=1e-10, ftol=1e-10,
                           gtol=1e-10, max_nfev=2000, x_scale="jac").x
    r1, r2 = fun(x), fun2(x2)
    c1, c2 = float(r1 @ r1), float(r2 @ r2)
    if np.isfinite(c2) and c2 < c1:
        th2 = th_fix.copy()
        th2[free_h] = x2
        return th2
    return theta


def jacobian_cs(fun, x):
    J = np.empty((fun(x).size, x.size))
    for j in range(x.size):
        xc = x.astype(complex)
        xc[j] += 1e-30j
        J[:, j] = fun(xc).imag / 1e-30
    return J


def gauss_newton(fun, jac, x0: np.ndarray, lo: np.ndarray, hi: np.ndarray, max_steps: int = 20,
                  xtol: float = 1e-10, floor: float = 1e-9) -> np.ndarray | None:
    """Undamped Gauss-Newton from a start next to the minimum, or None (caller falls back to ``trf``).

    Accepts only monotone cost decrease and iterates strictly inside the bounds. Converged when an
    accepted step is below ``xtol`` relative to ``x`` (the trust-region search's ``xtol``), or when the
    cost stops decreasing (rounding floor) with a proposed step below ``floor``: the Gauss-Newton step
    estimates the distance to the minimum, so ``x`` is then within ``floor`` of it.
    """
    x = x0.copy()
    r = fun(x)
    cost = float(r @ r)
    for _ in range(max_steps):
        J = jac(x)
        dx = np.linalg.lstsq(J, -r, rcond=None)[0]
        xn = x + dx
        if not (np.all(np.isfinite(xn)) and np.all(xn > lo) and np.all(xn < hi)):
            return None
        rn = fun(xn)
        cn = float(rn @ rn)
        small = np.linalg.norm(dx) <= xtol * (xtol + np.linalg.norm(x))
        if not np.isfinite(cn) or cn > cost * (1 + 1e-12) + 1e-300:
            return x if np.linalg.norm(dx) <= floor * np.linalg.norm(x) else None
        x, r, cost = xn, rn, cn
        if small:
            return x
    return None


def linear_initial(state: "IVState", known: KnownParams, z_f: float) -> np.ndarray:
    """Initial-value-free starting point: the multiplied-out (equation-error) form of (40), which is linear.

    With ``g_i = num_i / den_i`` (33), ``R_i g_i = r_i`` is multiplied by ``den_i`` to
    ``R_i num_i - r_i den_i = 0``. For a fixed ``z_f`` both ``num_i`` and ``den_i`` are linear in
    ``p = [k, A_x, d, K_r, K_vdot, K_delta, q, w]`` with the load moment ``q = m z_m`` and ``w = q zm_bar``
    (A2 of the loaded dataset contains ``q (zm_bar - zs_bar) = w - q zs_bar``), so one linear least-squares
    solve gives all of them (a Steiglitz–McBride-type first step). Returns theta in the moment
    parameterisation with ``zm_bar = w / q``.
    """
    rows, rhs = [], []
    kn = known
    zg, zs = kn.zg_bar + z_f, kn.zs_bar + z_f
    for i, (mo, cond, T) in enumerate(zip(state.moments, state.conds, state.Ts)):
        # express A2, B, kp, d, K_r, K_delta as (coefficient row over p, constant)
        def lin(coef, const=0.0):
            return np.asarray(coef, dtype=float), float(const)
        qc = kn.m_c * (kn.zc_bar + z_f)
        base_A2 = kn.M * zg * (kn.zg_bar - kn.zs_bar)
        if cond == NOMINAL:
            A2 = lin([0, 1, 0, 0, -zs, 0, 0, 0], base_A2)
            B = lin([0, 0, 0, 0, 1, 0, 0, 0], kn.M * zg)
        elif cond == CALIBRATION:
            A2 = lin([0, 1, 0, 0, -zs, 0, 0, 0], base_A2 + qc * (kn.zc_bar - kn.zs_bar))
            B = lin([0, 0, 0, 0, 1, 0, 0, 0], kn.M * zg + qc)
        else:
            A2 = lin([0, 1, 0, 0, -zs, 0, -kn.zs_bar, 1], base_A2)
            B = lin([0, 0, 0, 0, 1, 0, 1, 0], kn.M * zg)
        kp = lin([1, 0, 0, 0, -kn.g, 0, 0, 0])
        d = lin([0, 0, 1, 0, 0, 0, 0, 0])
        Kr = lin([0, 0, 0, 1, 0, 0, 0, 0])
        Kd = lin([0, 0, 0, 0, 0, 1, 0, 0])

        def comb(*terms):
            c = sum(a * t[0] for a, t in terms)
            k = sum(a * t[1] for a, t in terms)
            return c, k
        num = [comb((2 * T * T, kp), (-8, A2)), comb((-2 * T, d), (T * T, kp), (4, A2)),
               comb((-2 * T, B)), comb((2 * T, Kr)), comb((2 * T, Kd))]
        den = comb((2 * T, d), (T * T, kp), (4, A2))
        Nc = np.array([n[0] for n in num]); Nk = np.array([n[1] for n in num])
        w = 1.0 / np.sqrt(state.lam[i])
        rows.append(w * (mo.R @ Nc - np.outer(mo.r, den[0])))
        rhs.append(-w * (mo.R @ Nk - mo.r * den[1]))
    A = np.vstack(rows)
    b = np.concatenate(rhs)
    sc = np.maximum(np.linalg.norm(A, axis=0), 1e-300)
    p, *_ = np.linalg.lstsq(A / sc, b, rcond=None)
    p = p / sc
    k, A_x, d, K_r, K_v, K_d, q, w_ = p
    zm = w_ / q if q != 0 else 0.0
    return np.array([k, A_x, d, K_r, K_v, K_d, z_f, q, zm])


__all__ = ["IVState", "CONDITION_CODES", "condition_codes", "coeffs", "residual_function", "kernel_args", "known_constants",
           "compiled_search", "floored_weights", "held_cold_search", "jacobian_cs", "gauss_newton", "linear_initial"]
