"""Output-error refinement of an MMG fit on restarted horizons (multiple shooting from the measured state).

The step-2 regression (:func:`shipid.methods.mmg.estimator.fit`) minimises the equation
error of the smoothed forces. What the horizon CV scores is different: the heading and
position errors of the model simulated open loop over 60-s horizons restarted from the
measured state (:func:`shipid.methods.mmg.validate.validate`). This module takes the
regression estimate as the starting point and minimises that output error directly
over the TRAINING runs' horizons — the multiple-shooting output-error criterion of
Ljung (1999, *System Identification*, §7.3 and §10.2; Bock & Plitt 1984 for the shooting
nodes), here with the shooting nodes fixed at the measured states::

    J(θ) = Σ_h Σ_k [ (wrap(ψ̂_hk(θ) − ψ_hk) / 10°)² + ((x̂_hk − x_hk)² + (ŷ_hk − y_hk)²) / (1 m)² ]

the same weighting as the CV score :func:`shipid.methods.mmg.estimator.horizon_score`
(10° of heading ~ 1 m of position). Each horizon starts at the measured state of its
first sample and is integrated with the measured inputs held over each step
(:func:`shipid.methods.mmg.manoeuvres.rows_rk4`), every ``decimate``-th sample; for the Esso
structures by its compiled copy :mod:`shipid.models.mmg_kernels` (``compiled=False``: the reference),
which gives the same predictions to round-off.

Minimisation: Levenberg–Marquardt (Marquardt 1963) in coordinates scaled by the
starting values, ``θ = θ₀ + S z``, ``S = diag(max(|θ₀|, se₀))``; forward-difference
Jacobian with every perturbed parameter vector simulated in the same batch as the
nominal one (in the compiled path the nominal residuals of an accepted step are reused: each row's
prediction does not depend on its batch). A diverging horizon (non-finite state) has its residuals set to a fixed
cap, so a step into an unstable model is rejected.

Standard errors: the horizon-cluster sandwich ``(JᵀJ)⁻¹ (Σ_h J_hᵀ r_h r_hᵀ J_h) (JᵀJ)⁻¹``
(White 1980; clusters = horizons, which do not overlap), because residuals within a
horizon are strongly serially correlated and the plain ``σ² (JᵀJ)⁻¹`` would be far too
small. With no more horizons than refined coefficients the sandwich is singular (its rank
is at most the number of clusters) and the covariance is returned as NaN: not determined.

Robust criterion (the default, ``OEConfig.robust``): after the least-squares pass each horizon's sum of
squares is weighted by Huber's ``min(1, c / e_h)`` (``e_h`` its RMS scaled error, ``c`` twice the median
horizon's) and the minimisation is repeated, twice, from where it stopped — iteratively reweighted least
squares for Huber's M-estimate at the horizon level (Huber 1964; Holland & Welsch 1977). The sandwich is
then that of the weighted criterion with the final weights held fixed (the M-estimator's sandwich up to
the weights' own dependence on θ, which is zero for every horizon inside ``c``). Chosen by a
training-run CV (``docs/validation/mmg.md``); ``robust=None``
(:data:`LEAST_SQUARES`) is the plain criterion.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Mapping, Sequence

import numpy as np

from shipid.io.trial import Trial
from shipid.errors import InputError, ShipidError
from shipid.methods.mmg import manoeuvres as MM
from shipid.methods.mmg.cv_fast import run_horizons, simulate_rows
from shipid.models import mmg

#: Heading and position scales of the criterion (the CV score's 10° ~ 1 m).
PSI_SCALE = np.deg2rad(10.0)
POS_SCALE = 1.0
#: Residual given to every sample of a diverged horizon (in scaled units).
DIVERGED = 10.0
#: Default Huber threshold of :class:`OEConfig` (multiple of the median horizon error), chosen by the
#: training-run CV (one value, fixed before its score; ``docs/validation/mmg.md``).
ROBUST_K = 2.0


@dataclass(frozen=True)
class OEConfig:
    """Settings of the output-error refinement.

    ``horizon`` (s) and ``decimate`` (simulate every n-th sample) as the horizon
    CV; ``max_iter`` Levenberg–Marquardt iterations; ``rtol`` stop when the cost
    falls by less than this fraction; ``fd_step`` forward-difference step in the
    scaled coordinates; ``exclude`` coefficients never refined (their regressors are
    rarely excited, e.g. the astern side-force polynomials), which keep the
    regression value and its standard error. ``run_weighting``: ``"pooled"`` every horizon
    counts the same (the pooled RMS the CV scores); ``"per-run"`` each run's horizons share
    a weight of one run (the mean over runs of the per-run mean square). ``stride``: seconds
    between the training horizons' starts; None restarts every ``horizon`` seconds (non-overlapping,
    as the CV and the validation score); a shorter stride gives overlapping horizons (more shooting
    nodes from the same runs), whose sandwich covariance then takes whole runs as clusters.
    ``robust``: None, least squares (:data:`LEAST_SQUARES`); a number ``k`` (default :data:`ROBUST_K`),
    Huber's M-estimate at the horizon level (Huber 1964, Ann Math Stat 35:73; iteratively reweighted,
    Holland & Welsch 1977, Commun Stat Theory Methods 6:813): each horizon's sum of
    squares is weighted by ``min(1, c / e_h)``, ``e_h`` its RMS scaled residual and ``c = k`` times the
    median of ``e_h`` over the horizons, the weights computed from the unweighted residuals of the
    previous pass (``robust_passes`` reweighted passes after the least-squares one). A horizon the model
    cannot follow (a ship at rest turning on its reversed propeller in the wind) then pulls on the
    coefficients in proportion to its error, not to its square.
    """

    horizon: float = 60.0
    decimate: int = 5
    max_iter: int = 4
    rtol: float = 1e-3
    fd_step: float = 1e-3
    mu0: float = 1e-2
    jacobian: str = "every"
    exclude_prefixes: tuple[str, ...] = ("YP_a", "NP_b", "XP_c")
    run_weighting: str = "pooled"
    stride: float | None = None
    robust: float | None = ROBUST_K
    robust_passes: int = 2


#: The plain least-squares refinement (every horizon's sum of squares weighted alike), the default before
#: the Huber weights.
LEAST_SQUARES = OEConfig(robust=None)


@dataclass(frozen=True)
class Horizons:
    """Restarted horizons of several runs stacked: ``x0`` (B, 6), ``U`` (B, L, 4), ``Z`` (B, L, 6),
    ``valid`` (B, L), step ``h`` (B, L − 1), the index of each horizon's run ``run`` (B,)."""

    x0: np.ndarray
    U: np.ndarray
    Z: np.ndarray
    valid: np.ndarray
    h: np.ndarray
    run: np.ndarray

    @property
    def count(self) -> int:
        return int(self.x0.shape[0])


