"""Covariance of the monitor's estimate: a block (Newey-West) sandwich over all three datasets of (40).

The monitor minimises the IV criterion (40) of Linder et al. (2015) summed over the nominal, calibration and
loaded datasets, ``V(theta) = sum_i ||R_i g_i(theta) - r_i||^2 / lam_i`` with ``R_i^T R_i = Phi_i^T Z_i
(Z_i^T Z_i)^-1 Z_i^T Phi_i`` (the compressed products (41) of the prefiltered regressors (37) and
instruments (45)). The covariance of Algorithm 1, ``(J^T J)^-1`` with ``J`` the Jacobian of the weighted
residuals, holds when the prefiltered equation error ``e_i = y_i - Phi_i g_i`` of each dataset is white with
variance ``lam_i``: the noise model (42)-(43) is then exact. It is not, on a ship: the AR / Box-Jenkins
prefilter is refitted to a finite record, the wave roll is narrow-band, and a low-frequency misfit (bias,
unmodelled dynamics) leaves the equation error coloured. Two consequences, one per part of the estimate:

* the nominal and calibration datasets are processed once and their estimation error is *shared by every
  update* of the stream; the white-noise covariance understates it where their equation error is coloured,
  and then the whole stream lies outside its bands;
* the loaded window's error is what the window cannot average out: its blocks are not independent
  of the coloured error either.

The gradient of ``V / 2`` is a sum over blocks of samples (the monitor's ``every``-second blocks; the
reference datasets cut into blocks of the same length): the block ``b`` of dataset ``i`` contributes

    ``s_ib = dg_i^T u_ib / lam_i``,  ``u_ib = Phi_i^T Z_i (Z_i^T Z_i)^-1 Z_ib^T e_ib``,

with ``dg_i`` the derivative of (33) ``g_i(theta)`` over the free parameters. Whatever the colour of ``e_i``,
blocks much longer than its correlation time give nearly uncorrelated ``s_ib``, and the covariance of the
estimate is the sandwich ``H^-1 M H^-1`` with ``H = J^T J`` and ``M`` the covariance of the gradient,
estimated by Newey-West over the blocks of each dataset (Bartlett weights, the bandwidth of Newey & West's
(1994) rule ``floor(4 (B/100)^(2/9))`` blocks, 3 for the 30 blocks of a 300-s dataset: the correlation
between neighbouring blocks that a narrow-band wave moment, slow misfit and the prefilter's memory leave).
Under white noise ``E M = J^T J`` and the sandwich is the covariance of Algorithm 1. Each dataset's ``M_i`` is
never taken below its white-noise part ``J_i^T J_i``: only the positive part of ``M_i - J_i^T J_i`` is
added (a block estimate of a few tens of blocks falls below the model's covariance by sampling error, and
the white-noise covariance is already the least the data support). The blocks are uncentred: the score of a
block includes the dataset's misfit, which no average over the window removes.

A sensor bias is the one part of the reference datasets' error that no block average sees. A gyro bias
``b_1`` leaves the constant ``e0 = (1 + a_1 + a_2) b_1`` in the equation error (Linder et al. 2015, (9), (37));
the instruments (45) should be uncorrelated with it (section 4), and in the window they are (mean-removed per
block after the prefilter), but the reference datasets' instruments are mean-removed before the prefilter
(43), whose gain at zero frequency is ``D(1) / (1 - c)^k`` for the Box-Jenkins model, and the transient it
leaves is cut at a finite length: ``Z^T L(q) 1`` is not zero, and the constant moves the estimate by
``H^-1 b`` (:func:`sandwich`), the same error in every update of the stream. ``e0`` is estimated per reference
dataset by least squares on the prefiltered residual, and ``b b^T`` enters the gradient covariance whole
(the mean squared error of the unknown-bias part), the constant's part taken out of the block scores.
"""

from __future__ import annotations

import numpy as np

from shipid.methods.masscm.criterion import jacobian_cs
from shipid.methods.masscm.data import first_row
from shipid.methods.masscm.moments import closed_loop_sim, instruments, transient_length
from shipid.models.roll_reduced import discrete_coeffs, roll_terms


def nw_lags(n_blocks: int) -> int:
    """Bandwidth of the Newey-West sum: ``floor(4 (B / 100)^(2/9))`` lags for ``B`` blocks (Newey & West 1994)."""
    return int(4.0 * (n_blocks / 100.0) ** (2.0 / 9.0))


def _pinv_psd(A: np.ndarray, rtol: float = 1e-12) -> np.ndarray:
    """Pseudo-inverse of a symmetric positive semi-definite matrix with the rank rule of
    :func:`shipid.estimate.iv.iv_compress_products`."""
    s, V = np.linalg.eigh(A)
    keep = s > rtol * max(s[-1], 1e-300)
    return (V[:, keep] / s[keep]) @ V[:, keep].T


def block_projections(ZtZ: np.ndarray, ZtP: np.ndarray, blocks_ZtP) -> np.ndarray:
    """``Phi^T Z (Z^T Z)^-1 Z_b^T [Phi_b, y_b(, 1f_b)]`` per block: ``(B, 5, 6)`` (``(B, 5, 7)`` with the
    prefiltered constant ``1f`` as a seventh column); ``u_b = U_b[:, 5] - U_b[:, :5] g``."""
    A = ZtP[:, :5].T @ _pinv_psd(ZtZ)
    return np.einsum("ij,bjk->bik", A, np.asarray(blocks_ZtP))


