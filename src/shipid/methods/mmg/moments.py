"""Step-2 fits of cross-validation folds from per-run moments of the regression.

Every quantity :func:`shipid.methods.mmg.estimator.fit` takes from the stacked regression
``y = H θ`` of a mode — the column norms that decide which coefficients are estimable,
the number of rows on which a regressor is non-zero, and the ridge fit itself
(:func:`shipid.estimate.ridge.ridge`: unit-length scaling, the normal equations
``C b = g`` with ``C = WᵀW``, ``g = Wᵀy*``, the OLS residual variance and the
Hoerl–Kennard biasing parameter, Yoon & Rhee 2003 §4, eqs. 16–18) — is a function of
the moments ``Hᵀ H``, ``Hᵀ y``, ``yᵀ y``, the row count and, for the counts, the sorted
``|H|`` of each column. Those are additive over runs, so a fold's fit is the sum of its
training runs' moments: each run's are computed once per candidate instead of stacking
and rescaling the rows once per fold. The OLS residual sum of squares is
``y*ᵀy* − 2 bᵀg + bᵀ C b`` (``y*ᵀy* = 1`` after scaling). The coefficients equal the
stacked fit's to rounding (``tests/methods/mmg/test_moments.py``); the fold model is
used for prediction only (no standard errors are formed).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

from shipid.estimate.ridge import hoerl_kennard_k
from shipid.models import mmg


@dataclass(frozen=True)
class Moments:
    """Moments of one mode's regression rows: ``HᵀH`` (p, p), ``Hᵀy`` (p,), ``yᵀy``, rows ``n``,
    the ascending ``|H|`` of every column (list of p arrays), and per column the number of
    non-zero entries ``nnz`` and the smallest non-zero ``|H|`` ``min_nz`` (inf if none)."""

    G: np.ndarray
    c: np.ndarray
    yy: float
    n: int
    absH: tuple[np.ndarray, ...]
    names: tuple[str, ...]
    nnz: np.ndarray
    min_nz: np.ndarray

    @classmethod
    def of(cls, H: np.ndarray, y: np.ndarray, names: Sequence[str]) -> "Moments":
        a = np.abs(H)
        nz = a > 0
        return cls(G=H.T @ H, c=H.T @ y, yy=float(y @ y), n=int(H.shape[0]),
                   absH=tuple(np.sort(a[:, j]) for j in range(H.shape[1])), names=tuple(names),
                   nnz=np.count_nonzero(nz, axis=0), min_nz=np.where(nz, a, np.inf).min(axis=0, initial=np.inf))


def _count_above(blocks: Sequence[Moments], thr: float) -> np.ndarray:
    """Per column, the number of rows with ``|H| > thr`` over all blocks (exact)."""
    total = np.zeros(blocks[0].nnz.size, np.int64)
    for b in blocks:
        cnt = b.nnz.astype(np.int64)
        for j in np.flatnonzero(b.min_nz <= thr):      # rare: the threshold cuts into the column
            cnt[j] = b.n - np.searchsorted(b.absH[j], thr, side="right")
        total += cnt
    return total


def ridge_theta(G: np.ndarray, c: np.ndarray, yy: float, n: int, k: float | None = None, *,
                tol: float = 1e-6, max_iter: int = 200) -> tuple[np.ndarray, bool]:
    """The coefficients of :func:`shipid.estimate.ridge.ridge` from moments; ``(theta, converged)``.

    Raises ValueError where the stacked ridge would (too few rows, a zero column or response).
    """
    p = G.shape[0]
    S_jj = np.diag(G).copy()
    if np.any(S_jj <= 0):
        raise ValueError(f"regressor column(s) {np.flatnonzero(S_jj <= 0).tolist()} are identically zero")
    if yy <= 0:
        raise ValueError("the response is identically zero")
    if n <= p:
        raise ValueError(f"need more samples than coefficients (have {n} for {p})")
    sj = np.sqrt(S_jj)
    C = G / np.outer(sj, sj)
    g = c / (sj * np.sqrt(yy))
    b_ols = np.linalg.solve(C, g)
    sse_ols = max(float(1.0 - 2.0 * b_ols @ g + b_ols @ C @ b_ols), 0.0)
    sigma2 = sse_ols / (n - p)
    conv = True
    if k is None:
        k, iters, conv = hoerl_kennard_k(C, g, sigma2, tol=tol, max_iter=max_iter)
        if not conv:
            warnings.warn(f"Hoerl–Kennard iteration for k did not converge after {iters} steps "
                          f"(using k = {k:.3g})", RuntimeWarning, stacklevel=2)
    b = np.linalg.inv(C + float(k) * np.eye(p)) @ g
    return b * np.sqrt(yy / S_jj), bool(conv)


def run_moments(data: Mapping[str, "object"]) -> dict[str, Moments]:
    """Moments of each mode of one run's :func:`shipid.methods.mmg.estimator.regression_data`."""
    return {m: Moments.of(data[m].H, data[m].y, data[m].names) for m in mmg.MODES}


def fit_from_moments(blocks: Sequence[Mapping[str, Moments]], prior: mmg.MmgModel, ridge_k: float | None = None,
                     name: str = "mmg-identified") -> mmg.MmgModel:
    """The model of :func:`shipid.methods.mmg.estimator.fit` on the runs whose moments are ``blocks``.

    Same rules: a coefficient whose column norm is below 1e-12 of the largest, or that is
    non-zero on fewer than 20 rows, is dropped (kept at the prior value, its force moved
    to the fixed part); the rest are fitted by ridge with Hoerl–Kennard's k.
    """
    new: dict[str, float] = {}
    for mode in mmg.MODES:
        bm = [b[mode] for b in blocks]
        names = bm[0].names
        G = np.sum([b.G for b in bm], axis=0)
        c = np.sum([b.c for b in bm], axis=0)
        yy = float(sum(b.yy for b in bm))
        n = int(sum(b.n for b in bm))
        colnorm = np.sqrt(np.diag(G))
        thr = 1e-12 * max(colnorm.max(), 1e-300) if colnorm.size else 0.0
        ok = colnorm > thr
        ok &= _count_above(bm, thr) >= 20
        if not ok.any():
            continue
        cf, cd = c[ok], None
        if not ok.all():
            td = np.array([prior.coef[nm] for nm, k in zip(names, ok) if not k])
            Gon = G[np.ix_(ok, ~ok)]
            Gnn = G[np.ix_(~ok, ~ok)]
            cd = c[~ok]
            cf = c[ok] - Gon @ td
            yy = yy - 2.0 * float(td @ cd) + float(td @ Gnn @ td)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            theta, _ = ridge_theta(G[np.ix_(ok, ok)], cf, yy, n, ridge_k)
        for w in caught:
            warnings.warn(f"mode {mode}: {w.message}", w.category, stacklevel=2)
        new.update(dict(zip([nm for nm, k in zip(names, ok) if k], theta)))
    return prior.with_coef(new, name=name)


__all__ = ["Moments", "ridge_theta", "run_moments", "fit_from_moments"]