def stack_horizons(trials: Sequence[Trial], horizon: float = 60.0, decimate: int = 2,
                   stride: float | None = None) -> Horizons:
    """The horizons of :func:`shipid.methods.mmg.cv_fast.run_horizons` of every run, padded to one length
    (``stride``: seconds between starts, None: ``horizon``)."""
    hz, run = [], []
    for i, tr in enumerate(trials):
        try:
            H = run_horizons(tr, horizon, decimate, stride)
        except ShipidError:
            H = None
        if H is not None:
            hz.append(H)
            run += [i] * H["count"]
    if not hz:
        raise ShipidError("output-error refinement: no horizon in the training runs")
    L = max(H["U"].shape[1] for H in hz)

    def pad(a, edge=True):
        w = [(0, 0), (0, L - a.shape[1])] + [(0, 0)] * (a.ndim - 2)
        return np.pad(a, w, mode="edge") if edge else np.pad(a, w, constant_values=False)

    return Horizons(x0=np.concatenate([H["x0"] for H in hz]),
                    U=np.concatenate([pad(H["U"]) for H in hz]),
                    Z=np.concatenate([pad(H["Z"]) for H in hz]),
                    valid=np.concatenate([pad(H["valid"], edge=False) for H in hz]),
                    h=np.concatenate([pad(np.repeat(H["h"][None], H["count"], 0)) for H in hz]),
                    run=np.asarray(run, int))


def cluster_index(H: Horizons, config: OEConfig) -> np.ndarray:
    """The sandwich cluster of each horizon (B,): the horizon itself, or its run where ``config.stride`` makes
    the horizons overlap (overlapping horizons share samples, so they are not independent)."""
    if config.stride is not None and config.stride < config.horizon:
        return np.unique(H.run, return_inverse=True)[1]
    return np.arange(H.count)


