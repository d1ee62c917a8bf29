"""State-augmented discrete extended Kalman filter and its parallel configuration.

Fossen, Sagatun & Sørensen (1996) §3, Table 1 and eqs. 15–25:

* the plant ``x(k+1) = f(x(k), u(k), θ(k)) + w1(k)`` (eq. 15) with parameters as a
  random walk ``θ(k+1) = θ(k) + η(k)`` (eq. 16) is written as one augmented state
  ``ξ = [x; θ]`` with ``𝓕(ξ, u) = [f(x, u, θ); θ]`` (eqs. 17–18) and measurement
  ``z = 𝓗(ξ) + v`` (eq. 19); :func:`augmented_ekf` runs Table 1 on it;
* the parallel configuration (eqs. 20–25) stacks N trials that share one θ,
  ``ξ = [x1; …; xN; θ]``; :func:`parallel_augmented_ekf` builds that augmented
  model from a per-trial model and runs the same filter.

The filters are pure functions (DESIGN.md practice 2): model, θ, measurements and
inputs in, a named result out. Numerical choices (DESIGN.md practice 6): the
covariance update is the Joseph form (Table 1 prints it), every covariance is
symmetrised and checked for positive definiteness with a Cholesky factorisation, and
the innovation covariance is never inverted explicitly.

Time convention: ``x0, P0`` is the prior at step 0; the filter first updates with
``z[0]``, then predicts with ``u[0]`` to step 1, and so on. Missing measurements are
NaN (the corresponding rows are left out of that update).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import numpy as np

from shipid.errors import ConvergenceError
from shipid.numerics.linalg import (NotPositiveDefiniteError, check_positive_definite, joseph_update,
                                    kalman_gain, symmetrize)
from shipid.numerics.integrate import rk4_step_jacobians

# f(k, x, u, theta) -> x_next ; h(k, x, theta) -> z
DiscreteDynamics = Callable[[int, np.ndarray, np.ndarray, np.ndarray], np.ndarray]
Measurement = Callable[[int, np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class AugmentedModel:
    """A discrete-time model with unknown parameters, eqs. 15–16 and 19.

    Attributes
    ----------
    f : callable
        ``f(k, x, u, theta) -> x(k+1)`` (without noise), ``x`` shape ``(nx,)``.
    h : callable
        ``h(k, x, theta) -> z`` shape ``(nz,)``.
    nx, ntheta : int
        Sizes of ``x`` and ``θ`` (``ntheta`` may be 0: a plain EKF).
    f_jac : callable, optional
        ``f_jac(k, x, u, theta) -> (∂f/∂x (nx, nx), ∂f/∂θ (nx, ntheta))``; central finite
        differences (:func:`numerical_jacobian`) when omitted.
    h_jac : callable, optional
        ``h_jac(k, x, theta) -> (∂h/∂x, ∂h/∂θ)``; finite differences when omitted.
    residual : callable, optional
        ``residual(z, z_pred) -> innovation``; default ``z − z_pred``. Use it to wrap
        angles (heading innovations to (−π, π]).
    fd_step : float
        Relative step of the finite-difference Jacobians.
    """

    f: DiscreteDynamics
    h: Measurement
    nx: int
    ntheta: int
    f_jac: Callable[..., tuple[np.ndarray, np.ndarray]] | None = None
    h_jac: Callable[..., tuple[np.ndarray, np.ndarray]] | None = None
    residual: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None
    fd_step: float = 1e-6


class _ThetaHistory:
    """Shared views of a parameter history ``theta`` (n, ntheta) with covariances ``theta_cov``."""

    @property
    def theta_std(self) -> np.ndarray:
        """Standard deviations of θ̂ at every step, ``(n, ntheta)``."""
        return np.sqrt(np.einsum("kii->ki", self.theta_cov))

    @property
    def theta_final(self) -> np.ndarray:
        """The last parameter estimate."""
        return self.theta[-1]


@dataclass(frozen=True)
class AugmentedEKFResult(_ThetaHistory):
    """Output of :func:`augmented_ekf` (filtered, i.e. after the update at each step).

    Attributes
    ----------
    x : ndarray (n, nx)
        State estimates x̂(k).
    theta : ndarray (n, ntheta)
        Parameter estimates θ̂(k) (the parameter history, Fig. 8).
    P_diag : ndarray (n, nx + ntheta)
        Diagonals of P̂(k).
    theta_cov : ndarray (n, ntheta, ntheta)
        Parameter block of P̂(k).
    P_final : ndarray (nx + ntheta, nx + ntheta)
        P̂ at the last step.
    innovations : ndarray (n, nz)
        ``z(k) − 𝓗(ξ̄(k))``; NaN where the measurement was missing.
    S : ndarray (n, nz, nz)
        Innovation covariances (NaN rows/cols where missing).
    nis : ndarray (n,)
        Normalised innovation squared ``νᵀ S⁻¹ ν`` (χ² with the number of measured channels).
    nis_dof : ndarray (n,)
        Number of channels used at each step.
    loglik : float
        Gaussian log-likelihood of the innovations, ``Σ −½ (νᵀS⁻¹ν + log det 2πS)``.
    P : ndarray (n, nξ, nξ) or None
        All filtered covariances when ``store_covariances=True``.
    """

    x: np.ndarray
    theta: np.ndarray
    P_diag: np.ndarray
    theta_cov: np.ndarray
    P_final: np.ndarray
    innovations: np.ndarray
    S: np.ndarray
    nis: np.ndarray
    nis_dof: np.ndarray
    loglik: float
    P: np.ndarray | None = None



def numerical_jacobian(fun: Callable[[np.ndarray], np.ndarray], x: np.ndarray, rel_step: float = 1e-6
                       ) -> np.ndarray:
    """Central finite-difference Jacobian of ``fun`` at ``x``; step ``rel_step · max(|x_j|, 1e-3)``."""
    x = np.asarray(x, dtype=float)
    cols = []
    for j in range(x.size):
        hj = rel_step * max(abs(x[j]), 1e-3)
        e = np.zeros_like(x)
        e[j] = hj
        cols.append((np.asarray(fun(x + e)) - np.asarray(fun(x - e))) / (2.0 * hj))
    if not cols:
        return np.zeros((np.asarray(fun(x)).size, 0))
    return np.column_stack(cols)


def rk4_map(f: Callable[[float, np.ndarray, np.ndarray, np.ndarray], np.ndarray],
            jac: Callable[[float, np.ndarray, np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]],
            t: float, x: np.ndarray, u: np.ndarray, theta: np.ndarray, dt: float
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One RK4 step of ``ẋ = f(t, x, u, θ)`` and its exact Jacobians (discretisation of eq. 15).

    The discrete map ``f(k, x, u, θ)`` of eq. 15 and its ``Φ`` (Table 1) from the continuous
    model ``f(t, x, u, θ)`` with Jacobians ``jac(t, x, u, θ) -> (∂f/∂x, ∂f/∂θ)``, by the package's
    one RK4 (:func:`shipid.numerics.integrate.rk4_step_jacobians`): the Jacobians are propagated
    through the four stages by the chain rule, so ``Φ`` is the derivative of the very map the
    filter propagates with.

    Returns
    -------
    x_next, dx_next/dx (nx, nx), dx_next/dθ (nx, p)
    """
    return rk4_step_jacobians(f, jac, t, x, u, theta, dt)


