"""Continuous–discrete extended Kalman filter (Yoon & Rhee 2003, §3.1, eq. 9, Fig. 3).

Continuous state equation ``ẋ = f(t, x, u, θ) + w(t)`` (the package's one dynamics signature),
``E[w wᵀ] = Q δ(t−s)``, with the input ``u`` held over each sample interval and parameters ``θ``
passed through; discrete measurements ``z_k = h(t_k, x_k) + v_k``, ``E[v vᵀ] = R``.

Between samples the estimate follows ``f`` (the one RK4,
:func:`shipid.numerics.integrate.rk4_propagate`), and the covariance
follows the matrix Riccati equation ``Ṗ = F P + P Fᵀ + Q`` with the Jacobian ``F``
frozen at the start of the interval, solved exactly by Van Loan's method::

    expm([[−F, Q], [0, Fᵀ]] h) = [[·, Φ⁻¹Q_d], [0, Φᵀ]]  →  Φ, Q_d,  P⁻ = Φ P Φᵀ + Q_d

so that the transition matrices Φ_k the smoothers need come with the filter. The
update is the EKF update of eq. 9 in Joseph form (numerically stable, keeps P
symmetric positive definite; DESIGN.md practice 6).

The function is pure: it takes the model and data and returns a
:class:`FilterResult` holding everything the fixed-interval smoothers
(:mod:`shipid.estimate.smoothers`) need.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Callable

import numpy as np

from shipid.numerics.linalg import check_positive_definite, symmetrize
from shipid.numerics.integrate import Dynamics, rk4_propagate

LOG2PI = float(np.log(2.0 * np.pi))


@dataclass(frozen=True)
class FilterResult:
    """Output of :func:`cd_ekf`.

    Attributes
    ----------
    t : ndarray (N,)
    x_pred, P_pred : ndarray (N, n), (N, n, n)
        One-step predictions x̂(t_k|t_{k−1}), P(t_k|t_{k−1}) (at k = 0 the prior).
    x_filt, P_filt : ndarray (N, n), (N, n, n)
        Filtered x̂(t_k|t_k), P(t_k|t_k).
    Phi : ndarray (N−1, n, n)
        Transition matrix of the linearised dynamics from t_k to t_{k+1}.
    Qd : ndarray (N−1, n, n)
        Discrete process-noise covariance over the same interval.
    innov, S : ndarray (N, m), (N, m, m)
        Innovations Δz(t_k|t_{k−1}) and their covariances.
    K : ndarray (N, n, m)
        Kalman gains.
    H : ndarray (N, m, n)
        Measurement Jacobians at the predictions.
    loglik : float
        Gaussian log-likelihood of the innovations.
    nis : ndarray (N,)
        Normalised innovation squared νᵀ S⁻¹ ν (consistency check: mean ≈ m).
    HtSinv_nu, HtSinv_H : ndarray (N, n), (N, n, n)
        Hᵀ S⁻¹ ν and Hᵀ S⁻¹ H over the measurements present (for the MBF smoother).
    """

    t: np.ndarray
    x_pred: np.ndarray
    P_pred: np.ndarray
    x_filt: np.ndarray
    P_filt: np.ndarray
    Phi: np.ndarray
    Qd: np.ndarray
    innov: np.ndarray
    S: np.ndarray
    K: np.ndarray
    H: np.ndarray
    loglik: float
    nis: np.ndarray
    HtSinv_nu: np.ndarray
    HtSinv_H: np.ndarray

    @classmethod
    def allocate(cls, t: np.ndarray, N: int, n: int, m: int) -> "FilterResult":
        """Output arrays for ``N`` samples, ``n`` states and ``m`` measurements, for a filter
        to fill in place (innovations and NIS start as NaN = no measurement; ``loglik`` is NaN until
        set with :func:`dataclasses.replace`). Shared by :func:`cd_ekf` and the compiled
        :func:`shipid.methods.ebm.compiled.ebm_cd_ekf`, so both return the same fields."""
        nd = max(N - 1, 0)
        return cls(t=t, x_pred=np.empty((N, n)), P_pred=np.empty((N, n, n)), x_filt=np.empty((N, n)),
                   P_filt=np.empty((N, n, n)), Phi=np.empty((nd, n, n)), Qd=np.empty((nd, n, n)),
                   innov=np.full((N, m), np.nan), S=np.zeros((N, m, m)), K=np.zeros((N, n, m)),
                   H=np.zeros((N, m, n)), loglik=float("nan"), nis=np.full(N, np.nan),
                   HtSinv_nu=np.zeros((N, n)), HtSinv_H=np.zeros((N, n, n)))

    def buffers(self) -> tuple:
        """The arrays a filter fills: ``x_pred, P_pred, x_filt, P_filt, Phi, Qd, innov, S, K, H, nis,
        HtSinv_nu, HtSinv_H``."""
        return (self.x_pred, self.P_pred, self.x_filt, self.P_filt, self.Phi, self.Qd, self.innov, self.S,
                self.K, self.H, self.nis, self.HtSinv_nu, self.HtSinv_H)


def van_loan(F: np.ndarray, Q: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Transition matrix Φ = e^{F h} and Q_d = ∫₀ʰ e^{F s} Q e^{Fᵀ s} ds (Van Loan 1978)."""
    n = F.shape[0]
    # Q_d is linear in Q: scale Q to unit size so that the block matrix has a small
    # norm (expm's scaling-and-squaring would otherwise square ~40 times: slow, and
    # less accurate), and scale back.
    qs = float(np.max(np.abs(Q))) or 1.0
    A = np.zeros((2 * n, 2 * n))
    A[:n, :n] = -F * h
    A[:n, n:] = Q * (h / qs)
    A[n:, n:] = F.T * h
    from scipy.linalg import expm  # scipy.linalg only where it is called (start-up of the commands that load this)

    E = expm(A)
    Phi = E[n:, n:].T
    Qd = (Phi @ E[:n, n:]) * qs
    return Phi, symmetrize(Qd)


