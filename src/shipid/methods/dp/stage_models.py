"""Trial data and filter models of the DP identification schemes (Fossen, Sagatun & Sørensen 1996, §4.3).

:func:`prepare` converts one trial to the bis system (eqs. 26–28): ``t'' = t / sqrt(L/g)``,
``x'' = x / L``, ``y'' = y / L``; the pitch ratios become the control vector of eq. 5.
Measured are position and heading (eqs. 44–45).

Surge measurement (a reading of eq. 32 for real trials): eq. 32 needs the distance run
along the ship's x axis. It is computed from the position fixes as
``s_k = Σ_j (Δx_j cos ψ̄_j + Δy_j sin ψ̄_j)`` (ψ̄_j the mean measured heading over the step),
which is exact for ``η̇ = J(ψ) ν`` whatever the sway and yaw (``ẋ cos ψ + ẏ sin ψ = u``).

:func:`surge_model` (SI1, eqs. 31–32 in momentum form) and :func:`momentum_model` (SI2/SI3,
eqs. 35–38) are the :class:`~shipid.estimate.ekf_augmented.AugmentedModel` of one trial for the
state-augmented EKF (Table 1, eqs. 17–19). Each is written once as a continuous model
``f(t, x, u, θ)`` with its Jacobians; the discrete map ``f(k, x, u, θ)`` of eq. 15 and its Φ are the
package's one RK4 over the trial's own sample intervals (:func:`~shipid.estimate.ekf_augmented.rk4_map`).
The compiled likelihood kernels of :mod:`shipid.methods.dp.loglik` are tested against these maps.
"""

from __future__ import annotations

import numpy as np

from shipid.io.trial import Trial
from shipid.errors import InputError
from shipid.estimate.ekf_augmented import AugmentedModel, rk4_map
from shipid.models import dp
from shipid.models.thrusters import control_vector

# ---------------------------------------------------------------------------------------------
# Data preparation
# ---------------------------------------------------------------------------------------------
def prepare(trial: Trial, vessel: dp.DPVessel, kind: str, sample_interval: float | None = None) -> dict:
    """Bis time, measurements and inputs of one trial, block-averaged to ``sample_interval`` (s) if faster.

    A trial sampled faster than ``sample_interval`` (by a factor q ≥ 2) is decimated by
    :func:`decimate` (block means, an anti-alias filter whose output noise stays white); the
    returned ``"decimated"`` is then ``(q, dt_in, dt_out)`` in seconds, else None.
    """
    need = ["x", "y", "psi", "p1", "p2", "p3", "p4", "p5", "p6"]
    trial.require(need, method="identify dp")
    b = vessel.bis
    t = trial.t
    if t.size < 10:
        raise InputError(f"too short for identification ({t.size} samples)", file=trial.meta.get("source"))
    tb = b.t_to_bis(t - t[0])
    src = trial.meta.get("source")
    P = trial.stack([f"p{i}" for i in range(1, 7)])
    alpha = trial["alpha6"] if "alpha6" in trial else np.full(t.size, np.pi / 2)
    for j, col in enumerate(list(P.T) + [alpha]):
        bad = np.flatnonzero(~np.isfinite(col))
        if bad.size:  # inputs drive the model: no gaps allowed (measurements may have gaps)
            name = f"p{j + 1}" if j < 6 else "alpha6"
            raise InputError("missing input value (fill or trim the gap first)", file=src, channel=name,
                             row=int(bad[0]) + 1)
    U = np.column_stack([control_vector(P, vessel.p0), alpha])
    x, y, psi = trial["x"], trial["y"], trial["psi"]
    ok = np.isfinite(x) & np.isfinite(y) & np.isfinite(psi)
    if ok.sum() < 10:
        raise InputError(f"too few position/heading fixes ({int(ok.sum())})", file=src)
    idx = np.flatnonzero(ok)
    if kind == "surge":
        # distance run along the heading between consecutive fixes (gaps are bridged):
        # mean of two headings taken across the ±π cut
        pk = psi[idx]
        c = pk[:-1] + 0.5 * np.arctan2(np.sin(pk[1:] - pk[:-1]), np.cos(pk[1:] - pk[:-1]))
        sk = np.concatenate([[0.0], np.cumsum(np.diff(x[idx]) * np.cos(c) + np.diff(y[idx]) * np.sin(c))])
        Z = np.full((t.size, 1), np.nan)
        Z[idx, 0] = sk / b.L
    else:
        Z = np.full((t.size, 3), np.nan)
        Z[idx] = np.column_stack([x[idx] / b.L, y[idx] / b.L, np.unwrap(psi[idx])])
    dec = None
    if sample_interval is not None and t.size > 2:
        q = int(round(sample_interval / float(np.median(np.diff(t)))))
        if q >= 2:
            dt_in = float(np.median(np.diff(t)))
            tb, Z, U = decimate(tb, Z, U, q)
            dec = (q, dt_in, q * dt_in)
            good = np.flatnonzero(np.all(np.isfinite(Z), axis=1))
            if good.size < 10:
                raise InputError(f"too few position/heading fixes after decimation ({good.size})", file=src)
            idx = good
    return {"t": tb, "Z": Z, "U": U, "source": src, "first": int(idx[0]), "decimated": dec}


