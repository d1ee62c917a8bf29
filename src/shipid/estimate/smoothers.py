"""Fixed-interval smoothers for a filter run: modified Bryson–Frazier (Bierman 1973) and RTS.

Modified Bryson–Frazier (MBF) smoother (Bierman 1973; Yoon & Rhee 2003 eq. 10, Fig. 3).
The adjoint vector λ and matrix Λ run backwards from ``λ(t_N|t_N) = 0``,
``Λ(t_N|t_N) = 0``::

    λ(t_k|t_{k−1}) = −Hᵀ S⁻¹ ν_k + (I − K_k H_k)ᵀ λ(t_k|t_k)
    Λ(t_k|t_{k−1}) =  Hᵀ S⁻¹ H  + (I − K_k H_k)ᵀ Λ(t_k|t_k) (I − K_k H_k)
    λ(t_{k−1}|t_{k−1}) = Φ_{k−1}ᵀ λ(t_k|t_{k−1}),  Λ(t_{k−1}|t_{k−1}) = Φ_{k−1}ᵀ Λ(t_k|t_{k−1}) Φ_{k−1}

and the smoothed estimates are (eq. 10)::

    x̂(t_k|t_N) = x̂(t_k|t_k) − P(t_k|t_k) λ(t_k|t_k)
    P(t_k|t_N) = P(t_k|t_k) − P(t_k|t_k) Λ(t_k|t_k) P(t_k|t_k)

It needs no inverse of a covariance matrix (the reason Bierman preferred it to RTS).

Rauch–Tung–Striebel (RTS)::

    C_k = P(t_k|t_k) Φ_kᵀ P(t_{k+1}|t_k)⁻¹
    x̂(t_k|t_N) = x̂(t_k|t_k) + C_k (x̂(t_{k+1}|t_N) − x̂(t_{k+1}|t_k))
    P(t_k|t_N) = P(t_k|t_k) + C_k (P(t_{k+1}|t_N) − P(t_{k+1}|t_k)) C_kᵀ

On a linear model both give the same smoothed estimates (tested); on the EKF they
differ only through the linearisation (RTS uses the nonlinear prediction
x̂(t_{k+1}|t_k), MBF the linear Φ).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shipid.estimate.cd_ekf import FilterResult
from shipid.numerics.linalg import symmetrize


@dataclass(frozen=True)
class SmootherResult:
    """Smoothed states ``x`` (N, n) and covariances ``P`` (N, n, n) at the filter's times ``t``."""

    t: np.ndarray
    x: np.ndarray
    P: np.ndarray
    method: str

    @property
    def std(self) -> np.ndarray:
        """Standard deviations (N, n)."""
        return np.sqrt(np.maximum(np.einsum("kii->ki", self.P), 0.0))


def mbf_smoother(fr: FilterResult) -> SmootherResult:
    """Modified Bryson–Frazier fixed-interval smoother (Bierman 1973; eq. 10)."""
    N, n = fr.x_filt.shape
    xs = np.empty_like(fr.x_filt)
    Ps = np.empty_like(fr.P_filt)
    lam = np.zeros(n)
    Lam = np.zeros((n, n))
    I = np.eye(n)
    for k in range(N - 1, -1, -1):
        Pf = fr.P_filt[k]
        xs[k] = fr.x_filt[k] - Pf @ lam
        Ps[k] = symmetrize(Pf - Pf @ Lam @ Pf)
        if k == 0:
            break
        # through the measurement update at t_k (to "before the measurement")
        ikh = I - fr.K[k] @ fr.H[k]
        lam_m = -fr.HtSinv_nu[k] + ikh.T @ lam
        Lam_m = fr.HtSinv_H[k] + ikh.T @ Lam @ ikh
        # back to t_{k−1} through the linearised dynamics
        Ph = fr.Phi[k - 1]
        lam = Ph.T @ lam_m
        Lam = symmetrize(Ph.T @ Lam_m @ Ph)
    return SmootherResult(t=fr.t, x=xs, P=Ps, method="mbf")


def rts_smoother(fr: FilterResult) -> SmootherResult:
    """Rauch–Tung–Striebel fixed-interval smoother on the filter's Φ and predictions."""
    import scipy.linalg as sla  # scipy.linalg only where it is called

    N, n = fr.x_filt.shape
    xs = np.empty_like(fr.x_filt)
    Ps = np.empty_like(fr.P_filt)
    xs[-1] = fr.x_filt[-1]
    Ps[-1] = fr.P_filt[-1]
    for k in range(N - 2, -1, -1):
        Pf = fr.P_filt[k]
        Pp = fr.P_pred[k + 1]
        cf = sla.cho_factor(symmetrize(Pp), lower=True, check_finite=False)
        C = sla.cho_solve(cf, fr.Phi[k] @ Pf, check_finite=False).T  # Pf Φᵀ Pp⁻¹
        xs[k] = fr.x_filt[k] + C @ (xs[k + 1] - fr.x_pred[k + 1])
        Ps[k] = symmetrize(Pf + C @ (Ps[k + 1] - Pp) @ C.T)
    return SmootherResult(t=fr.t, x=xs, P=Ps, method="rts")


__all__ = ["SmootherResult", "mbf_smoother", "rts_smoother"]