def _as_callable(a: Any) -> Callable[[int], np.ndarray]:
    if callable(a):
        return a
    arr = np.asarray(a, dtype=float)
    return lambda k: arr


def augmented_ekf(model: AugmentedModel, x0: np.ndarray, theta0: np.ndarray, P0: np.ndarray,
                  Q: np.ndarray | Callable[[int], np.ndarray], R: np.ndarray | Callable[[int], np.ndarray],
                  measurements: np.ndarray, inputs: np.ndarray | None = None, *,
                  store_covariances: bool = False, consider: Sequence[int] | None = None) -> AugmentedEKFResult:
    """State-augmented discrete EKF of Table 1 (eqs. 15–19).

    Parameters
    ----------
    model : AugmentedModel
    x0 : ndarray (nx,)
        Prior mean of the state at step 0.
    theta0 : ndarray (ntheta,)
        Prior mean of the parameters.
    P0 : ndarray (nx + ntheta, nx + ntheta)
        Prior covariance of ξ = [x; θ].
    Q : ndarray (nξ, nξ) or callable ``Q(k)``
        Covariance of ``w(k) = [w1; η]`` (Γ = I), driving the step k → k+1.
    R : ndarray (nz, nz) or callable ``R(k)``
        Measurement noise covariance.
    measurements : ndarray (n, nz)
        ``z(k)``; NaN entries are treated as missing.
    inputs : ndarray (n, nu) or None
        ``u(k)``, applied over the step k → k+1.
    store_covariances : bool
        Keep every filtered covariance in the result (memory n · nξ²).
    consider : sequence of int, optional
        Indices of ξ that are *considered* but not estimated (Schmidt–Kalman consider
        filter): their rows of the gain are zero, so their estimates stay where they
        are, while their uncertainty still enters the covariances of everything else.
        The Joseph form is exact for such a suboptimal gain. This is how a parameter
        "frozen" from an earlier identification keeps its uncertainty.

    Returns
    -------
    AugmentedEKFResult

    Raises
    ------
    ConvergenceError
        When a covariance stops being positive definite or the state becomes non-finite
        (the filter has diverged; the step is named).
    """
    Z = np.atleast_2d(np.asarray(measurements, dtype=float))
    if Z.shape[0] == 1 and np.ndim(measurements) == 1:
        Z = Z.T
    n, nz = Z.shape
    U = np.zeros((n, 0)) if inputs is None else np.asarray(inputs, dtype=float).reshape(n, -1)
    nx, p = model.nx, model.ntheta
    nxi = nx + p
    xi = np.concatenate([np.asarray(x0, dtype=float).ravel(), np.asarray(theta0, dtype=float).ravel()])
    if xi.size != nxi:
        raise ValueError(f"x0 and theta0 have {xi.size} entries, model expects {nxi}")
    P = symmetrize(np.asarray(P0, dtype=float))
    check_positive_definite(P, "P0")
    Qf, Rf = _as_callable(Q), _as_callable(R)
    resid = model.residual or (lambda z, zp: z - zp)
    cons = None if consider is None or len(consider) == 0 else np.asarray(consider, dtype=int)

    def fjac(k, x, u, th):
        if model.f_jac is not None:
            return model.f_jac(k, x, u, th)
        J = numerical_jacobian(lambda s: model.f(k, s[:nx], u, s[nx:]), np.concatenate([x, th]), model.fd_step)
        return J[:, :nx], J[:, nx:]

    def hjac(k, x, th):
        if model.h_jac is not None:
            return model.h_jac(k, x, th)
        J = numerical_jacobian(lambda s: model.h(k, s[:nx], s[nx:]), np.concatenate([x, th]), model.fd_step)
        return J[:, :nx], J[:, nx:]

    Xs = np.empty((n, nx))
    Ths = np.empty((n, p))
    Pd = np.empty((n, nxi))
    Pth = np.empty((n, p, p))
    Pall = np.empty((n, nxi, nxi)) if store_covariances else None
    innov = np.full((n, nz), np.nan)
    Ss = np.full((n, nz, nz), np.nan)
    nis = np.full(n, np.nan)
    dof = np.zeros(n, dtype=int)
    loglik = 0.0
    Phi = np.zeros((nxi, nxi))
    Phi[nx:, nx:] = np.eye(p)
    Hfull = np.zeros((nz, nxi))
    for k in range(n):
        # -- measurement update (Table 1: gain, state and Joseph covariance update) ------------
        z = Z[k]
        ok = ~np.isnan(z)
        if ok.any():
            x, th = xi[:nx], xi[nx:]
            zp = np.asarray(model.h(k, x, th), dtype=float)
            Hx, Ht = hjac(k, x, th)
            Hfull[:, :nx] = Hx
            Hfull[:, nx:] = Ht
            Rk = np.asarray(Rf(k), dtype=float)
            if ok.all():
                H, Rm, nu = Hfull, Rk, resid(z, zp)
            else:
                H, Rm, nu = Hfull[ok], Rk[np.ix_(ok, ok)], resid(z, zp)[ok]
            try:
                Kg, S = kalman_gain(P, H, Rm)
                if cons is not None:
                    Kg[cons] = 0.0
                xi = xi + Kg @ nu
                P = joseph_update(P, Kg, H, Rm)
                check_positive_definite(P, f"P at step {k}")
                c = np.linalg.cholesky(S)
                w = np.linalg.solve(c, nu)
            except (NotPositiveDefiniteError, np.linalg.LinAlgError) as err:
                raise ConvergenceError(f"EKF diverged at step {k}: {err}") from None
            nis[k] = float(w @ w)
            dof[k] = int(ok.sum())
            loglik += -0.5 * (nis[k] + 2.0 * np.sum(np.log(np.diag(c))) + dof[k] * np.log(2 * np.pi))
            full_nu = np.full(nz, np.nan)
            full_nu[ok] = nu
            innov[k] = full_nu
            Ss[k][np.ix_(ok, ok)] = S
        if not np.all(np.isfinite(xi)):
            raise ConvergenceError(f"EKF diverged at step {k}: non-finite state")
        Xs[k] = xi[:nx]
        Ths[k] = xi[nx:]
        Pd[k] = np.diag(P)
        Pth[k] = P[nx:, nx:]
        if Pall is not None:
            Pall[k] = P
        if k == n - 1:
            break
        # -- time update (Table 1: state propagation and Φ P Φᵀ + Γ Q Γᵀ) ----------------------
        x, th = xi[:nx], xi[nx:]
        xn = np.asarray(model.f(k, x, U[k], th), dtype=float)
        Fx, Ft = fjac(k, x, U[k], th)
        Phi[:nx, :nx] = Fx
        Phi[:nx, nx:] = Ft
        xi = np.concatenate([xn, th])
        P = symmetrize(Phi @ P @ Phi.T + np.asarray(Qf(k), dtype=float))
    return AugmentedEKFResult(x=Xs, theta=Ths, P_diag=Pd, theta_cov=Pth, P_final=P, innovations=innov,
                              S=Ss, nis=nis, nis_dof=dof, loglik=float(loglik), P=Pall)