def reference_projections(prep, L, theta_q: np.ndarray, known, conds, options, nb: int, idx=(0, 1)) -> list:
    """:func:`block_projections` of the reference datasets ``prep[i]`` (``i`` in ``idx``) at ``theta_q``.

    The instruments (45) of :func:`shipid.methods.masscm.moments.instruments` from the closed-loop simulation
    (46)-(47) at ``theta_q``, the prefilter ``L[i]`` (43) of the converged start-up run, its transient dropped
    (:func:`~shipid.methods.masscm.moments.transient_length`); blocks of ``nb`` samples (a shorter last one is
    merged into the one before). Per dataset ``(U, c)``: ``U`` the ``(B, 5, 7)`` projections of
    ``[Phi, y, 1f]`` with ``1f`` a constant through the same prefilter (the path of a sensor bias, see
    :func:`sandwich`), ``c = 1f^T [Phi_f, y_f, 1f]``; None for a dataset whose model at ``theta_q`` is unstable.
    """
    terms = roll_terms(theta_q, known, conds, moment=True)
    s = first_row(options)
    out = []
    for i in idx:
        ds, Li = prep[i], L[i]
        sim = closed_loop_sim(ds, terms, i, known)
        if sim is None:
            out.append(None)
            continue
        Z = instruments(ds, sim[0], sim[1], ds.r_hat0, Li, options)
        one = np.ones_like(ds.y)
        yf = (Li.prefilter(ds.y) if Li is not None else ds.y)[s:]
        Pf = (Li.prefilter(ds.Phi) if Li is not None else ds.Phi)[s:]
        of = (Li.prefilter(one) if Li is not None else one)[s:]
        k = transient_length(Li, yf.size, options)
        Z, P = Z[k:], np.column_stack([Pf[k:], yf[k:], of[k:]])
        nbk = max(1, Z.shape[0] // nb)
        edges = [j * nb for j in range(nbk)] + [Z.shape[0]]
        bl = [Z[a:b].T @ P[a:b] for a, b in zip(edges[:-1], edges[1:])]
        out.append((block_projections(Z.T @ Z, Z.T @ P, bl), P[:, 6] @ P))
    return out


def coeff_jacobian(theta_q: np.ndarray, known, conds, T: float, free: np.ndarray) -> np.ndarray:
    """``d g_i / d theta_q[free]`` of (33) for every dataset by complex step: ``(n_datasets, 5, n_free)``."""
    idx = np.flatnonzero(free)
    Ts = np.full(len(conds), T)

    def coeffs(x):
        th = theta_q.astype(x.dtype)
        th[idx] = x
        return discrete_coeffs(th, known, conds, Ts, moment=True).ravel()

    return jacobian_cs(coeffs, theta_q[idx]).reshape(len(conds), 5, idx.size)


def _newey_west(S: np.ndarray) -> np.ndarray:
    """``sum_b s_b s_b^T + sum_{l=1..L} (1 - l/(L+1)) sum_b (s_b s_{b+l}^T + s_{b+l} s_b^T)`` for block scores
    ``S`` (B, p), ``L = nw_lags(B)`` (Bartlett weights: the estimate is positive semi-definite)."""
    M = S.T @ S
    L = nw_lags(S.shape[0])
    for lag in range(1, min(L, S.shape[0] - 1) + 1):
        C = S[lag:].T @ S[:-lag]
        M += (1.0 - lag / (L + 1.0)) * (C + C.T)
    return M


def sandwich(J: np.ndarray, dg: np.ndarray, G: np.ndarray, lams, projections) -> np.ndarray:
    """Covariance ``H^-1 (M + b b^T) H^-1`` of the free parameters (see the module docstring).

    ``J``: the Jacobian of the stacked weighted residuals of (40), five rows per dataset; ``dg`` from
    :func:`coeff_jacobian`; ``G`` the coefficients (33) at the estimate, ``(n_datasets, 5)``; ``lams`` the
    weights; ``projections[i]``: :func:`block_projections` of dataset ``i`` (None: its white-noise part only),
    or the pair ``(U, c)`` of :func:`reference_projections`, whose seventh column carries the prefiltered
    constant: the dataset's constant equation error ``e0`` (a gyro bias ``b_1`` leaves ``b_1 (1 + a_1 + a_2)``)
    is estimated by least squares on the prefiltered residual, ``e0 = (c_y - c_Phi g) / c_1``, its part is
    taken out of the block scores (it is no sampling error that the blocks average) and its gradient
    ``b_i = e0 dg_i^T Phi^T Z (Z^T Z)^-1 Z^T 1f / lam_i``, summed over the datasets into ``b``, enters whole:
    the error it causes, ``H^-1 b``, is shared by every block and every update.
    """
    H = J.T @ J
    M = np.zeros_like(H)
    bias = np.zeros(H.shape[0])
    for i, P in enumerate(projections):
        Ji = J[5 * i:5 * i + 5]
        white = Ji.T @ Ji
        M += white
        U, c = P if isinstance(P, tuple) else (P, None)
        if U is None or U.shape[0] < 2:
            continue
        u = U[:, :, 5] - U[:, :, :5] @ G[i]                # (B, 5): Phi^T Z (Z^T Z)^-1 Z_b^T e_b
        if c is not None and c[6] > 0:
            uc = U[:, :, 6] * ((c[5] - c[:5] @ G[i]) / c[6])   # the constant's part of every block
            u = u - uc
            bias += uc.sum(axis=0) @ dg[i] / lams[i]
        S = u @ dg[i] / lams[i]                            # (B, n_free): the blocks' scores
        ev, V = np.linalg.eigh(_newey_west(S) - white)
        M += (V * np.maximum(ev, 0.0)) @ V.T
    Hi = np.linalg.inv(H)
    C = Hi @ (M + np.outer(bias, bias)) @ Hi
    return 0.5 * (C + C.T)


__all__ = ["nw_lags", "block_projections", "reference_projections", "coeff_jacobian", "sandwich"]