def simulate(model: mmg.MmgModel, names: Sequence[str], values: np.ndarray, H: Horizons,
             compiled: bool = True) -> np.ndarray:
    """(K, B, L, 6) predictions of every horizon for each of the K parameter vectors ``values`` (K, p).

    ``compiled``: as :func:`shipid.methods.mmg.cv_fast.simulate_rows` (False: the reference integration)."""
    values = np.atleast_2d(values)
    K, B, L = values.shape[0], H.count, H.U.shape[1]
    Th = MM.theta_rows(model, names, values)
    Th = {m: np.repeat(T, B, axis=0) for m, T in Th.items()}          # row = k * B + b
    out = simulate_rows(model, Th, np.tile(H.x0, (K, 1)), np.tile(H.U, (K, 1, 1)), np.tile(H.h, (K, 1)),
                        compiled=compiled)
    return out.reshape(K, B, L, 6)


def residuals(P: np.ndarray, H: Horizons) -> np.ndarray:
    """Scaled residuals (K, B, L, 3): heading / 10°, x and y / 1 m; zero on padding, capped on divergence."""
    Z = H.Z[None]
    dpsi = np.angle(np.exp(1j * (P[..., 2] - Z[..., 2]))) / PSI_SCALE
    r = np.stack([dpsi, (P[..., 0] - Z[..., 0]) / POS_SCALE, (P[..., 1] - Z[..., 1]) / POS_SCALE], axis=-1)
    bad = ~np.all(np.isfinite(P), axis=(-1, -2))                          # (K, B): a diverged horizon
    r = np.where(bad[..., None, None], DIVERGED, r)
    r = np.clip(np.nan_to_num(r, nan=DIVERGED), -DIVERGED, DIVERGED)
    return r * H.valid[None, :, :, None]


def horizon_errors(r: np.ndarray, H: Horizons) -> np.ndarray:
    """(B,) RMS scaled residual of each horizon: ``sqrt(Σ_k |r_hk|² / n_h)``, ``n_h`` its valid samples."""
    n = np.maximum(H.valid.sum(axis=1), 1)
    return np.sqrt(np.sum(r * r, axis=(1, 2)) / n)


def huber_weights(r: np.ndarray, H: Horizons, k: float) -> np.ndarray:
    """(B,) Huber weights ``min(1, c / e_h)`` of the horizons' sums of squares, ``c = k · median(e_h)``.

    ``r``: (B, L, 3) unweighted scaled residuals (:func:`residuals`). The weight of a horizon's sum of
    squares ``S_h = n_h e_h²`` that makes the weighted least squares stationary where Huber's loss
    ``ρ_c(e_h)`` is: ``ρ_c'(e_h) / e_h = min(1, c / e_h)`` (``OEConfig.robust``).
    """
    e = horizon_errors(r, H)
    c = float(k) * float(np.median(e))
    return np.where(e > c, c / np.where(e > 0, e, 1.0), 1.0) if c > 0 else np.ones_like(e)


def _levenberg_marquardt(z, r, J, c, exact, fd_jacobian, res_of, th0, S, cost_of, config: OEConfig):
    """Levenberg–Marquardt iterations of :func:`refine` from ``z`` (residuals ``r``, Jacobian ``J``, cost ``c``).

    Returns ``z, r, J, c, exact, iterations, converged``; ``exact``: ``J`` is the finite-difference
    Jacobian at ``z``.
    """
    mu, it, converged = config.mu0, 0, False
    for it in range(1, config.max_iter + 1):
        if not exact and config.jacobian == "every":
            r, J = fd_jacobian(z, r)
            exact = True
        g = J.T @ r.ravel()
        A = J.T @ J
        dA = np.diag(np.diag(A))
        improved, rel = False, 0.0
        for _ in range(6):
            try:
                dz = -np.linalg.solve(A + mu * dA, g)
            except np.linalg.LinAlgError:
                mu *= 10.0
                continue
            rn = res_of((th0 + (z + dz) * S)[None])[0]
            cn = cost_of(rn)
            if config.jacobian == "broyden":
                J = J + np.outer(rn.ravel() - r.ravel() - J @ dz, dz) / float(dz @ dz)
                exact = False
            if cn < c:
                improved = True
                rel = (c - cn) / c
                z, c, r = z + dz, cn, rn
                exact = False
                mu = max(mu / 3.0, 1e-6)
                break
            mu *= 4.0
        if not improved or rel < config.rtol:
            converged = True
            break
    return z, r, J, c, exact, it, converged


