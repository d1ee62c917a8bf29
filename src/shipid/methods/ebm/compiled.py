"""Compiled (numba) continuous–discrete EKF and fixed-interval smoothers (Yoon & Rhee 2003).

The same algorithms as the reference pure-Python path — :func:`shipid.estimate.cd_ekf.cd_ekf`
(eq. 9, Fig. 3), :func:`shipid.estimate.smoothers.mbf_smoother` (eq. 10, Bierman 1973) and
:func:`~shipid.estimate.smoothers.rts_smoother` — compiled with numba (:mod:`shipid.methods.ebm.kernels`), returning the same
:class:`~shipid.estimate.cd_ekf.FilterResult` / :class:`~shipid.estimate.smoothers.SmootherResult`.
The reference path stays the definition: tests run both on a seeded trial and require
agreement to ~1e-9 relative (``tests/methods/ebm/test_kernels.py``).

What is compiled
----------------
* :func:`ebm_cd_ekf`: the filter for the 17-state EBM model of
  :mod:`shipid.models.ebm_state` (eqs. 4–8). The model's ``f, F, h, H`` are compiled
  kernels (:mod:`shipid.methods.ebm.model_kernels`) on the parameter
  vector of :meth:`shipid.models.ebm_state.EbmModel.kernel_params`; a generic model given as
  Python callables keeps using the reference :func:`~shipid.estimate.cd_ekf.cd_ekf`.
* :func:`mbf_smoother_fast`, :func:`rts_smoother_fast`: generic — they only read the arrays
  of a :class:`FilterResult`, whichever filter produced it.

Numerics (the standards of :mod:`shipid.numerics.linalg`, kept)
---------------------------------------------------------------
float64 throughout, no ``fastmath``. The per-sample algebra is the reference's, evaluated
so that the structure of the problem is not paid for in flops:

* Φ and Q_d by the same Taylor series as :func:`~shipid.estimate.cd_ekf.taylor_discretise`
  (same terms, same stopping rule). ``F`` has 24 non-zeros of 289, so products with ``F h``
  run over its non-zeros; ``C_k = F C_{k−1} + C_{k−1} Fᵀ`` is formed as ``G + Gᵀ`` with
  ``G = F C_{k−1}`` (``C`` is symmetric). If the series has not converged after
  ``max_terms`` the whole trial is handed to the reference path (which falls back to Van
  Loan's ``expm``), so no unconverged Φ is ever used.
* ``P⁻ = Φ P Φᵀ + Q_d`` skipping the zeros of Φ; the upper triangle is computed and
  mirrored, so P⁻ is exactly symmetric.
* The measurement update is the batch update of eq. 9 (all six measurements at once,
  Cholesky of S) — *no sequential scalar processing*, so the gains, ``S`` and the
  smoother's inputs are those of the reference. The covariance update is the Joseph form
  ``(I − K H) P (I − K H)ᵀ + K R Kᵀ``, evaluated through the low rank of ``K H``:
  ``A = P − K (H P)``, ``P⁺ = A + (K R − A Hᵀ) Kᵀ`` (algebraically identical; the Joseph
  form's insensitivity to errors in K is a property of the expression, not of the
  evaluation order), then symmetrised.
* Positive definiteness of the filtered covariance is checked by a Cholesky factorisation
  at *every* sample (the reference checks every 50th, for cost); a failure, or an innovation
  covariance S that is not positive definite, raises
  :class:`~shipid.numerics.linalg.NotPositiveDefiniteError` naming the sample index and time
  — nothing is returned from a failed run.
* MBF backward pass: ``(I − K H)ᵀ Λ (I − K H) = Λ − (Z H + (Z H)ᵀ)`` with ``U = Λ K``,
  ``Z = U − ½ Hᵀ (Kᵀ U)`` (again exact algebra, using Λ = Λᵀ).

Compilation is cached on disk (``cache=True``, in ``__pycache__``), so only the first call on a
machine pays the compile (~30 s on a 2-core machine); see :mod:`shipid.methods.ebm.kernels` for
how the cache is kept consistent.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from shipid.estimate.cd_ekf import FilterResult, cd_ekf
from shipid.numerics.linalg import NotPositiveDefiniteError
from shipid.estimate.smoothers import SmootherResult
from shipid.methods.ebm.kernels import (P_NOT_PD, S_NOT_PD, TAYLOR_NOT_CONVERGED, ebm_filter_loop, mbf_loop,
                                        rts_loop)


def _raise_not_pd(what: str, k: int, t: float, M: np.ndarray) -> None:
    with np.errstate(all="ignore"):
        finite = bool(np.all(np.isfinite(M)))
        lo = float(np.linalg.eigvalsh(0.5 * (M + M.T))[0]) if finite else float("nan")
    detail = f"smallest eigenvalue {lo:.3g}" if finite else "non-finite entries"
    raise NotPositiveDefiniteError(f"{what} at sample {k} (t = {t:.6g} s) is not positive definite ({detail})")


def ebm_cd_ekf(model, Q: np.ndarray, R: np.ndarray, t: np.ndarray, z: np.ndarray, x0: np.ndarray,
               P0: np.ndarray, *, substeps: int = 1, check_pd: bool = True, tol: float = 1e-15,
               max_terms: int = 40) -> FilterResult:
    """The CD-EKF of :func:`shipid.estimate.cd_ekf.cd_ekf` for the 17-state EBM model, compiled.

    Parameters
    ----------
    model : shipid.models.ebm_state.EbmModel
        Supplies :meth:`~shipid.models.ebm_state.EbmModel.kernel_params`; ``model.f/F/h/H``
        serve the reference fallback.
    Q, R, t, z, x0, P0, substeps, check_pd
        As :func:`~shipid.estimate.cd_ekf.cd_ekf` (NaN in ``z`` = missing measurement).
    tol, max_terms
        Stopping rule of the Taylor discretisation (as
        :func:`~shipid.estimate.cd_ekf.taylor_discretise`); if it does not converge at some
        sample the whole run is done by the reference path (Van Loan fallback there).

    Returns
    -------
    FilterResult
        Same fields as the reference; equal to it to rounding (~1e-12 relative).

    Raises
    ------
    NotPositiveDefiniteError
        The innovation covariance S, or (``check_pd``, checked at every sample) the filtered
        covariance, is not positive definite; the message names the sample index and time.
    """
    p = np.ascontiguousarray(model.kernel_params(), dtype=float)
    t = np.ascontiguousarray(t, dtype=float)
    z = np.ascontiguousarray(z, dtype=float)
    N, m = z.shape
    x0 = np.ascontiguousarray(x0, dtype=float).ravel()
    n = x0.size
    if n != 17 or m != 6:
        raise ValueError(f"ebm_cd_ekf needs 17 states and 6 measurements, got {n} and {m}")
    Qa = np.asarray(Q, dtype=float)
    Qa = np.ascontiguousarray(Qa[None] if Qa.ndim == 2 else Qa)
    if Qa.shape[0] > 1 and Qa.shape[0] != max(N - 1, 1):
        raise ValueError(f"Q per step must have N - 1 = {N - 1} matrices, got {Qa.shape[0]}")
    R = np.ascontiguousarray(R, dtype=float)
    P0 = np.ascontiguousarray(P0, dtype=float)
    fr = FilterResult.allocate(t, N, n, m)
    out = np.zeros(1)
    status, k = ebm_filter_loop(p, Qa, R, t, z, x0, P0, int(substeps), bool(check_pd), float(tol),
                                 int(max_terms), *fr.buffers(), out)
    if status == TAYLOR_NOT_CONVERGED:
        return cd_ekf(model.f, model.F, model.h, model.H, Q, R, t, z, x0, P0, substeps=substeps,
                      check_pd=check_pd)
    if status == S_NOT_PD:
        ok = np.isfinite(z[k])
        Hm = fr.H[k][ok]
        _raise_not_pd("innovation covariance", k, t[k], Hm @ fr.P_pred[k] @ Hm.T + R[np.ix_(ok, ok)])
    if status == P_NOT_PD:
        _raise_not_pd("filter covariance", k, t[k], fr.P_filt[k])
    return replace(fr, loglik=float(out[0]))


def mbf_smoother_fast(fr: FilterResult) -> SmootherResult:
    """Compiled :func:`shipid.estimate.smoothers.mbf_smoother` (same algorithm, eq. 10)."""
    xs = np.empty_like(fr.x_filt)
    Ps = np.empty_like(fr.P_filt)
    c = np.ascontiguousarray
    mbf_loop(c(fr.x_filt), c(fr.P_filt), c(fr.K), c(fr.H), c(fr.HtSinv_nu), c(fr.HtSinv_H), c(fr.Phi), xs, Ps)
    return SmootherResult(t=fr.t, x=xs, P=Ps, method="mbf")


def rts_smoother_fast(fr: FilterResult) -> SmootherResult:
    """Compiled :func:`shipid.estimate.smoothers.rts_smoother` (same algorithm).

    Raises :class:`NotPositiveDefiniteError` naming the sample whose predicted covariance
    cannot be factorised (the reference raises scipy's LinAlgError there).
    """
    xs = np.empty_like(fr.x_filt)
    Ps = np.empty_like(fr.P_filt)
    c = np.ascontiguousarray
    k = rts_loop(c(fr.x_filt), c(fr.P_filt), c(fr.x_pred), c(fr.P_pred), c(fr.Phi), xs, Ps)
    if k >= 0:
        _raise_not_pd("predicted covariance", k, fr.t[k], fr.P_pred[k])
    return SmootherResult(t=fr.t, x=xs, P=Ps, method="rts")


__all__ = ["ebm_cd_ekf", "mbf_smoother_fast", "rts_smoother_fast"]