# ---------------------------------------------------------------------------------------------
# Parallel configuration, eqs. 20–25
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ParallelEKFResult(_ThetaHistory):
    """Output of :func:`parallel_augmented_ekf`.

    Attributes
    ----------
    x : list of ndarray
        Per trial i, the filtered states ``(n_i, nx)``.
    theta, theta_cov : ndarray
        Shared parameter history ``(n_max, p)`` and its covariance ``(n_max, p, p)``.
    innovations, nis : list of ndarray
        Per trial, innovations ``(n_i, nz)`` and NIS ``(n_i,)``.
    x_var : list of ndarray
        Per trial, the variances of the states ``(n_i, nx)``.
    loglik : float
    combined : AugmentedEKFResult
        The result of the stacked filter (all of ξ = [x1 … xN θ]).
    """

    x: list[np.ndarray]
    x_var: list[np.ndarray]
    theta: np.ndarray
    theta_cov: np.ndarray
    innovations: list[np.ndarray]
    nis: list[np.ndarray]
    loglik: float
    combined: AugmentedEKFResult = field(repr=False)



def _blocks(a: Any, N: int) -> list[Any]:
    if isinstance(a, (list, tuple)):
        if len(a) != N:
            raise ValueError(f"expected {N} per-trial entries, got {len(a)}")
        return [b if callable(b) else np.asarray(b, dtype=float) for b in a]
    return [a if callable(a) else np.asarray(a, dtype=float)] * N