@dataclass(frozen=True)
class OEFit:
    """Result of :func:`refine`: the model, the refined names, values, sandwich covariance, costs.

    ``cost0`` and ``cost``: the criterion at the start and at the end, both under the final Huber weights
    (``OEConfig.robust``), so that ``cost < cost0`` says the refinement lowered what it minimised.
    """

    model: mmg.MmgModel
    names: tuple[str, ...]
    theta: np.ndarray
    cov: np.ndarray
    cost0: float
    cost: float
    iterations: int
    converged: bool
    horizons: int


def refine(model: mmg.MmgModel, names: Sequence[str], trials: Sequence[Trial], se0: Mapping[str, float] | None = None,
           config: OEConfig = OEConfig(), H: Horizons | None = None, compiled: bool = True) -> OEFit:
    """Levenberg–Marquardt on the restarted-horizon output error from ``model``'s values of ``names``.

    Parameters
    ----------
    model : MmgModel
        The starting (regression) model; coefficients outside ``names`` stay fixed.
    names : sequence of str
        Coefficients to refine (those matching ``config.exclude_prefixes`` are skipped).
    trials : sequence of Trial
        The TRAINING runs.
    se0 : mapping, optional
        Standard errors of the starting values, used in the scaling ``S``.
    H : Horizons, optional
        :func:`stack_horizons` of ``trials`` if the caller has it.
    compiled : bool
        Simulate with the compiled force model (:func:`simulate`); False: the reference integration
        (the same numbers to round-off, ``tests/methods/mmg/test_output_error_compiled.py``).
    """
    names = tuple(c for c in names if not c.startswith(config.exclude_prefixes))
    H = stack_horizons(trials, config.horizon, config.decimate, config.stride) if H is None else H
    if config.run_weighting == "per-run":
        _, inv, cnt = np.unique(H.run, return_inverse=True, return_counts=True)
        wh = np.sqrt(H.count / (cnt.size * cnt[inv]))          # mean weight 1 per horizon
    elif config.run_weighting == "pooled":
        wh = np.ones(H.count)
    else:
        raise InputError(f"unknown run_weighting '{config.run_weighting}' (pooled, per-run)")
    wbase = wh[None, :, None, None]
    wts = {"w": wbase}
    th0 = np.array([model.coef[c] for c in names], float)
    se = np.array([float((se0 or {}).get(c, 0.0)) for c in names])
    S = np.maximum(np.abs(th0), np.nan_to_num(se))
    S = np.where(S > 0, S, 1e-6)
    p = len(names)

    def cost_of(r):
        return float(np.sum(r * r))

    def res_of(values):
        return residuals(simulate(model, names, values, H, compiled), H) * wts["w"]

    def fd_jacobian(z, r_at_z=None):
        if compiled and r_at_z is not None:
            # each row's prediction does not depend on the batch it is in: the nominal residuals at z are
            # those of the accepted step, as recomputing them would give, bit for bit
            R = np.concatenate([r_at_z[None], res_of(th0 + (z + config.fd_step * np.eye(p)) * S)])
        else:
            R = res_of(th0 + np.vstack([z, z + config.fd_step * np.eye(p)]) * S)
        return R[0], ((R[1:] - R[0][None]) / config.fd_step).reshape(p, -1).T     # (B, L, 3), (N, p)

    if config.jacobian not in ("every", "broyden"):
        raise InputError(f"unknown jacobian '{config.jacobian}' (every, broyden)")
    if config.robust is not None and not config.robust > 0:
        raise InputError(f"robust must be a positive multiple of the median horizon error, not {config.robust}")
    z = np.zeros(p)
    r, J = fd_jacobian(z)
    exact = True                               # J is the finite-difference Jacobian at z
    c0 = c = cost_of(r)
    it_total, converged = 0, False
    for pass_ in range(1 + (config.robust_passes if config.robust is not None else 0)):
        if pass_:
            if not exact:
                r, J = fd_jacobian(z, r)
                exact = True
            # the weights are fixed within a pass and positive: the residuals and the Jacobian at z under the
            # new weights are the old ones rescaled per horizon (no new simulation)
            w_old = wts["w"][0]
            wts["w"] = wbase * np.sqrt(huber_weights(r / w_old, H, config.robust))[None, :, None, None]
            ratio = wts["w"][0] / w_old                                   # (B, 1, 1)
            r = r * ratio
            J = J * np.broadcast_to(ratio, r.shape).reshape(-1, 1)
            c = cost_of(r)
        z, r, J, c, exact, it, converged = _levenberg_marquardt(z, r, J, c, exact, fd_jacobian, res_of, th0, S,
                                                                cost_of, config)
        it_total += it
    it = it_total
    if config.robust is not None:
        c0 = cost_of(res_of(th0[None])[0])       # the start under the final weights: the same objective as c
    if not exact:
        r, J = fd_jacobian(z, r)
    # sandwich covariance (clusters = horizons, or whole runs where the horizons overlap) with the
    # finite-difference Jacobian at the final point
    Jh = J.T.reshape(p, H.count, -1)                                       # (p, B, n_h)
    rh = r.reshape(H.count, -1)
    A = np.einsum("pbn,qbn->pq", Jh, Jh)
    cl = cluster_index(H, config)
    G = np.zeros((int(cl.max()) + 1, p))
    np.add.at(G, cl, np.einsum("pbn,bn->bp", Jh, rh))                     # score of each cluster
    clusters = G.shape[0]
    try:
        Ai = np.linalg.inv(A)
        cov_z = Ai @ (G.T @ G) @ Ai
        cov_z = 0.5 * (cov_z + cov_z.T)
    except np.linalg.LinAlgError:
        cov_z = np.full((p, p), np.nan)
    if clusters <= p:                # the sandwich's rank is at most the number of clusters
        cov_z = np.full((p, p), np.nan)
    theta = th0 + z * S
    cov = cov_z * np.outer(S, S)
    out = model.with_coef(dict(zip(names, theta)))
    return OEFit(model=out, names=names, theta=theta, cov=cov, cost0=c0, cost=c, iterations=it,
                 converged=converged, horizons=H.count)


