"""The DP schemes' parallel augmented EKF through the compiled kernel (:mod:`shipid.methods.dp.aekf_kernels`).

:func:`run_parallel` takes the prepared trials of one scheme (:func:`shipid.methods.dp.stage_models.prepare`)
and the filter's priors and noise levels and returns the same
:class:`~shipid.estimate.ekf_augmented.ParallelEKFResult` as
:func:`shipid.estimate.ekf_augmented.parallel_augmented_ekf` on the models of
:mod:`shipid.methods.dp.stage_models` (Fossen, Sagatun & Sørensen 1996, Table 1 and eqs. 20–25),
to round-off.
"""

from __future__ import annotations

import numpy as np

from shipid.errors import ConvergenceError
from shipid.estimate.ekf_augmented import AugmentedEKFResult, ParallelEKFResult
from shipid.methods.dp.aekf_kernels import MOMENTUM, SURGE, parallel_aekf


def run_parallel(kind: str, data: list[dict], vessel, theta_full: np.ndarray, est, x0, P0x: np.ndarray,
                 P0t: np.ndarray, qdiag: np.ndarray, Qt: np.ndarray, R: np.ndarray, consider=()) -> ParallelEKFResult:
    """Parallel augmented EKF of one scheme (surge model for ``kind == "surge"``, else momentum).

    Parameters
    ----------
    data : list of dict
        Prepared trials (``"t"`` bis, ``"Z"``, ``"U"``).
    theta_full : ndarray (9,)
        θ1..θ9; those in ``est`` are the augmented states' starting values.
    est : sequence of int
        θ indices in the augmented state.
    x0 : sequence of ndarray (nx,); P0x : (nx, nx) prior of each trial's state
    P0t : (p, p) prior of θ[est]
    qdiag : (nx,) process-noise intensities per bis time (the diagonal of Q / dt)
    Qt : (p, p) parameter random walk per step
    R : (nz, nz) diagonal measurement covariance
    consider : sequence of int
        Positions in ``est`` that are considered, not estimated.
    """
    code = SURGE if kind == "surge" else MOMENTUM
    N = len(data)
    lens = np.array([d["t"].size for d in data], dtype=np.int64)
    n = int(lens.max())
    nz = data[0]["Z"].shape[1]
    nx = len(x0[0])
    p = len(est)
    Z = np.full((N, n, nz), np.nan)
    U = np.zeros((N, n, 7))
    dt = np.zeros((N, n))
    for i, d in enumerate(data):
        Z[i, :lens[i]] = d["Z"]
        U[i, :lens[i]] = d["U"]
        dt[i, :lens[i] - 1] = np.diff(d["t"])
    P0 = np.zeros((N * nx + p, N * nx + p))
    for i in range(N):
        P0[i * nx:(i + 1) * nx, i * nx:(i + 1) * nx] = P0x
    P0[N * nx:, N * nx:] = P0t
    cons = np.zeros(p, dtype=np.bool_)
    cons[list(consider)] = True
    wrap = np.zeros(nz, dtype=np.bool_)
    if code == MOMENTUM:
        wrap[2] = True
    Rd = np.tile(np.diag(np.asarray(R, dtype=float)), (N, 1))
    qx = np.tile(np.asarray(qdiag, dtype=float), (N, 1))
    out = parallel_aekf(code, Z, lens, dt, U, np.asarray(theta_full, dtype=float), np.asarray(est, dtype=np.int64),
                        np.array([np.asarray(x, dtype=float) for x in x0]), P0, qx, np.asarray(Qt, dtype=float),
                        Rd, cons, wrap, vessel.M, vessel.Minv, np.asarray(vessel.arms, dtype=float))
    X, TH, PTH, PD, INN, SS, NIS, NIS_TR, loglik, P, bad, why = out
    if bad >= 0:
        cause = "a covariance is not positive definite" if why == 1 else "non-finite state"
        raise ConvergenceError(f"EKF diverged at step {bad}: {cause}")
    dof = np.sum(np.isfinite(INN), axis=1).astype(int)
    combined = AugmentedEKFResult(x=X.transpose(1, 0, 2).reshape(n, N * nx), theta=TH, P_diag=PD, theta_cov=PTH,
                                  P_final=P, innovations=INN, S=SS, nis=NIS, nis_dof=dof, loglik=float(loglik))
    xs = [X[i, :lens[i]] for i in range(N)]
    xv = [PD[:lens[i], i * nx:(i + 1) * nx] for i in range(N)]
    inn = [INN[:lens[i], i * nz:(i + 1) * nz] for i in range(N)]
    nis = [NIS_TR[i, :lens[i]] for i in range(N)]
    return ParallelEKFResult(x=xs, x_var=xv, theta=TH, theta_cov=PTH, innovations=inn, nis=nis,
                             loglik=float(loglik), combined=combined)


__all__ = ["run_parallel"]
