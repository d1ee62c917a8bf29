"""Observability rank test along a trajectory (Yoon & Rhee 2003, §3.2, eq. 11).

At each sample t_k the linearised model (F = ∂f/∂x, H = ∂h/∂x at the estimate) is
observable when the observability matrix (eq. 11)::

    O(t_k) = [H; H F; …; H F^{n−1}]

has rank n. Numerically the rank is that of a *scaled* matrix: states are scaled
by typical magnitudes ``D`` (forces of 1e6 N next to angles of 1e-3 rad would
otherwise make the singular values meaningless) and measurements are whitened by
their noise standard deviations ``σ``::

    F_s = D⁻¹ F D,   H_s = diag(σ)⁻¹ H D,   O_s = [H_s; H_s F_s; …]

and the rank counts singular values above ``rtol · σ_max(O_s)``. The smallest
relative singular value is reported too: it is the margin of the decision.

§3.2: with the absolute position (x, y) in the state instead of the position
relative to the water (x_r, y_r), the rank drops to n − 1 —
:func:`ebm_observability` computes both.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def observability_matrix(F: np.ndarray, H: np.ndarray, order: int | None = None) -> np.ndarray:
    """Stack ``[H; HF; …; HF^{order−1}]`` (order defaults to n), eq. 11."""
    n = F.shape[0]
    order = n if order is None else order
    blocks = [H]
    M = H
    for _ in range(order - 1):
        M = M @ F
        blocks.append(M)
    return np.vstack(blocks)


def numerical_rank(O: np.ndarray, rtol: float = 1e-9) -> tuple[int, np.ndarray]:
    """Rank and relative singular values ``s / s_max`` of ``O``."""
    s = np.linalg.svd(O, compute_uv=False)
    rel = s / s[0] if s[0] > 0 else s
    return int(np.sum(rel > rtol)), rel


@dataclass(frozen=True)
class RankHistory:
    """Rank of eq. 11 at each tested sample."""

    t: np.ndarray
    rank: np.ndarray
    min_rel_sv: np.ndarray
    n: int

    @property
    def full_rank_fraction(self) -> float:
        return float(np.mean(self.rank == self.n))


def rank_along(F_fn, H_fn, t: np.ndarray, X: np.ndarray, scales: np.ndarray, meas_std: np.ndarray,
               *, every: int = 1, rtol: float = 1e-9) -> RankHistory:
    """Rank of the scaled observability matrix at ``t[::every]`` along ``X``."""
    D = np.asarray(scales, dtype=float)
    Dinv = 1.0 / D
    Sinv = 1.0 / np.asarray(meas_std, dtype=float)
    idx = np.arange(0, len(t), every)
    ranks = np.empty(idx.size, dtype=int)
    mins = np.empty(idx.size)
    n = D.size
    for j, k in enumerate(idx):
        F = F_fn(t[k], X[k])
        H = H_fn(t[k], X[k])
        Fs = Dinv[:, None] * F * D[None, :]
        Hs = Sinv[:, None] * H * D[None, :]
        rk, rel = numerical_rank(observability_matrix(Fs, Hs), rtol)
        ranks[j] = rk
        mins[j] = rel[min(n, rel.size) - 1]
    return RankHistory(t=np.asarray(t)[idx], rank=ranks, min_rel_sv=mins, n=n)


#: Typical magnitudes of the 17 EBM states (u_r, v_r, r, x_r, y_r, ψ, X…, Y…, N…, c_x, c_y).
EBM_SCALES = np.array([1.0, 1.0, 1e-3, 10.0, 10.0, 1e-3, 1e6, 1e4, 1e2, 1e6, 1e4, 1e2,
                       1e8, 1e6, 1e4, 1.0, 1.0])


def ebm_observability(model, t: np.ndarray, X: np.ndarray, meas_std: np.ndarray, *, every: int = 10,
                      rtol: float = 1e-9) -> dict[str, RankHistory]:
    """Rank test of eq. 11 along an estimated trajectory, relative and absolute position (§3.2).

    Parameters
    ----------
    model : shipid.models.ebm_state.EbmModel
    t, X : sample times and (smoothed) 17-state trajectory.
    meas_std : the six measurement standard deviations (eq. 19).

    Returns
    -------
    dict with ``"relative"`` (the paper's state, eq. 7) and ``"absolute"`` (x, y instead
    of x_r, y_r) rank histories.
    """
    from dataclasses import replace

    rel = rank_along(model.F, model.H, t, X, EBM_SCALES, meas_std, every=every, rtol=rtol)
    absm = replace(model, absolute=True)
    ab = rank_along(absm.F, absm.H, t, X, EBM_SCALES, meas_std, every=every, rtol=rtol)
    return {"relative": rel, "absolute": ab}


__all__ = ["observability_matrix", "numerical_rank", "RankHistory", "rank_along", "ebm_observability",
           "EBM_SCALES"]
