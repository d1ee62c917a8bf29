"""Parameter covariance of an identified MMG model that allows for correlated residuals.

The ridge standard errors of :func:`shipid.methods.mmg.estimator.fit` (``σ̂² A⁻¹ WᵀW A⁻¹``,
Yoon & Rhee 2003 §4) treat every regression row as an independent observation. The rows
are samples of smoothed force histories, correlated over seconds within a run, and the
runs of a campaign differ in more than noise (an approach speed, the sea state of the
basin, a model error that shows differently in each manoeuvre), so those errors are too
small. Two covariances that do not assume independent rows:

* ``"hac"`` — per mode, the Newey–West (1987) sandwich ``A⁻¹ S A⁻¹ · n/(n − p)`` with
  ``S`` the Bartlett-kernel long-run covariance of the scores and Andrews' (1991)
  bandwidth, lags never pairing rows of different runs
  (:func:`shipid.estimate.ridge.ridge` with ``cov="hac"``). Valid for serial correlation
  within runs; it still treats the runs as independent with the same residual process,
  and the modes as independent (block-diagonal).
* ``"run-bootstrap"`` — the runs are resampled with replacement ``draws`` times (a
  cluster bootstrap with one cluster per run, e.g. Cameron, Gelbach & Miller 2008) and
  the whole step-2 fit is repeated on each resample from the per-run moments
  (:func:`shipid.methods.mmg.moments.fit_from_moments`, same ridge rule and
  Hoerl–Kennard k as the fit itself); the covariance is that of the refitted
  coefficients, across modes included (the same rudder force enters sway and yaw).
  It carries the run-to-run variation of the estimate, whatever its cause; with few
  runs it is itself uncertain (the number of distinct resamples is small), and it is
  scaled by ``R/(R − 1)`` for ``R`` runs (the usual small-cluster correction).

Which covariance is honest was checked on real runs by splitting the training runs at random into two
halves, fitting each, and dividing every coefficient's difference between the halves by the standard
deviation the covariance states for it (an honest one gives an RMS z near 1): on the KVLCC2 and Esso
Osaka runs the ridge errors are several times too small, the HAC sandwich too small on KVLCC2, and the
run bootstrap about right (``studies/mmg_covariance``; figures: ``docs/validation/mmg.md``), so
:func:`honest_covariance`, which ``identify mmg`` stores in MODEL.json, uses the run bootstrap.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import NamedTuple, Sequence

import numpy as np

from shipid.errors import InputError
from shipid.estimate.ridge import ridge
from shipid.methods.mmg.estimator import FitConfig, MmgFit, SmoothedRun, fit, regression_data
from shipid.methods.mmg.moments import fit_from_moments, run_moments
from shipid.models import mmg

#: Covariance kinds :func:`parameter_covariance` computes.
KINDS = ("ridge", "hac", "run-bootstrap")
#: Fewest training runs for the run bootstrap in :func:`honest_covariance`.
MIN_BOOTSTRAP_RUNS = 5


@dataclass(frozen=True)
class CovarianceOptions:
    """``kind`` one of :data:`KINDS`; ``draws``, ``seed`` of the run bootstrap."""

    kind: str = "run-bootstrap"
    draws: int = 200
    seed: int = 0


def free_names(f: MmgFit) -> list[str]:
    """The estimated coefficients in the order of MODEL.json's ``covariance_names``."""
    return [c for m in mmg.MODES for c in f.free.get(m, ())]


def _per_run_data(f: MmgFit, runs: Sequence[SmoothedRun], prior: mmg.MmgModel, config: FitConfig) -> list[dict]:
    """Each run's regression rows on the coefficients the fit estimated (dropped ones at the prior)."""
    free = {m: tuple(f.free.get(m, ())) for m in mmg.MODES}
    return [regression_data([r], prior, free, config) for r in runs]


def hac_covariance(f: MmgFit, runs: Sequence[SmoothedRun], prior: mmg.MmgModel,
                   config: FitConfig = FitConfig()) -> np.ndarray:
    """Block-diagonal Newey–West covariance of the fitted coefficients (module docstring), same k as the fit."""
    data = _per_run_data(f, runs, prior, config)
    blocks = []
    for m in mmg.MODES:
        names = f.free.get(m, ())
        if not names:
            continue
        H = np.concatenate([d[m].H for d in data])
        y = np.concatenate([d[m].y for d in data])
        seg = np.concatenate([np.full(d[m].y.size, i) for i, d in enumerate(data)])
        rf = ridge(H, y, f.fits[m].k, cov="hac", segments=seg)
        # the same regression with its rows regrouped by run: equal up to round-off, which grows with the
        # conditioning (a coefficient 1e-3 of the largest in a cond-6.6e3 X mode moved by 1.8e-8 relative)
        th = f.fits[m].theta
        if not np.allclose(rf.theta, th, rtol=1e-6, atol=1e-9 * float(np.max(np.abs(th), initial=0.0))):
            raise InputError(f"mode {m}: the HAC refit does not reproduce the fitted coefficients")
        blocks.append(rf.cov_theta)
    p = sum(b.shape[0] for b in blocks)
    out = np.zeros((p, p))
    i = 0
    for b in blocks:
        out[i:i + b.shape[0], i:i + b.shape[0]] = b
        i += b.shape[0]
    return 0.5 * (out + out.T)