def decimate(t: np.ndarray, Z: np.ndarray, U: np.ndarray, q: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Non-overlapping block means of q samples: the anti-alias filter and decimation of a fast trial.

    Measurements (eqs. 44–45): each block of q consecutive samples (by time, ``t`` from its first
    sample in steps of q times the median interval) becomes the mean of its fixes, stamped at the
    mean time of those fixes; a block without a fix is missing (NaN). The block mean is a
    low-pass filter (a sinc response, zero at the new sampling rate and its multiples) whose
    output noise is exactly white with variance σ²/q for white sensor noise of variance σ² --
    the filter's measurement model -- while a smooth track is moved only by ``T² z̈ / 24``
    (T the block length; sub-millimetre for a DP vessel at T = 1 s).

    Inputs: the filter holds ``U[k]`` over the step from block time k to k + 1, so the new input
    is the exact time average of the zero-order-held input over that step (from the cumulative
    integral of the held input). The models are linear in ``u1 … u5`` and in the azimuth
    thruster's force direction ``u6 (cos α6, sin α6)`` (eq. 7), so the mean of those is taken and
    turned back into ``(u6, α6)``: the mean thrust of every step is then the true one.

    Parameters
    ----------
    t : ndarray (n,)
        Sample times (any unit; the output has the same).
    Z : ndarray (n, nz)
        Measurements, NaN where missing (a sample counts as a fix when all its channels are finite).
    U : ndarray (n, 7)
        ``[u1 … u6, α6]`` per sample, held until the next sample.
    q : int
        Decimation factor (≥ 2).
    """
    n = t.size
    h = float(np.median(np.diff(t))) * q
    blk = np.floor((t - t[0]) / h + 1e-9).astype(int)
    nb = int(blk[-1]) + 1
    ok = np.all(np.isfinite(Z), axis=1)
    cnt_all = np.bincount(blk, minlength=nb).astype(float)
    cnt = np.bincount(blk[ok], minlength=nb).astype(float)
    tm_all = np.bincount(blk, weights=t, minlength=nb) / np.maximum(cnt_all, 1.0)
    tm_ok = np.bincount(blk[ok], weights=t[ok], minlength=nb) / np.maximum(cnt, 1.0)
    keep = cnt_all > 0
    tb = np.where(cnt > 0, tm_ok, tm_all)[keep]
    Zb = np.full((nb, Z.shape[1]), np.nan)
    for c in range(Z.shape[1]):
        s = np.bincount(blk[ok], weights=Z[ok, c], minlength=nb)
        Zb[cnt > 0, c] = s[cnt > 0] / cnt[cnt > 0]
    Zb = Zb[keep]
    # time averages of the zero-order-held inputs over [tb_k, tb_k+1)
    F = np.column_stack([U[:, :5], U[:, 5] * np.cos(U[:, 6]), U[:, 5] * np.sin(U[:, 6])])
    C = np.vstack([np.zeros((1, F.shape[1])), np.cumsum(F[:-1] * np.diff(t)[:, None], axis=0)])

    def integral(tau):
        i = np.clip(np.searchsorted(t, tau, side="right") - 1, 0, n - 1)
        return C[i] + F[i] * (tau - t[i])[:, None]

    Ci = integral(tb)
    Fm = np.empty((tb.size, F.shape[1]))
    if tb.size > 1:
        Fm[:-1] = (Ci[1:] - Ci[:-1]) / np.diff(tb)[:, None]
    Fm[-1] = F[-1]
    u6 = np.hypot(Fm[:, 5], Fm[:, 6])
    alpha = np.arctan2(Fm[:, 6], Fm[:, 5])
    still = u6 <= 1e-15
    if still.any():  # no azimuth thrust over the step: keep the recorded angle
        alpha[still] = U[np.clip(np.searchsorted(t, tb[still], side="right") - 1, 0, n - 1), 6]
    Ub = np.column_stack([Fm[:, :5], u6, alpha])
    return tb, Zb, Ub


class _RK4Discrete:
    """Discrete f(k, x, u, θ) and Φ of one trial: :func:`rk4_map` of the continuous ``f(t, x, u, θ)``
    over the trial's own (bis) sample intervals, cached."""

    def __init__(self, fc, jc, t: np.ndarray):
        self.fc, self.jc = fc, jc
        self.t = np.asarray(t, dtype=float)
        self.dt = np.diff(self.t)
        self._key = None
        self._val = None

    def _eval(self, k, x, u, th):
        key = (k, x.tobytes(), th.tobytes())
        if key != self._key:
            self._val = rk4_map(self.fc, self.jc, self.t[k], x, u, th, self.dt[k])
            self._key = key
        return self._val

    def f(self, k, x, u, th):
        return self._eval(k, x, u, th)[0]

    def jac(self, k, x, u, th):
        v = self._eval(k, x, u, th)
        return v[1], v[2]


def _wrap_last(z: np.ndarray, zp: np.ndarray) -> np.ndarray:
    d = z - zp
    d[-1] = np.arctan2(np.sin(d[-1]), np.cos(d[-1]))
    return d


def surge_model(vessel: dp.DPVessel, theta_full: np.ndarray, free: tuple[int, ...], t: np.ndarray):
    """Eqs. 31–32 in momentum form; state [h_u, s, b_u]."""
    m11 = vessel.M[0, 0]
    free = list(free)

    def full(th):
        out = theta_full.copy()
        out[free] = th
        return out

    def fc(t, x, u, th):
        """Eqs. 31–32 (momentum form), ``f(t, x, u, θ)``; autonomous."""
        f = full(th)
        return np.array([f[0] * x[0] + f[5] * (u[0] + u[1]) + f[8] * np.cos(u[6]) * u[5] + x[2], x[0] / m11, 0.0])

    def jc(t, x, u, th):
        f = full(th)
        A = np.array([[f[0], 0.0, 1.0], [1.0 / m11, 0.0, 0.0], [0.0, 0.0, 0.0]])
        Bfull = np.zeros((3, 9))
        Bfull[0, 0] = x[0]
        Bfull[0, 5] = u[0] + u[1]
        Bfull[0, 8] = np.cos(u[6]) * u[5]
        return A, Bfull[:, free]

    d = _RK4Discrete(fc, jc, t)
    H = np.array([[0.0, 1.0, 0.0]])
    return AugmentedModel(f=d.f, h=lambda k, x, th: x[1:2], nx=3, ntheta=len(free), f_jac=d.jac,
                          h_jac=lambda k, x, th: (H, np.zeros((1, len(free)))))


def momentum_model(vessel: dp.DPVessel, theta_full: np.ndarray, free: tuple[int, ...], t: np.ndarray,
                    current: bool = True):
    """Eqs. 35–38 (ERRATA readings); state [h, η, b_h] (+ [V_x, V_y] bis with ``current``)."""
    M, Minv, arms = vessel.M, vessel.Minv, vessel.arms
    free = list(free)
    rhs = dp.momentum_current_rhs if current else dp.momentum_rhs
    rjac = dp.momentum_current_jacobian if current else dp.momentum_jacobian
    nx = 11 if current else 9

    cache: dict = {}

    def mats(th):
        key = th.tobytes()
        if key not in cache:
            cache.clear()
            out = theta_full.copy()
            out[free] = th
            cache[key] = dp.matrices_from_theta(out)
        return cache[key]

    def fc(t, x, u, th):
        """Eqs. 35–38, ``f(t, x, u, θ)`` with ``u = [u1 … u6, α6]``; autonomous."""
        A_h, K = mats(th)
        return rhs(x, u[:6], u[6], M, Minv, A_h, K, arms)

    def jc(t, x, u, th):
        A_h, K = mats(th)
        Fx, Ft = rjac(x, u[:6], u[6], M, Minv, A_h, K, arms)
        return Fx, Ft[:, free]

    d = _RK4Discrete(fc, jc, t)
    H = np.zeros((3, nx))
    H[:, 3:6] = np.eye(3)
    return AugmentedModel(f=d.f, h=lambda k, x, th: x[3:6], nx=nx, ntheta=len(free), f_jac=d.jac,
                          h_jac=lambda k, x, th: (H, np.zeros((3, len(free)))), residual=_wrap_last)


__all__ = ["prepare", "decimate", "surge_model", "momentum_model"]