def refinable(f, config: OEConfig = OEConfig()) -> tuple[str, ...]:
    """The free coefficients of the fit ``f`` that :func:`refine` refines (``config.exclude_prefixes`` left out)."""
    return tuple(c for m in mmg.MODES for c in f.free.get(m, ()) if not c.startswith(config.exclude_prefixes))


def refined_fit(f, trials: Sequence[Trial], config: OEConfig = OEConfig(), H: Horizons | None = None,
                compiled: bool = True):
    """An :class:`~shipid.methods.mmg.estimator.MmgFit` with its free coefficients refined by :func:`refine`.

    The refined coefficients' ``theta``, ``se`` and covariance block in each mode's fit
    are replaced by the output-error values (cross-mode covariances are not kept, as in
    the regression's per-mode blocks); the rest keep the regression's.
    """
    names = [c for m in mmg.MODES for c in f.free.get(m, ())]
    se0 = {c: float(f.fits[m].se[f.free[m].index(c)]) for m in mmg.MODES for c in f.free.get(m, ())}
    oe = refine(f.model, names, trials, se0, config, H=H, compiled=compiled)
    fits = dict(f.fits)
    for m in mmg.MODES:
        if m not in fits:
            continue
        ft = fits[m]
        th, se, cv = ft.theta.copy(), ft.se.copy(), ft.cov_theta.copy()
        idx = [(f.free[m].index(c), oe.names.index(c)) for c in f.free[m] if c in oe.names]
        for i, j in idx:
            th[i] = oe.theta[j]
        ii = [i for i, _ in idx]
        jj = [j for _, j in idx]
        if ii:
            cv[np.ix_(ii, range(len(th)))] = 0.0
            cv[np.ix_(range(len(th)), ii)] = 0.0
            cv[np.ix_(ii, ii)] = oe.cov[np.ix_(jj, jj)]
            se = np.sqrt(np.where(np.diag(cv) >= 0, np.diag(cv), np.nan))
        fits[m] = replace(ft, theta=th, se=se, cov_theta=cv)
    return replace(f, model=oe.model.with_coef({}, name=f.model.name), fits=fits), oe


__all__ = ["ROBUST_K", "LEAST_SQUARES", "OEConfig", "OEFit", "Horizons", "stack_horizons", "cluster_index",
           "simulate", "residuals", "horizon_errors", "huber_weights", "refine", "refinable", "refined_fit"]