def bootstrap_draws(f: MmgFit, runs: Sequence[SmoothedRun], prior: mmg.MmgModel, config: FitConfig = FitConfig(),
                    *, draws: int = 200, seed: int = 0) -> np.ndarray:
    """``(draws, p)`` coefficients refitted on runs resampled with replacement (seeded)."""
    if len(runs) < 2:
        raise InputError("a run bootstrap needs at least 2 training runs")
    names = free_names(f)
    mom = [run_moments(d) for d in _per_run_data(f, runs, prior, config)]
    rng = np.random.default_rng(seed)
    out = np.empty((draws, len(names)))
    R = len(runs)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")       # a resample's Hoerl-Kennard fallback is part of its spread
        for b in range(draws):
            idx = rng.integers(0, R, R)
            try:
                model = fit_from_moments([mom[i] for i in idx], prior, config.ridge_k)
                out[b] = [model.coef[n] for n in names]
            except (ValueError, np.linalg.LinAlgError):
                out[b] = np.nan              # a resample on which a column vanished: left out
    return out


def bootstrap_covariance(f: MmgFit, runs: Sequence[SmoothedRun], prior: mmg.MmgModel,
                         config: FitConfig = FitConfig(), *, draws: int = 200, seed: int = 0) -> np.ndarray:
    """Run-bootstrap covariance (module docstring), ``R/(R − 1)``-scaled."""
    B = bootstrap_draws(f, runs, prior, config, draws=draws, seed=seed)
    B = B[np.all(np.isfinite(B), axis=1)]
    if B.shape[0] < max(10, B.shape[1] + 1):
        raise InputError(f"run bootstrap: only {B.shape[0]} of {draws} resamples could be fitted")
    R = len(runs)
    S = np.cov(B, rowvar=False, ddof=1).reshape(B.shape[1], B.shape[1]) * R / (R - 1.0)
    return 0.5 * (S + S.T)


def ridge_covariance(f: MmgFit) -> np.ndarray:
    """The ridge (independent-rows) covariance, block-diagonal over modes."""
    names = free_names(f)
    out = np.zeros((len(names), len(names)))
    i = 0
    for m in mmg.MODES:
        if m in f.fits:
            p = len(f.free[m])
            out[i:i + p, i:i + p] = f.fits[m].cov_theta
            i += p
    return out


def parameter_covariance(f: MmgFit, runs: Sequence[SmoothedRun], prior: mmg.MmgModel,
                         config: FitConfig = FitConfig(),
                         options: CovarianceOptions = CovarianceOptions()) -> np.ndarray:
    """The covariance of :attr:`CovarianceOptions.kind` for the coefficients :func:`free_names` lists.

    Positive semi-definiteness is checked (a negative eigenvalue beyond rounding raises).
    """
    if options.kind == "ridge":
        S = ridge_covariance(f)
    elif options.kind == "hac":
        S = hac_covariance(f, runs, prior, config)
    elif options.kind == "run-bootstrap":
        S = bootstrap_covariance(f, runs, prior, config, draws=options.draws, seed=options.seed)
    else:
        raise InputError(f"unknown covariance '{options.kind}' (choose from {', '.join(KINDS)})")
    w = np.linalg.eigvalsh(S) if S.size else np.zeros(0)
    if w.size and w.min() < -1e-9 * max(w.max(), 1e-300):
        raise InputError(f"{options.kind} covariance is not positive semi-definite (eigenvalue {w.min():.3g})")
    return S


class HonestCovariance(NamedTuple):
    """:func:`honest_covariance`'s answer: the matrix, its one-line description and its kind
    (``"run-bootstrap"`` or ``"hac"``)."""

    cov: np.ndarray
    note: str
    kind: str


def honest_covariance(f: MmgFit, runs: Sequence[SmoothedRun], prior: mmg.MmgModel,
                      config: FitConfig = FitConfig(), *, draws: int = 200, seed: int = 0) -> HonestCovariance:
    """The covariance MODEL.json carries, its description and kind: the run bootstrap from
    :data:`MIN_BOOTSTRAP_RUNS` training runs on, the HAC sandwich below that (fewer runs
    give too few distinct resamples; the HAC is then the less optimistic of the two that can be formed)."""
    R = len(runs)
    if R >= MIN_BOOTSTRAP_RUNS:
        try:
            return HonestCovariance(bootstrap_covariance(f, runs, prior, config, draws=draws, seed=seed),
                                    f"run-bootstrap SE ({draws} resamples of the {R} training runs, seed {seed})",
                                    "run-bootstrap")
        except InputError:
            pass
    return HonestCovariance(hac_covariance(f, runs, prior, config),
                            f"HAC (Newey-West within runs) SE: {R} training run(s), too few for a run bootstrap; "
                            "optimistic when runs differ by more than noise", "hac")


__all__ = ["KINDS", "CovarianceOptions", "free_names", "hac_covariance", "bootstrap_draws", "bootstrap_covariance",
           "ridge_covariance", "parameter_covariance", "honest_covariance", "HonestCovariance",
           "MIN_BOOTSTRAP_RUNS"]
