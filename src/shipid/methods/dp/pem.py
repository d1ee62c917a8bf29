"""Noise intensities and observed-information covariance of one DP scheme (Fossen, Sagatun & Sørensen 1996).

Fossen, Sagatun & Sørensen (1996) estimate θ with the state-augmented EKF (Table 1,
eqs. 20–25) and assume the noise covariances known. Here, after the EKF passes of a scheme
(:func:`shipid.methods.dp.estimator.run_stage`) have found a starting point, the scheme's free
parameters θ_f and the noise intensities are estimated together by the prediction-error
(maximum-likelihood) method around the filter: the innovation log-likelihood ℓ of the EKF
with θ fixed (:mod:`shipid.methods.dp.loglik`, summed over the scheme's trials) is
maximised over

    φ = [θ_f, a_h, a_b, a_pos, a_psi],   q_h = q_h⁰ e^{2a_h},  q_b = q_b⁰ e^{2a_b},
                                          σ_pos = σ_pos⁰ e^{a_pos},  σ_ψ = σ_ψ⁰ e^{a_psi}

(SI1 has no heading channel, so no a_psi), i.e. the momentum process noise w_h (eq. 35),
the bias random walk w_b (eq. 37) and the position/heading measurement noise (eqs. 44–45),
each as a scale on the nominal level of :class:`shipid.methods.dp.estimator.DPOptions`.

Reported covariance: the **observed information**. The Hessian H of −ℓ over φ at the
optimum is taken by central finite differences of the full filter likelihood (states and
biases re-estimated by the filter at every evaluation), and ``cov(θ̂_f) = [H⁻¹]_θθ`` —
the θ block of the inverse, so the uncertainty of the estimated noise levels is included.
Why not the filter's P_θθ: the augmented EKF's P_θθ after a pass assumes the noise
intensities known and ignores that its gain depends on θ; with noise levels that differ from
the assumed ones (a factor 2 either way) it was wrong by factors of 2–10 (±2σ
coverage 44 %, ``docs/validation/dp.md``). The Hessian of the likelihood measures the information actually in the
data under the noise levels the data show.

Parameters frozen from an earlier scheme (θ_c, covariance Σ_c) are handled as in the
paper (fixed at their values) and their uncertainty is propagated to first order: with
``J = −H⁻¹ ∂²(−ℓ)/∂φ∂θ_c`` (the sensitivity of the optimum to θ_c),
``cov(θ̂_f) += J Σ_c Jᵀ`` and ``cov(θ̂_f, θ_c) = J Σ_c``.

Noise levels the data do not determine -- at a bound of the log-scale, within 0.25 of it, or
with a curvature that is not positive (the likelihood flat or concave along it) -- are held
at their optimum when H is formed (:func:`undetermined_noise`), so H is that of θ and the noise
directions the data do determine; they are listed in ``diagnostics["noise_at_bound"]`` and
reported as not determined. Each is then profiled over the range the data allow
(:func:`noise_profile`: its likelihood-ratio interval) and the likelihood-weighted spread of θ̂
over that range is added to ``cov(θ̂_f)`` (law of total variance), so θ's std does not assume the
undetermined level known.

A scheme has *settled* when the optimiser stopped on its gradient test, H is positive
definite and the Newton decrement ``sqrt(gᵀ H⁻¹ g)`` at the final point is below 0.1 (the
optimum is within 0.1 std of where it stopped). Otherwise the caller warns and marks the
scheme's std unreliable.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from shipid.errors import ConvergenceError
from shipid.methods.dp.loglik import momentum_loglik, surge_loglik

#: Noise scales of each kind of scheme, in the order of φ after θ_f.
NOISE_NAMES = {"surge": ("q_h", "q_b", "sigma_pos"), "momentum": ("q_h", "q_b", "sigma_pos", "sigma_psi")}
#: Bounds of the log-scales a (a factor e³ ≈ 20 either way of the nominal level).
A_BOUND = 3.0


@dataclass
class PEMResult:
    """Outcome of :func:`pem_stage`.

    Attributes
    ----------
    theta : ndarray (p,)
        Estimates of the free parameters.
    cov_free : ndarray (p, p)
        Their covariance (observed information plus the considered parameters' share).
    cross : ndarray (p, c)
        Covariance of θ̂_f with the considered parameters.
    log_scales, log_scales_std : ndarray (m,)
        Estimated noise log-scales a and their std (from H⁻¹).
    loglik : float
    settled : bool
    diagnostics : dict
    """

    theta: np.ndarray
    cov_free: np.ndarray
    cross: np.ndarray
    log_scales: np.ndarray
    log_scales_std: np.ndarray
    loglik: float
    settled: bool
    diagnostics: dict = field(default_factory=dict)


def thrust_force(U: np.ndarray, theta: np.ndarray, arms: np.ndarray) -> np.ndarray:
    """``T(α) K u`` (eq. 7 columns, eq. 47 grouping) per sample, ``(n, 3)`` bis; U = [u1..u6, α6]."""
    u = U[:, :6]
    ca, sa = np.cos(U[:, 6]), np.sin(U[:, 6])
    k = np.array([theta[5], theta[5], theta[6], theta[6], theta[7], theta[8]])
    f = u * k
    l1, l2, l3, l4, l5, l6 = arms
    return np.column_stack([f[:, 0] + f[:, 1] + ca * f[:, 5],
                            f[:, 2] + f[:, 3] + f[:, 4] + sa * f[:, 5],
                            l1 * f[:, 0] - l2 * f[:, 1] - l3 * f[:, 2] - l4 * f[:, 3] + l5 * f[:, 4]
                            + l6 * sa * f[:, 5]])


class StageLikelihood:
    """−ℓ of one scheme as a function of the full θ (9,) and the noise log-scales."""

    def __init__(self, kind: str, data: list[dict], vessel, options):
        self.kind = "surge" if kind == "surge" else "momentum"
        self.data = data
        self.vessel = vessel
        self.opt = options
        b = vessel.bis
        self.sp0 = options.sigma_pos / b.L
        self.a2 = np.array([1.0, 1.0, options.yaw_arm ** 2])
        self.dts = [np.ascontiguousarray(np.diff(d["t"])) for d in data]
        self.n_eval = 0

    @property
    def noise_names(self) -> tuple[str, ...]:
        return NOISE_NAMES[self.kind]

    def noise(self, a: np.ndarray) -> dict:
        """Noise levels (bis) for log-scales ``a``."""
        o = self.opt
        out = {"q_h": o.q_h * np.exp(2 * a[0]), "q_b": o.q_b * np.exp(2 * a[1]),
               "sigma_pos": self.sp0 * np.exp(a[2])}
        out["sigma_psi"] = o.sigma_psi * np.exp(a[3]) if self.kind == "momentum" else np.nan
        return out

    def nll(self, theta_full: np.ndarray, a: np.ndarray) -> float:
        """−ℓ summed over the trials (raises ConvergenceError when a filter fails)."""
        self.n_eval += 1
        nz = self.noise(a)
        o = self.opt
        v = self.vessel
        total = 0.0
        for d, dt in zip(self.data, self.dts):
            tau = thrust_force(d["U"], theta_full, v.arms)
            if self.kind == "surge":
                sp = nz["sigma_pos"]
                Z = np.ascontiguousarray(d["Z"][:, 0])
                x0 = np.array([0.0, Z[d["first"]], 0.0])
                P0 = np.diag([o.h0_std ** 2, 2 * sp ** 2, o.b0_std ** 2])
                ll, _, _, bad = surge_loglik(Z, dt, np.ascontiguousarray(tau[:, 0]), float(v.M[0, 0]),
                                             float(theta_full[0]), nz["q_h"], nz["q_b"], sp ** 2, x0, P0)
            else:
                sp, ss = nz["sigma_pos"], nz["sigma_psi"]
                A_h = np.zeros((3, 3))
                A_h[0, 0], A_h[1, 1], A_h[1, 2], A_h[2, 1], A_h[2, 2] = theta_full[:5]
                x0 = np.concatenate([np.zeros(3), d["Z"][d["first"]], np.zeros(3)])
                P0 = np.diag(np.concatenate([[o.h0_std ** 2] * 3, [sp ** 2, sp ** 2, ss ** 2],
                                             o.b0_std ** 2 * self.a2]))
                R = np.array([sp ** 2, sp ** 2, ss ** 2])
                ll, _, _, bad = momentum_loglik(np.ascontiguousarray(d["Z"]), dt, tau, v.M, v.Minv, A_h,
                                                nz["q_h"] * self.a2, nz["q_b"] * self.a2, R, x0, P0)
            if bad >= 0:
                raise ConvergenceError(f"likelihood filter failed at step {bad} of {d['source']}")
            total -= ll
        return float(total)


def measurement_log_scales(kind: str, data: list[dict], vessel, options) -> dict:
    """Starting log-scales of the measurement noise from the data: second differences of the fixes.

    For white noise of std σ on a smooth track, ``Δ²z_k = z_{k+1} − 2z_k + z_{k−1}`` has variance
    6σ² (the motion adds ``z̈ dt²``, a few cm at 1 Hz, against 0.5 m); σ is taken robustly as
    ``1.4826 MAD(Δ²z) / √6`` over every trial of the scheme. Only a starting point of the
    likelihood maximisation.
    """
    cols = [0] if kind == "surge" else [0, 1, 2]
    sig = []
    for c in cols:
        d2 = np.concatenate([np.diff(d["Z"][:, c], 2) for d in data])
        d2 = d2[np.isfinite(d2)]
        if d2.size < 10:
            return {}
        sig.append(1.4826 * np.median(np.abs(d2 - np.median(d2))) / np.sqrt(6.0))
    sp0 = options.sigma_pos / vessel.bis.L
    out = {"sigma_pos": float(np.log(max(np.mean(sig[:2]) if kind != "surge" else sig[0], 1e-12) / sp0))}
    if kind != "surge":
        out["sigma_psi"] = float(np.log(max(sig[2], 1e-12) / options.sigma_psi))
    return {k: float(np.clip(v, -A_BOUND + 0.1, A_BOUND - 0.1)) for k, v in out.items()}


def _hessian(fun, z: np.ndarray, h: np.ndarray, f0: float) -> np.ndarray:
    """Finite-difference Hessian of ``fun`` at ``z`` with steps ``h`` (n² + n evaluations).

    Diagonal: central second differences. Off-diagonal: the symmetric form
    ``[f(z+h_i+h_j) − f_i⁺ − f_j⁺ + 2f₀ − f_i⁻ − f_j⁻ + f(z−h_i−h_j)] / (2 h_i h_j)``
    (second-order accurate, reusing the diagonal evaluations).
    """
    n = z.size
    H = np.empty((n, n))
    fp = np.empty(n)
    fm = np.empty(n)
    E = np.diag(h)
    for i in range(n):
        fp[i], fm[i] = fun(z + E[i]), fun(z - E[i])
        H[i, i] = (fp[i] - 2 * f0 + fm[i]) / h[i] ** 2
    for i in range(n):
        for j in range(i + 1, n):
            v = (fun(z + E[i] + E[j]) - fp[i] - fp[j] + 2 * f0 - fm[i] - fm[j] + fun(z - E[i] - E[j]))
            H[i, j] = H[j, i] = v / (2 * h[i] * h[j])
    return H


def _modified(H: np.ndarray) -> np.ndarray:
    """``H`` with its eigenvalues made positive (|λ|, at least 1e-6 of the largest): a descent metric."""
    w, V = np.linalg.eigh(0.5 * (H + H.T))
    w = np.maximum(np.abs(w), 1e-6 * max(np.max(np.abs(w)), 1e-300))
    return (V * w) @ V.T


def _steps(H: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Difference steps of about 0.3 std of each coordinate from the curvature ``H`` (else ``h``)."""
    d = np.diag(H)
    out = h.copy()
    ok = d > 0
    out[ok] = np.clip(0.3 / np.sqrt(d[ok]), 1e-4 * h[ok], 30.0 * h[ok])
    return out


def _gradient(fun, z: np.ndarray, h: np.ndarray) -> np.ndarray:
    g = np.empty(z.size)
    for i in range(z.size):
        e = np.zeros(z.size)
        e[i] = h[i]
        g[i] = (fun(z + e) - fun(z - e)) / (2 * h[i])
    return g


def pem_stage(lik: StageLikelihood, theta_full: np.ndarray, free: list[int], theta_scale: np.ndarray,
              consider: list[int], cov_prev: np.ndarray, a0: np.ndarray, *, max_newton: int = 20) -> PEMResult:
    """Maximise ℓ over (θ_f, a) from ``theta_full[free]``, ``a0``; observed-information covariance.

    Parameters
    ----------
    lik : StageLikelihood
    theta_full : ndarray (9,)
        Values of every θ (the free ones: the starting point, e.g. the EKF's estimate).
    free : list of int
        Indices of θ_f.
    theta_scale : ndarray (p,)
        A scale of each θ_f (e.g. its EKF std): the optimiser works in these units.
    consider : list of int
        Frozen parameters whose uncertainty (``cov_prev``) is propagated.
    cov_prev : ndarray (9, 9)
    a0 : ndarray (m,)
        Starting noise log-scales.
    """
    p, m = len(free), len(a0)
    th_base = np.asarray(theta_full, dtype=float).copy()
    s = np.asarray(theta_scale, dtype=float)
    z0 = np.concatenate([np.zeros(p), np.asarray(a0, dtype=float)])

    def unpack(z):
        th = th_base.copy()
        th[free] = th_base[free] + s * z[:p]
        return th, z[p:]

    def f(z):
        th, a = unpack(z)
        try:
            return lik.nll(th, a)
        except ConvergenceError:
            return np.inf

    lo = np.concatenate([np.full(p, -np.inf), np.full(m, -A_BOUND)])
    hi = -lo
    f_start = f(z0)
    if not np.isfinite(f_start):
        raise ConvergenceError("the likelihood filter fails at the EKF estimate")
    # Newton's method on the numerical Hessian (recomputed when progress is slow), line search
    z, fz = z0.copy(), f_start
    h = np.concatenate([np.full(p, 0.3), np.full(m, 0.05)])
    H = _hessian(f, z, h, fz)
    newton = []
    success = False
    n_hess = 0
    for it in range(max_newton):
        g = _gradient(f, z, 0.1 * h)
        Hm = _modified(H)
        step = -np.linalg.solve(Hm, g)
        dec = float(np.sqrt(max(-(g @ step), 0.0)))
        newton.append(dec)
        if dec < 0.05:
            success = True
            break
        lam = 1.0
        for _ in range(8):
            zn = np.clip(z + lam * step, lo, hi)
            fn = f(zn)
            if fn < fz:
                break
            lam *= 0.5
        else:
            break
        z, fz = zn, fn
        if len(newton) >= 2 and dec > 0.3 * newton[-2] and n_hess < 5:  # slow: curvature changed, take it again
            H = _hessian(f, z, _steps(H, h), fz)
            n_hess += 1
    # noise scales pinned at a bound are held there (the data do not determine them)
    at_bound = [j for j in range(m) if abs(abs(z[p + j]) - A_BOUND) < 1e-9]
    act = [i for i in range(p + m) if i - p not in at_bound]
    zact = z[act]

    def fa(y):
        return f(_full(z, act, y))

    f0 = fz
    # covariance Hessian at the optimum, steps about 0.3 std of each coordinate
    h1 = _steps(H, h)[act]
    H = _hessian(fa, zact, h1, f0)
    # noise directions the data do not determine (curvature not positive, or the optimum next
    # to a bound) are held at their optimum too, so θ's covariance comes from the rest
    held = undetermined_noise(H, z[act], p)
    if held:
        keep = [k for k in range(len(act)) if k not in held]
        at_bound = sorted(at_bound + [act[k] - p for k in held])
        act, h1, H = [act[k] for k in keep], h1[keep], H[np.ix_(keep, keep)]
        zact = z[act]
    pd = _is_pd(H)
    dec = np.inf
    for _ in range(4):  # Newton steps on the final Hessian until the decrement is small
        g = _gradient(fa, zact, 0.1 * h1)
        if not pd:
            break
        step = -np.linalg.solve(H, g)
        dec = float(np.sqrt(max(-(g @ step), 0.0)))
        newton.append(dec)
        if dec < 0.05:
            break
        lam, moved = 1.0, False
        for _ in range(6):
            yn = zact + lam * step
            yn = np.clip(yn, lo[act], hi[act])
            fn = fa(yn)
            if fn < f0:
                zact, f0, moved = yn, fn, True
                break
            lam *= 0.5
        if not moved:
            break
    z = _full(z, act, zact)
    opt_success = success or dec < 0.05
    settled = bool(opt_success and pd and dec < 0.1)
    th_hat, a_hat = unpack(z)
    nact = len(act)
    if pd:
        Cz = np.linalg.inv(0.5 * (H + H.T))
    else:
        Cz = np.full((nact, nact), np.nan)
    # considered parameters: mixed second derivatives, steps of 0.5 std of each
    cov_c = cov_prev[np.ix_(consider, consider)] if consider else np.zeros((0, 0))
    J = np.zeros((nact, len(consider)))
    if consider and pd:
        Hc = np.empty((nact, len(consider)))
        hc = 0.5 * np.sqrt(np.diag(cov_c))
        for j, ci in enumerate(consider):
            def fc(y, dcj):
                th, a = unpack(_full(z, act, y))
                th[ci] += dcj
                try:
                    return lik.nll(th, a)
                except ConvergenceError:
                    return np.inf
            for i in range(nact):
                e = np.zeros(nact)
                e[i] = h1[i]
                Hc[i, j] = (fc(zact + e, hc[j]) - fc(zact + e, -hc[j]) - fc(zact - e, hc[j])
                            + fc(zact - e, -hc[j])) / (4 * h1[i] * hc[j])
        J = -Cz @ Hc
    Cz_tot = Cz + J @ cov_c @ J.T
    ip = list(range(p))  # θ_f are the first p of act (noise may be dropped, never θ)
    profiles = {}
    if pd and at_bound:
        for j in at_bound:
            spread, prof = noise_profile(f, z, act, p + j, H, h1, f0, lo[p + j], hi[p + j])
            Cz_tot = Cz_tot + spread
            profiles[lik.noise_names[j]] = prof
    cov_free = (s[:, None] * Cz_tot[np.ix_(ip, ip)]) * s[None, :]
    cross = s[:, None] * (J[ip] @ cov_c) if consider else np.zeros((p, 0))
    a_std = np.zeros(m)
    for j in range(m):
        if p + j in act:
            k = act.index(p + j)
            a_std[j] = np.sqrt(Cz_tot[k, k]) if pd else np.nan
        else:
            a_std[j] = np.nan
    diag = {"optimizer": {"success": bool(opt_success), "iterations": len(newton) - 1},
            "newton_decrement": newton, "hessian_positive_definite": pd,
            "noise_at_bound": [lik.noise_names[j] for j in at_bound],
            "noise_held": [lik.noise_names[j] for j in at_bound if abs(abs(z[p + j]) - A_BOUND) >= 1e-9],
            "noise_profiles": profiles,
            "evaluations": lik.n_eval,
            "loglik_start": -float(f_start), "loglik": -float(f0)}
    return PEMResult(theta=th_hat[free], cov_free=0.5 * (cov_free + cov_free.T), cross=cross, log_scales=a_hat,
                     log_scales_std=a_std, loglik=-float(f0), settled=settled, diagnostics=diag)


#: Profile of an undetermined noise level: grid step in its log-scale, the likelihood-ratio drop
#: (χ²₁ 95 %: 3.84 / 2) that ends the interval the data allow, and the most grid points each way.
PROFILE_STEP = 0.5
PROFILE_DROP = 1.92
PROFILE_MAX_STEPS = 8


def noise_profile(f, z: np.ndarray, act: list[int], j: int, H: np.ndarray, h: np.ndarray, f0: float,
                  lo: float, hi: float) -> tuple[np.ndarray, dict]:
    """θ's spread over the values of an undetermined noise log-scale that the data allow.

    The noise coordinate ``z[j]`` (not in ``act``: held) is stepped by :data:`PROFILE_STEP` each way
    from its optimum, within ``[lo, hi]``, while the active coordinates ``act`` (θ_f first, then
    the determined noise scales) are re-optimised at every grid point (one Newton step on the
    optimum's Hessian ``H`` with a finite-difference gradient, from the previous grid point: a
    continuation). The walk stops where the profile log-likelihood has fallen by more than
    :data:`PROFILE_DROP` (the 95 % likelihood-ratio interval of one parameter). Over the grid
    points inside it, with weights ``w_g ∝ exp(ℓ_p(a_g) − ℓ_max)`` (the likelihood integrated over
    the log-scale, a flat prior on it within its bounds), the law of total variance adds
    ``Σ w_g (θ̂_g − θ̂)(θ̂_g − θ̂)ᵀ`` to cov(θ̂): the share of θ's uncertainty that comes from
    not knowing the noise level. (The conditional covariance is taken as the optimum's.)

    Returns the spread over the active coordinates (``len(act)`` square, in the units of ``z``) and a record:
    the interval of the log-scale the data allow (to the first grid point outside it, or the bound),
    the grid, its log-likelihood drops and weights.
    """
    Hs = 0.5 * (H + H.T)
    Hinv = np.linalg.inv(Hs)
    base = z[act].copy()
    pts = [(float(z[j]), 0.0, base.copy())]
    edge = [lo, hi]
    for direction in (1.0, -1.0):
        y = base.copy()
        a = float(z[j])
        for _ in range(PROFILE_MAX_STEPS):
            if (direction > 0 and a >= hi - 1e-9) or (direction < 0 and a <= lo + 1e-9):
                break
            a = float(np.clip(a + direction * PROFILE_STEP, lo, hi))
            zz = z.copy()
            zz[j] = a

            def fy(v, zz=zz):
                zz2 = zz.copy()
                zz2[act] = v
                return f(zz2)

            g = _gradient(fy, y, 0.1 * h)
            step = -Hinv @ g
            fy0, lam, fn = fy(y), 1.0, np.inf
            for _ in range(4):
                fn = fy(y + lam * step)
                if fn < fy0:
                    y = y + lam * step
                    break
                lam *= 0.5
            else:
                fn = fy0
            drop = f0 - fn
            if not np.isfinite(fn) or drop < -PROFILE_DROP:
                edge[direction > 0] = a
                break
            pts.append((a, float(drop), y.copy()))
        else:
            edge[direction > 0] = a
    a_g = np.array([q[0] for q in pts])
    dl = np.array([q[1] for q in pts])
    w = np.exp(dl - dl.max())
    w /= w.sum()
    dth = np.array([q[2] for q in pts]) - base
    spread = (dth * w[:, None]).T @ dth
    order = np.argsort(a_g)
    rec = {"log_scale_interval": [float(edge[0]), float(edge[1])], "grid_inside": [float(a_g.min()), float(a_g.max())],
           "grid": a_g[order].tolist(), "loglik_drop": dl[order].tolist(), "weights": w[order].tolist()}
    return 0.5 * (spread + spread.T), rec


def noise_report(lik: StageLikelihood, pem: PEMResult, vessel) -> dict:
    """Estimated noise levels with std and units (bis and SI; yaw components are × ``yaw_arm``)."""
    b = vessel.bis
    nz = lik.noise(pem.log_scales)
    F2 = (b.m * b.g) ** 2
    conv = {"q_h": (F2 * b.time, "N^2 s (surge/sway force; yaw moment x (yaw_arm L)^2)"),
            "q_b": (F2 / b.time, "N^2/s (surge/sway force; yaw moment x (yaw_arm L)^2)"),
            "sigma_pos": (b.L, "m"), "sigma_psi": (float(np.rad2deg(1.0)), "deg")}
    out = {}
    for j, k in enumerate(lik.noise_names):
        sc, sd = float(np.exp(pem.log_scales[j])), float(pem.log_scales_std[j])
        power = 2 if k.startswith("q") else 1  # intensities scale as scale², std as scale
        fac, unit = conv[k]
        val = float(nz[k]) * fac
        out[k] = {"value": val, "std": val * power * sd, "unit": unit, "value_bis": float(nz[k]),
                  "scale_vs_nominal": sc, "log_scale_std": sd,
                  "at_bound": k in pem.diagnostics["noise_at_bound"],
                  "determined": k not in pem.diagnostics["noise_at_bound"]}
        prof = pem.diagnostics.get("noise_profiles", {}).get(k)
        if prof:
            lo_, hi_ = prof["log_scale_interval"]
            out[k]["allowed_scale_vs_nominal"] = [float(np.exp(lo_)), float(np.exp(hi_))]
            out[k]["profile"] = prof
    return out


def _is_pd(H: np.ndarray) -> bool:
    try:
        np.linalg.cholesky(0.5 * (H + H.T))
        return True
    except np.linalg.LinAlgError:
        return False


def undetermined_noise(H: np.ndarray, y: np.ndarray, p: int, margin: float = 0.25) -> list[int]:
    """Noise coordinates (index ≥ ``p`` of ``H``) to hold fixed when forming the observed information.

    First every noise log-scale whose own curvature ``H[k, k]`` is not positive or whose value
    lies within ``margin`` of the bound ±``A_BOUND`` (the likelihood is flat there: the level
    is not determined, and a finite-difference Hessian across it is not a curvature). Then,
    while the rest of ``H`` is not positive definite, the noise coordinate with the largest
    weight in the eigenvector of the most negative eigenvalue. θ coordinates (index < ``p``)
    are never held: if ``H`` restricted to θ is indefinite, the scheme stays unsettled.
    """
    n = H.shape[0]
    Hs = 0.5 * (H + H.T)
    held = [k for k in range(p, n) if Hs[k, k] <= 0 or abs(y[k]) > A_BOUND - margin]
    while True:
        keep = [k for k in range(n) if k not in held]
        if _is_pd(Hs[np.ix_(keep, keep)]):
            return held
        noise = [i for i, k in enumerate(keep) if k >= p]
        if not noise:
            return held
        w, V = np.linalg.eigh(Hs[np.ix_(keep, keep)])
        i = max(noise, key=lambda i: abs(V[i, 0]))
        held.append(keep[i])


def _full(z: np.ndarray, act: list[int], y: np.ndarray) -> np.ndarray:
    out = z.copy()
    out[act] = y
    return out


__all__ = ["measurement_log_scales", "NOISE_NAMES", "PEMResult", "StageLikelihood", "pem_stage", "thrust_force", "noise_report", "undetermined_noise"]