def taylor_discretise(F: np.ndarray, Q: np.ndarray, h: float, *, tol: float = 1e-15,
                      max_terms: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """Φ = e^{F h} and Q_d by their Taylor series (same result as :func:`van_loan`).

    ``Φ = Σ (F h)^k / k!`` and ``Q_d = Σ C_k h^{k+1}/(k+1)!`` with ``C_0 = Q``,
    ``C_k = F C_{k−1} + C_{k−1} Fᵀ`` (the k-th derivative of ``e^{Fs} Q e^{Fᵀs}`` at 0).
    For the ship models the linearised dynamics are nearly nilpotent over one
    sample (kinematic chains, slow velocity modes), so a handful of terms reach
    machine precision; this is ~20× cheaper than a 2n × 2n ``expm``. Falls back to
    :func:`van_loan` when the series has not converged after ``max_terms``.
    """
    n = F.shape[0]
    Fh = F * h
    FhT = Fh.T
    Phi = np.eye(n) + Fh
    term = Fh
    C = (Fh @ Q + Q @ FhT) * (0.5 * h)
    Qd = Q * h + C
    qscale = float(np.abs(Qd).max()) or 1.0
    for k in range(2, max_terms):
        term = (term @ Fh) * (1.0 / k)
        C = (Fh @ C + C @ FhT) * (1.0 / (k + 1))
        Phi += term
        Qd += C
        # convergence: both new terms negligible (Φ has unit diagonal)
        if np.abs(term).max() <= tol and np.abs(C).max() <= tol * qscale:
            return Phi, 0.5 * (Qd + Qd.T)
    return van_loan(F, Q, h)


def cd_ekf(f: Dynamics, F: Callable[[float, np.ndarray, np.ndarray, Any], np.ndarray],
           h: Callable[[float, np.ndarray], np.ndarray], H: Callable[[float, np.ndarray], np.ndarray],
           Q: np.ndarray, R: np.ndarray, t: np.ndarray, z: np.ndarray, x0: np.ndarray,
           P0: np.ndarray, *, u: np.ndarray | None = None, theta: Any = None, substeps: int = 1,
           check_pd: bool = True) -> FilterResult:
    """Run the continuous–discrete EKF over measurements ``z`` at times ``t``.

    Parameters
    ----------
    f, F : callable
        ``f(t, x, u, θ)`` state derivative and its Jacobian ``F(t, x, u, θ) = ∂f/∂x``.
    h, H : callable
        ``h(t, x)`` measurement function and its Jacobian.
    Q : ndarray (n, n) or (N−1, n, n)
        Process-noise spectral density, constant or one per sample interval
        (``Q[k]`` acts on ``[t_k, t_{k+1})``; e.g. larger while a known input moves).
    R : ndarray (m, m)
        Measurement-noise covariance.
    t : ndarray (N,)
    z : ndarray (N, m)
        Measurements; a NaN entry is a missing measurement (skipped in the update).
    x0, P0 : prior at ``t[0]`` (before the first measurement).
    u : ndarray (N, nu), optional
        Inputs on the sample grid; ``u[k]`` is held over ``[t_k, t_{k+1})`` (zero-order hold).
        None: ``f`` and ``F`` get an empty input.
    theta : object, optional
        Parameters passed through to ``f`` and ``F``.
    substeps : int
        RK4 steps per sample interval for the state.
    check_pd : bool
        Check that P stays positive definite (raises ``NotPositiveDefiniteError`` naming the
        sample; checked every 50th sample and at the last, for cost — the compiled EBM path
        :func:`shipid.methods.ebm.compiled.ebm_cd_ekf` checks every sample). An innovation
        covariance that is not positive definite raises it too.

    Returns
    -------
    FilterResult
    """
    from scipy.linalg import cho_solve  # scipy.linalg only where it is called

    t = np.asarray(t, dtype=float)
    z = np.asarray(z, dtype=float)
    N, m = z.shape
    n = x0.size
    fr = FilterResult.allocate(t, N, n, m)
    x_pred, P_pred, x_filt, P_filt, Phi, Qd, innov, S_all, K_all, H_all, nis, HSn, HSH = fr.buffers()
    loglik = 0.0
    x = np.array(x0, dtype=float)
    P = symmetrize(np.array(P0, dtype=float))
    I = np.eye(n)
    Q = np.asarray(Q, dtype=float)
    Q_per_step = Q.ndim == 3
    U = np.zeros((N, 0)) if u is None else np.asarray(u, dtype=float).reshape(N, -1)
    for k in range(N):
        if k > 0:
            hk = t[k] - t[k - 1]
            uk = U[k - 1]
            Fk = F(t[k - 1], x, uk, theta)
            Phi_k, Qd_k = taylor_discretise(Fk, Q[k - 1] if Q_per_step else Q, hk)
            x = rk4_propagate(f, t[k - 1], x, hk, substeps, (uk, theta))
            P = Phi_k @ P @ Phi_k.T + Qd_k
            P = 0.5 * (P + P.T)
            Phi[k - 1] = Phi_k
            Qd[k - 1] = Qd_k
        x_pred[k] = x
        P_pred[k] = P
        zk = z[k]
        ok = np.isfinite(zk)
        Hk = H(t[k], x)
        H_all[k] = Hk
        all_ok = bool(ok.all())
        if all_ok or ok.any():
            if all_ok:  # fast path: no indexing
                Hm, Rm = Hk, R
                nu = zk - h(t[k], x)
            else:
                Hm = Hk[ok]
                Rm = R[np.ix_(ok, ok)]
                nu = zk[ok] - h(t[k], x)[ok]
            HP = Hm @ P
            S = HP @ Hm.T + Rm
            S = 0.5 * (S + S.T)
            # one Cholesky and one triangular-solve pair for [S⁻¹H | S⁻¹ν]
            try:
                L = np.linalg.cholesky(S)
            except np.linalg.LinAlgError:
                check_positive_definite(S, f"innovation covariance at sample {k} (t = {t[k]:.6g} s)")
                raise
            SiB = cho_solve((L, True), np.column_stack([Hm, nu]), check_finite=False)
            SiH = SiB[:, :-1]
            Sinv_nu = SiB[:, -1]
            K = (SiH @ P).T  # P Hᵀ S⁻¹ (P symmetric)
            x = x + K @ nu
            ikh = I - K @ Hm
            # Joseph form: stays symmetric positive semi-definite under rounding
            P = ikh @ P @ ikh.T + K @ Rm @ K.T
            P = 0.5 * (P + P.T)
            HSn[k] = Hm.T @ Sinv_nu
            HSH[k] = Hm.T @ SiH
            nis[k] = float(nu @ Sinv_nu)
            logdet = 2.0 * float(np.sum(np.log(np.diag(L))))
            loglik += -0.5 * (nis[k] + logdet + nu.size * LOG2PI)
            if all_ok:
                innov[k] = nu
                S_all[k] = S
                K_all[k] = K
            else:
                innov[k, ok] = nu
                S_all[k][np.ix_(ok, ok)] = S
                K_all[k][:, ok] = K
                H_all[k][~ok] = 0.0  # missing rows zeroed for the smoother
        else:
            H_all[k][:] = 0.0
        if check_pd and (k % 50 == 0 or k == N - 1):
            check_positive_definite(P, f"filter covariance at sample {k} (t = {t[k]:.6g} s)")
        x_filt[k] = x
        P_filt[k] = P
    return replace(fr, loglik=float(loglik))


__all__ = ["FilterResult", "cd_ekf", "van_loan", "taylor_discretise", "rk4_propagate"]