def parallel_augmented_ekf(model: AugmentedModel, x0: Sequence[np.ndarray], theta0: np.ndarray,
                           P0x: Sequence[np.ndarray] | np.ndarray, P0theta: np.ndarray,
                           Qx: Sequence[np.ndarray] | np.ndarray, Qtheta: np.ndarray,
                           R: Sequence[np.ndarray] | np.ndarray, measurements: Sequence[np.ndarray],
                           inputs: Sequence[np.ndarray] | None = None, *,
                           models: Sequence[AugmentedModel] | None = None,
                           consider_theta: Sequence[int] | None = None) -> ParallelEKFResult:
    """Parallel augmented EKF over N ≥ 1 trials sharing one parameter vector (eqs. 20–25).

    The trials are stacked as ``ξ = [x1; …; xN; θ]`` with ``𝓕 = [f(x1,u1,θ); …; f(xN,uN,θ); θ]``
    (eq. 24) and ``𝓗 = [h(x1,θ); …; h(xN,θ)]`` (eq. 25), and Table 1 runs on the stack. The
    trials are aligned by step index; a trial shorter than the longest is frozen after its
    last sample (identity transition, no process noise, no measurements), so trials of
    different lengths can be processed together.

    Parameters
    ----------
    model : AugmentedModel
        The per-trial model (same f for every trial; use ``models`` for per-trial h/f).
    x0 : sequence of ndarray (nx,)
        Per-trial prior state means.
    theta0 : ndarray (p,)
    P0x : ndarray (nx, nx) or sequence of them
        Per-trial prior state covariances (states of different trials start uncorrelated).
    P0theta : ndarray (p, p)
    Qx : ndarray (nx, nx), callable ``Qx(k)``, or a sequence of them
        Per-trial process-noise covariance of the step k → k+1.
    Qtheta : ndarray (p, p)
        Parameter random-walk covariance per step (eq. 16/43).
    R : ndarray (nz, nz) or sequence
    measurements : sequence of ndarray (n_i, nz)
    inputs : sequence of ndarray (n_i, nu) or None
    models : sequence of AugmentedModel, optional
        Per-trial models (e.g. different sampling intervals); default ``[model] * N``.
    consider_theta : sequence of int, optional
        Indices of θ that are considered, not estimated (see ``consider`` of
        :func:`augmented_ekf`).

    Returns
    -------
    ParallelEKFResult
    """
    Zs = [np.asarray(z, dtype=float) for z in measurements]
    N = len(Zs)
    if N < 1:
        raise ValueError("need at least one trial")
    mods = list(models) if models is not None else [model] * N
    nx, p = mods[0].nx, mods[0].ntheta
    nz = Zs[0].shape[1]
    lens = [z.shape[0] for z in Zs]
    n = max(lens)
    Us = [np.zeros((li, 0)) for li in lens] if inputs is None else [np.asarray(u, dtype=float) for u in inputs]
    nu = Us[0].shape[1]
    P0xs, Qxs, Rs = _blocks(P0x, N), _blocks(Qx, N), _blocks(R, N)
    # Pad: the measurements of a finished trial are missing; its inputs are never used.
    Zpad = np.full((n, N * nz), np.nan)
    Upad = np.zeros((n, N * nu))
    for i in range(N):
        Zpad[:lens[i], i * nz:(i + 1) * nz] = Zs[i]
        Upad[:lens[i], i * nu:(i + 1) * nu] = Us[i]
    sx = [slice(i * nx, (i + 1) * nx) for i in range(N)]
    active = [lambda k, li=li: k < li - 1 for li in lens]  # trial i propagates over k → k+1

    def f(k, X, U, th):
        out = np.empty(N * nx)
        for i in range(N):
            xi = X[sx[i]]
            out[sx[i]] = mods[i].f(k, xi, U[i * nu:(i + 1) * nu], th) if active[i](k) else xi
        return out

    def fjac(k, X, U, th):
        Fx = np.zeros((N * nx, N * nx))
        Ft = np.zeros((N * nx, p))
        for i in range(N):
            xi = X[sx[i]]
            if not active[i](k):
                Fx[sx[i], sx[i]] = np.eye(nx)
                continue
            ui = U[i * nu:(i + 1) * nu]
            mi = mods[i]
            if mi.f_jac is not None:
                a, b = mi.f_jac(k, xi, ui, th)
            else:
                J = numerical_jacobian(lambda s: mi.f(k, s[:nx], ui, s[nx:]), np.concatenate([xi, th]), mi.fd_step)
                a, b = J[:, :nx], J[:, nx:]
            Fx[sx[i], sx[i]] = a
            Ft[sx[i]] = b
        return Fx, Ft

    def h(k, X, th):
        return np.concatenate([mods[i].h(min(k, lens[i] - 1), X[sx[i]], th) for i in range(N)])

    def hjac(k, X, th):
        Hx = np.zeros((N * nz, N * nx))
        Ht = np.zeros((N * nz, p))
        for i in range(N):
            ki = min(k, lens[i] - 1)
            mi = mods[i]
            xi = X[sx[i]]
            if mi.h_jac is not None:
                a, b = mi.h_jac(ki, xi, th)
            else:
                J = numerical_jacobian(lambda s: mi.h(ki, s[:nx], s[nx:]), np.concatenate([xi, th]), mi.fd_step)
                a, b = J[:, :nx], J[:, nx:]
            Hx[i * nz:(i + 1) * nz, sx[i]] = a
            Ht[i * nz:(i + 1) * nz] = b
        return Hx, Ht

    def residual(z, zp):
        return np.concatenate([(mods[i].residual or (lambda a, b: a - b))(z[i * nz:(i + 1) * nz],
                                                                          zp[i * nz:(i + 1) * nz])
                               for i in range(N)])

    Qth = np.asarray(Qtheta, dtype=float)

    def Q(k):
        out = np.zeros((N * nx + p, N * nx + p))
        for i in range(N):
            if active[i](k):
                out[sx[i], sx[i]] = Qxs[i](k) if callable(Qxs[i]) else Qxs[i]
        out[N * nx:, N * nx:] = Qth
        return out

    Rbig = np.zeros((N * nz, N * nz))
    for i in range(N):
        Rbig[i * nz:(i + 1) * nz, i * nz:(i + 1) * nz] = Rs[i]
    P0 = np.zeros((N * nx + p, N * nx + p))
    for i in range(N):
        P0[sx[i], sx[i]] = P0xs[i]
    P0[N * nx:, N * nx:] = np.asarray(P0theta, dtype=float)
    big = AugmentedModel(f=f, h=h, nx=N * nx, ntheta=p, f_jac=fjac, h_jac=hjac, residual=residual)
    cons = None if not consider_theta else [N * nx + int(i) for i in consider_theta]
    res = augmented_ekf(big, np.concatenate([np.asarray(x, dtype=float) for x in x0]), theta0, P0, Q, Rbig,
                        Zpad, Upad, consider=cons)
    xs = [res.x[:lens[i], sx[i]] for i in range(N)]
    xv = [res.P_diag[:lens[i], sx[i]] for i in range(N)]
    inn = [res.innovations[:lens[i], i * nz:(i + 1) * nz] for i in range(N)]
    # NIS per trial from its own block of S
    nis = []
    for i in range(N):
        blk = slice(i * nz, (i + 1) * nz)
        v = inn[i]
        Si = res.S[:lens[i], blk, blk]
        out = np.full(lens[i], np.nan)
        for k in range(lens[i]):
            ok = ~np.isnan(v[k])
            if ok.any():
                out[k] = float(v[k][ok] @ np.linalg.solve(Si[k][np.ix_(ok, ok)], v[k][ok]))
        nis.append(out)
    return ParallelEKFResult(x=xs, x_var=xv, theta=res.theta, theta_cov=res.theta_cov, innovations=inn,
                             nis=nis, loglik=res.loglik, combined=res)


__all__ = ["AugmentedModel", "AugmentedEKFResult", "ParallelEKFResult", "augmented_ekf",
           "parallel_augmented_ekf", "numerical_jacobian", "rk4_map"]
