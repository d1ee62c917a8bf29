"""Frequency-domain (Whittle) maximum-likelihood refinement of the mass / CM estimate (Linder et al. 2015).

The same model, parameterisation, start, search and failure rules as :mod:`shipid.methods.masscm.pem` (beyond the
paper), with the exact time-domain likelihood replaced by Whittle's frequency-domain one, so that an iteration
costs the same whatever the record length.

**Data.** Per dataset the normalised DFTs ``Y_j = sum_k y_k z_j^-k / sqrt(N)`` of ``y = [p, a_s, r]`` and ``D_j`` of
the rudder are formed once, at ``z_j = exp(i w_j)``, ``w_j = 2 pi j / N``, ``j = 1 .. (N - 1) // 2`` (the DC bin,
which only the biases explain, and the Nyquist bin are left out, so the biases drop out of the likelihood).

**Rudder path, exactly.** With the ship at rest at ``k = 0`` and the first-order hold ``x+ = Ad x + B0 d_k + B1
d_{k+1}`` (``d_N = d_{N-1}``, as :func:`~shipid.methods.masscm.pem` uses it), summing over one period of ``z_j``
gives the exact DFT of the rudder response

    M_j = G_u(z_j) D_j + z_j C (z_j I - Ad)^-1 c / sqrt(N),   G_u(z) = C (zI - Ad)^-1 (B0 + z B1) + D,
    c = B1 (d_{N-1} - d_0) - x_N,

``x_N`` the state after the last sample, from the recursion over the last ``L`` samples only (``L`` where
``rho(Ad)^L < 1e-12``: the ship's memory, not the record length). The residual is ``E_j = A(z_j) Z_j`` with
``Z_j = [Y_j, D_j, 1/sqrt(N)]`` and ``A = [I_3, -G_u, -z C (zI - Ad)^-1 c]`` (3 x 5).

**Bands.** Over a band of adjacent bins the noise spectrum ``S(w) = T T^H + R`` (``T(z) = H (zI - F)^-1 G + J`` of
:func:`~shipid.methods.masscm.crlb_kf.noise_matrices`) is held at its value at the band's mean frequency ``w_b``
and ``A`` is taken linear in frequency, ``A(w_j) = A_b + (w_j - w_b) A'_b`` (``A'`` the exact derivative, the
profiled noise transient below held); then, with ``At_b = [A_b, A'_b]`` (3 x 10) and the band's summed moments
``Mt_b = sum_j Zt_j Zt_j^H`` of ``Zt_j = [Z_j, (w_j - w_b) Z_j]`` (10 x 10), formed once,

    sum_{j in b} E_j^H W E_j = tr(W At_b Mt_b At_b^H),    -l = sum_b [ n_b log det S_b + tr(S_b^-1 At_b Mt_b At_b^H) ],

exact for the data part given the band-linear model, and plain Whittle at one bin per band (``exact=True``); the
linear term of ``log det S`` vanishes by the choice of ``w_b``. Band edges (:func:`band_index`): a warped frequency
``u(f)`` grows by ``1 / band_rel`` per unit of ``log f`` and by ``1 / band_tol`` per unit change of the current
model's curves (``log |G_u|``, the phase of ``G_u`` and ``log S_ii`` of the three channels) on a fixed grid of
:data:`GRID` log-spaced frequencies; a band is the bins with the same ``floor(u)``, so bands are narrow where the
model's transfer or spectrum changes quickly (the roll resonance, the wave peak), of constant relative width
elsewhere, and their number is bounded by the model's curves, not the record length. They are designed on the
start model and again on the wave start (the likelihood-ratio test of the wave structure compares both structures
on the second set). Defaults ``band_tol = band_rel = 0.1``: the estimates are then within a small fraction of a
standard error of one bin per band, and the banding error stays below what decides the wave structure with
sensor noise alone (how they were chosen: docs/validation/mass-cm.md).

**Noise-state transient.** The noise states do not start stationary (the simulator starts waves and ship at rest);
their DFT carries ``z H (zI - F)^-1 (s_0 - s_N) / sqrt(N)`` (as the rudder path's), large at low frequency where the
slow sway and yaw poles amplify it and the wave spectrum has its zero. Its real 6-vector is profiled out in closed
form (generalised least squares over the bands, :func:`~shipid.methods.masscm.whittle_kernels.transient_normal`);
ignored, it moves the likelihood's peak far from pem's. The model without waves gets the same over the ship states
(an initial state not at rest), so that the likelihood-ratio test of the wave structure compares like with like
(with the transient in the wave model only, the wave structure is chosen with sensor noise alone). The Ljung-Box
residuals of the model without waves leave this transient out (it decays within the ship's memory).

**Search, errors, failure.** Fisher scoring with Levenberg damping as :mod:`~shipid.methods.masscm.pem`: the
Whittle expected information ``sum_b 2 Re tr(dAt_a^H W dAt_b Mt_b) + n_b tr(W dS_a W dS_b)`` (``W = S_b^-1``;
``dA`` has no data columns, so the first part is deterministic), derivatives by forward differences; standard
errors from its inverse at the optimum (asymptotically the exact information's), ``rho`` by the delta method.
A model without waves is checked for white residuals (Ljung-Box, as pem's ``whiteness_reason``, on the time-domain
residual obtained by the inverse DFT of ``E_j`` at every bin, once).

Measured figures, with the commands that regenerate them: ``docs/validation/mass-cm.md``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from shipid.numerics.linalg import one_blas_thread
from shipid.methods.masscm.crlb_kf import continuous_model, foh, noise_from_ship
from shipid.methods.masscm.whittle_kernels import noise_spectrum, ship_columns, transient_normal
from shipid.methods.masscm.pem import (FREE, PEMFit, PEMOptions, WAVE_LR, WHITE_LAGS, WHITE_P, finish,
                                      ljung_box_reason, model_vector, wave_log_sigma)
from shipid.methods.masscm.pem import physical_reason as _pem_physical
from shipid.methods.masscm.refine_start import initial_local
from shipid.methods.masscm.scoring import fisher_scoring, perturbed
from shipid.models.roll_reduced import KnownParams

N_TH = len(FREE)
I_M, I_ZM = FREE.index("m"), FREE.index("zm_bar")
MEAN_LOCAL = list(range(12))
NOISE_LOCAL = list(range(12, 18))
GRID = 4000       # frequencies of the band design grid
RESIDUAL_CHUNK = 4096  # bins per model evaluation in time_residuals
MODEL_COLS = [3, 4, 8, 9]   # the columns of At that depend on the parameters (the rest: [I, 0])
TAIL_TOL = 1e-12  # x_N from the last L samples, rho(Ad)^L < TAIL_TOL
_Z42, _Z32, _Z22, _Z6 = np.zeros((4, 2)), np.zeros((3, 2)), np.zeros((2, 2)), np.zeros(6)   # no waves


@dataclass(frozen=True)
class WhittleOptions(PEMOptions):
    """:class:`~shipid.methods.masscm.pem.PEMOptions` and the band design (see the module docstring).

    ``band_tol``: change of the model's curves per band; ``band_rel``: widest band relative to its frequency;
    ``exact``: one bin per band (exact Whittle, cost linear in N; for checks).
    """

    band_tol: float = 0.1
    band_rel: float = 0.1
    exact: bool = False


@njit(cache=True)
def _final_state(delta, Ad, b0, b1, k0):
    """State after the last sample of ``x+ = Ad x + b0 d_k + b1 d_{k+1}`` from rest at ``k0`` (``d_N = d_{N-1}``);
    each entry ``b0_i d_k + b1_i d_{k+1} + sum_j Ad_ij x_j``, summed in that order."""
    n = delta.shape[0]
    x0 = x1 = x2 = x3 = 0.0
    a00, a01, a02, a03 = Ad[0, 0], Ad[0, 1], Ad[0, 2], Ad[0, 3]
    a10, a11, a12, a13 = Ad[1, 0], Ad[1, 1], Ad[1, 2], Ad[1, 3]
    a20, a21, a22, a23 = Ad[2, 0], Ad[2, 1], Ad[2, 2], Ad[2, 3]
    a30, a31, a32, a33 = Ad[3, 0], Ad[3, 1], Ad[3, 2], Ad[3, 3]
    for k in range(k0, n):
        dk = delta[k]
        dnext = delta[k + 1] if k + 1 < n else dk
        y0 = (((b0[0] * dk + b1[0] * dnext) + a00 * x0) + a01 * x1) + a02 * x2 + a03 * x3
        y1 = (((b0[1] * dk + b1[1] * dnext) + a10 * x0) + a11 * x1) + a12 * x2 + a13 * x3
        y2 = (((b0[2] * dk + b1[2] * dnext) + a20 * x0) + a21 * x1) + a22 * x2 + a23 * x3
        y3 = (((b0[3] * dk + b1[3] * dnext) + a30 * x0) + a31 * x1) + a32 * x2 + a33 * x3
        x0, x1, x2, x3 = y0, y1, y2, y3
    return np.array([x0, x1, x2, x3])


def band_index(f_bins, f_grid, curves, tol, rel):
    """Band number of each bin frequency: ``floor(u(f))`` of the warped frequency of the module docstring.

    ``curves`` (len(f_grid), m) real; returns consecutive integers from 0.
    """
    dc = np.max(np.abs(np.diff(curves, axis=0)), axis=1) / tol
    dl = np.diff(np.log(f_grid)) / rel
    u = np.concatenate([[0.0], np.cumsum(dc + dl)])
    b = np.floor(np.interp(f_bins, f_grid, u)).astype(np.int64)
    return np.unique(b, return_inverse=True)[1]


class _FSet:
    """One dataset: DFTs, band sums, and the band matrices ``A_b, S_b`` of a parameter vector."""

    def __init__(self, cond, trial, known, z_f):
        self.cond, self.known, self.z_f = cond, known, z_f
        self.y = np.ascontiguousarray(np.column_stack([trial["p"], trial["a_s"], trial["r"]]), dtype=float)
        self.delta = np.ascontiguousarray(trial["delta"], dtype=float)
        self.T = float(trial.dt)
        self.n = n = self.y.shape[0]
        self.w = 2 * np.pi * np.arange(1, (n - 1) // 2 + 1) / n        # rad / sample
        self._ship_key = self._ship_val = None

    def transform(self):
        """The DFTs ``Z_j`` (K, 5); the time-domain outputs are not needed after this (and are released)."""
        K, sq = self.w.size, np.sqrt(self.n)
        self.Z = Z = np.empty((K, 5), dtype=complex)          # filled in place: no stacked copies
        np.divide(np.fft.rfft(self.y, axis=0)[1:K + 1], sq, out=Z[:, :3])
        self.y = None
        np.divide(np.fft.rfft(self.delta)[1:K + 1], sq, out=Z[:, 3])
        Z[:, 4] = 1.0 / sq

    def set_bands(self, idx):
        """Band sums for the band number ``idx`` of each bin."""
        starts = np.flatnonzero(np.r_[True, np.diff(idx) != 0])
        self.nb = np.diff(np.r_[starts, idx.size]).astype(float)
        self.wb = np.add.reduceat(self.w, starts) / self.nb
        dw = self.w - self.wb[idx]
        dwk = [dw ** k for k in range(3)]
        P = np.empty((3, starts.size, 5, 5), dtype=complex)   # P_k = sum_j (w_j - w_b)^k Z_j Z_j^H
        for a in range(5):                                      # pair by pair: no (K, 5, 5) transient
            for b in range(a, 5):
                zz = self.Z[:, a] * np.conj(self.Z[:, b])
                for k in range(3):
                    P[k, :, a, b] = np.add.reduceat(zz * dwk[k], starts)
                    P[k, :, b, a] = np.conj(P[k, :, a, b])
        M = np.block([[P[0], P[1]], [P[1], P[2]]])             # moments of Zt = [Z, (w - w_b) Z]
        self.M = M
        self.zb = np.exp(1j * self.wb)
        self._ship_key = self._ship_val = None

    def design_bands(self, theta, loc, waves, opts: WhittleOptions):
        if opts.exact:
            return self.set_bands(np.arange(self.w.size))
        f_grid = np.geomspace(self.w[0], self.w[-1], GRID)
        m = self.matrices(theta, loc, waves, np.exp(1j * f_grid), with_tail=False)
        if m is None:                               # no admissible model: constant relative width only
            curves = np.zeros((GRID, 1))
        else:
            A, S = m
            G = -A[:, :, 3]
            ph = np.concatenate([np.zeros((1, 3)), np.cumsum(np.angle(G[1:] / G[:-1]), axis=0)])
            curves = np.column_stack([np.log(np.abs(G) + 1e-300), ph,
                                      np.log(np.real(np.diagonal(S, axis1=1, axis2=2)))])
        self.set_bands(band_index(self.w, f_grid, curves, opts.band_tol, opts.band_rel))

    def matrices(self, theta, loc, waves, z=None, with_tail=True):
        """``(At (nz, 3, 10), S (nz, 3, 3))`` at ``z`` (default: the band centres, with the profiled noise transient)
        or ``None`` where the model is not admissible (unstable ship or wave filter).

        The ship part (everything that depends on ``theta`` and the sway / yaw rows ``loc[:12]`` only) of the last
        ship evaluated is kept (:meth:`_ship`), so a change of the wave or sensor-noise entries alone (their
        derivative columns, the noise-only stages) recomputes just the noise model. The per-band loops are the
        compiled kernels of :mod:`~shipid.methods.masscm.whittle_kernels`."""
        band_centres = z is None
        z = self.zb if band_centres else z
        p = model_vector(theta, loc)
        sh = self._ship(theta, loc, z, band_centres, with_tail)
        if sh is None:
            return None
        ship, rho, A0, CR = sh
        try:
            _, (F, G, H, J, R) = noise_from_ship(ship, p, self.T, waves)
            if F.shape[0] and np.max(np.abs(np.linalg.eigvals(F))) >= 1.0:
                return None
        except (ValueError, np.linalg.LinAlgError):
            return None
        A = A0.copy()
        if F.shape[0]:
            S, Gam = noise_spectrum(z, CR, np.ascontiguousarray(F[:4, 4:]), np.ascontiguousarray(H[:, 4:]),
                                    np.ascontiguousarray(F[4:, 4:]), G, J, R, True)
        else:
            S, Gam = noise_spectrum(z, CR, _Z42, _Z32, _Z22, _Z6, J, R, False)
        if not np.all(np.isfinite(S)):
            return None
        if band_centres:          # transient of the noise states (with waves) or of the ship states (without)
            try:
                Hm, b = transient_normal(A, S, Gam, self.M)
                A[:, :, 4] -= Gam @ np.linalg.solve(0.5 * (Hm + Hm.T), b)
            except np.linalg.LinAlgError:
                return None
        return A, S

    def _ship(self, theta, loc, z, band_centres, with_tail):
        """``(ship matrices, rho(Ad), At without the noise transient, C (zI - Ad)^-1)`` or ``None``; the last one
        evaluated is kept, keyed on ``theta``, ``loc[:12]`` and the frequencies."""
        key = (theta.tobytes(), np.asarray(loc[:12]).tobytes(), band_centres, with_tail,
               None if band_centres else z.tobytes())
        if self._ship_key == key:
            return self._ship_val
        val = self._ship_eval(theta, loc, z, with_tail)
        self._ship_key, self._ship_val = key, val
        return val

    def _ship_eval(self, theta, loc, z, with_tail):
        p = model_vector(theta, loc)
        try:
            Ac, Bc, C, D = continuous_model(p[:8], p[8:14], p[14:20], self.known, self.z_f, self.cond)
            Ad, B0, B1 = foh(Ac, Bc, self.T)
            if not np.all(np.isfinite(Ad)):
                return None
            rho = np.max(np.abs(np.linalg.eigvals(Ad)))
            if rho >= 1.0:
                return None
        except (ValueError, np.linalg.LinAlgError):
            return None
        b0, b1 = B0[:, 0], B1[:, 0]
        if with_tail:
            L = self.n if rho <= 0 else int(min(self.n, np.ceil(np.log(TAIL_TOL) / np.log(rho)) + 1))
            xN = _final_state(self.delta, np.ascontiguousarray(Ad), np.ascontiguousarray(b0),
                              np.ascontiguousarray(b1), self.n - L)
            c = b1 * (self.delta[-1] - self.delta[0]) - xN
        else:
            c = np.zeros(4)
        A, CR = ship_columns(np.ascontiguousarray(z), np.ascontiguousarray(Ad), np.ascontiguousarray(b0),
                             np.ascontiguousarray(b1), np.ascontiguousarray(C), np.ascontiguousarray(D[:, 0]), c)
        if not np.all(np.isfinite(A)):
            return None
        return (Ad, B0, B1, C, D), rho, A, CR

    def residual_periodogram(self, A):
        """``At_b Mt_b At_b^H`` (nb, 3, 3): the band-summed residual cross-periodogram."""
        return (A @ self.M) @ np.conj(np.swapaxes(A, 1, 2))

    def nll(self, A, S):
        det = np.real(det3(S))
        if np.any(det <= 0):
            return np.inf
        RM = self.residual_periodogram(A)
        return float(self.nb @ np.log(det) + np.real(np.sum(inv_herm3(S) * np.swapaxes(RM, 1, 2))))


def det3(S):
    """Determinants of a stack of 3 x 3 matrices (cofactor expansion)."""
    return (S[:, 0, 0] * (S[:, 1, 1] * S[:, 2, 2] - S[:, 1, 2] * S[:, 2, 1])
            - S[:, 0, 1] * (S[:, 1, 0] * S[:, 2, 2] - S[:, 1, 2] * S[:, 2, 0])
            + S[:, 0, 2] * (S[:, 1, 0] * S[:, 2, 1] - S[:, 1, 1] * S[:, 2, 0]))


def inv_herm3(S):
    """Inverses of a stack of 3 x 3 matrices by the adjugate (the spectra here are well conditioned: they
    contain the sensor-noise floor ``R``)."""
    adj = np.empty_like(S)
    for i in range(3):
        for j in range(3):
            r = [k for k in range(3) if k != j]
            c = [k for k in range(3) if k != i]
            adj[:, i, j] = (-1) ** (i + j) * (S[:, r[0], c[0]] * S[:, r[1], c[1]] - S[:, r[0], c[1]] * S[:, r[1], c[0]])
    return adj / det3(S)[:, None, None]


def _objective(sets, theta, locs, waves):
    tot = 0.0
    for s, loc in zip(sets, locs):
        m = s.matrices(theta, loc, waves)
        if m is None:
            return np.inf
        tot += s.nll(*m)
    return tot if np.isfinite(tot) else np.inf


def _free_local(waves):
    if waves:
        return list(range(18))
    return [i for i in range(18) if i not in (5, 11, 12, 13, 14)]


def score_information(sets, theta, locs, waves, th_idx, fl, rel_step=1e-6):
    """Score of the Whittle log-likelihood and its expected information over ``theta[th_idx]`` and ``loc[fl]``.

    ``-dl/da = sum_b n_b tr(W dS_a) - tr(W dS_a W R_b) + 2 Re tr(W dA_a M_b A_b^H)`` (``R_b = A_b M_b A_b^H``),
    information as in the module docstring; forward differences of ``A_b, S_b`` (a parameter whose perturbation
    is not admissible either side is held: zero row).
    """
    nloc = len(fl)
    P = len(th_idx) + nloc * len(sets)
    g, info = np.zeros(P), np.zeros((P, P))
    for d, (s, loc) in enumerate(zip(sets, locs)):
        A, S = s.matrices(theta, loc, waves)
        W = inv_herm3(S)
        cols = [("t", i) for i in th_idx] + [("l", i) for i in fl]
        gi = list(range(len(th_idx))) + [len(th_idx) + d * nloc + j for j in range(nloc)]
        nc = len(cols)
        dA = np.zeros((nc, A.shape[0], 3, len(MODEL_COLS)), dtype=complex)     # the other columns of At are fixed
        dS = np.zeros((nc,) + S.shape, dtype=complex)
        order = sorted(range(nc), key=lambda c: cols[c] not in [("l", i) for i in NOISE_LOCAL])
        A_model = A[:, :, MODEL_COLS]
        for c in order:           # noise-only columns first: they reuse the base point's ship (_FSet._ship)
            r, h = perturbed(lambda t, l: s.matrices(t, l, waves), theta, loc, *cols[c], rel_step)
            if r is None:
                continue
            dA[c] = (r[0][:, :, MODEL_COLS] - A_model) / h
            dS[c] = (r[1] - S) / h
        RM = s.residual_periodogram(A)
        nb = dA.shape[1]
        V = W[None] @ dS                                                          # W dS_a
        X = np.swapaxes((s.M @ np.conj(np.swapaxes(A, 1, 2))) @ W, 1, 2)          # (M A^H W)^T
        grad = (np.trace(V, axis1=2, axis2=3) @ s.nb
                - np.sum(V * np.swapaxes(W @ RM, 1, 2)[None], axis=(1, 2, 3))
                + 2 * dA.reshape(nc, -1) @ np.ascontiguousarray(X[:, :, MODEL_COLS]).reshape(-1))
        g[gi] += -np.real(grad)
        WdAM = (W[None] @ dA) @ s.M[:, MODEL_COLS][:, :, MODEL_COLS][None]
        Imean = 2 * np.real(np.conj(dA.reshape(nc, -1)) @ WdAM.reshape(nc, -1).T)
        Vt = np.swapaxes(V, 2, 3).reshape(nc, -1)
        Icov = np.real((V.reshape(nc, -1) * np.repeat(s.nb, 9)[None]) @ Vt.T)
        info[np.ix_(gi, gi)] += Imean + Icov
    return g, 0.5 * (info + info.T)


def _scoring(sets, theta, locs, waves, opts: PEMOptions, fix_theta=False, only=None):
    """:func:`~shipid.methods.masscm.scoring.fisher_scoring` of the Whittle likelihood (as pem's); theta, locs,
    info, loglik, its, conv."""
    return fisher_scoring(lambda t, l: _objective(sets, t, l, waves),
                          lambda t, l, ti, fl: score_information(sets, t, l, waves, ti, fl, opts.rel_step),
                          theta, locs, _free_local(waves), N_TH, opts.max_iter, opts.tol, fix_theta=fix_theta,
                          only=only)


def _white_variances(s: _FSet, theta, loc):
    """``loc`` with the sensor variances at their Whittle maximum given the rest (model without waves)."""
    loc = loc.copy()
    m = s.matrices(theta, loc, False)
    if m is not None:
        RM = s.residual_periodogram(m[0])
        loc[15:18] = np.log(np.maximum(np.real(np.einsum("kii->i", RM)) / s.nb.sum(), 1e-300))
    return loc


def _wave_start(s: _FSet, theta, loc, known: KnownParams) -> np.ndarray:
    """Wave filter start from the no-wave fit's residual roll-rate band periodogram (peak, variance)."""
    m = s.matrices(theta, loc, False)
    loc = loc.copy()
    if m is None:
        return loc
    RM = np.real(np.einsum("kii->ki", s.residual_periodogram(m[0])))
    ntot = s.nb.sum()
    loc[15:18] = np.log(np.maximum((np.abs(2 * np.sin(s.wb / 2)) ** 4) @ RM / (6 * ntot), 1e-12))
    loc[12:15] = np.log([s.wb[int(np.argmax(RM[:, 0] / s.nb))] / s.T, 0.1, 1.0])
    loc[14] = wave_log_sigma(s, theta, loc, known, RM[:, 0].sum() / ntot)
    return loc


def time_residuals(s: _FSet, theta, loc) -> np.ndarray:
    """Time-domain residual ``y - mu`` (N, 3), mean removed: inverse DFT of ``E_j`` at every bin (once; the model
    evaluated :data:`RESIDUAL_CHUNK` bins at a time, so its memory does not grow with the record length)."""
    full = np.zeros((s.n // 2 + 1, 3), dtype=complex)
    for j0 in range(0, s.w.size, RESIDUAL_CHUNK):
        j1 = min(j0 + RESIDUAL_CHUNK, s.w.size)
        m = s.matrices(theta, loc, False, z=np.exp(1j * s.w[j0:j1]))
        full[1 + j0:1 + j1] = np.einsum("kij,kj->ki", m[0][:, :, :5], s.Z[j0:j1]) * np.sqrt(s.n)
    return np.fft.irfft(full, n=s.n, axis=0)


def whiteness_reason(sets, theta, locs, lags: int = WHITE_LAGS, p: float = WHITE_P) -> str:
    """Ljung-Box test (:func:`~shipid.methods.masscm.pem.ljung_box_reason`) of the residuals of the model without
    waves (:func:`time_residuals`, mean zero); empty when white."""
    return ljung_box_reason(sets, locs, lambda s, loc: time_residuals(s, theta, loc), "residuals", lags, p)


def physical_reason(theta, sets, locs, waves) -> str:
    """Empty when the optimum is physical, else why not: pem's ``physical_reason`` with the Whittle likelihood."""
    return _pem_physical(theta, sets, locs, waves, objective=_objective)


def refine(datasets, known: KnownParams, z_f: float, theta_free,
           options: WhittleOptions = WhittleOptions()) -> PEMFit:
    """Whittle maximum-likelihood refinement of ``theta_free`` (names :data:`FREE`); same contract as
    :func:`shipid.methods.masscm.pem.refine` (a :class:`~shipid.methods.masscm.pem.PEMFit`)."""
    theta = np.asarray(theta_free, dtype=float).copy()
    o = options
    with np.errstate(all="ignore"), one_blas_thread():
        sets, locs = [], []
        for c, tr in datasets:    # one dataset at a time: the start in the time domain, then the DFTs (less memory)
            s = _FSet(c, tr, known, z_f)
            sets.append(s)
            one_bin = np.exp(1j * s.w[:1])      # a stable ship: the model admissible at one frequency
            locs.append(initial_local(s, theta, known,
                                      lambda l, s=s, z=one_bin: s.matrices(theta, l, False, z=z, with_tail=False)
                                      is not None))
            s.transform()
            s.design_bands(theta, locs[-1], False, o)
        quick = PEMOptions(max_iter=o.start_iter, tol=o.tol, rel_step=o.rel_step)
        _, lo0, _, _, _, _ = _scoring(sets, theta, locs, False, quick, fix_theta=True, only=MEAN_LOCAL)
        lo0 = [_white_variances(s, theta, l) for s, l in zip(sets, lo0)]
        nw = o if o.waves == "no" else PEMOptions(max_iter=o.nowave_iter, tol=o.tol, rel_step=o.rel_step)
        fit = _scoring(sets, theta, lo0, False, nw) + (False,)
        th0, lo0 = fit[0], fit[1]
        if o.waves != "no" and fit[2] is not None:
            lw = [_wave_start(s, th0, l, known) for s, l in zip(sets, lo0)]
            for s, l in zip(sets, lw):            # bands on the wave start; both structures compared on them
                s.design_bands(th0, l, True, o)
            ll0 = -_objective(sets, th0, lo0, False)
            fit = fit[:3] + (ll0,) + fit[4:]
            _, lw, infw, ll1, _, _ = _scoring(sets, th0, lw, True, quick, fix_theta=True, only=NOISE_LOCAL)
            if o.waves == "yes" or (infw is not None and 2 * (ll1 - ll0) > WAVE_LR * len(sets)):
                fw = _scoring(sets, th0, lw, True, o)
                fit = fw[:4] + (fit[4] + fw[4], fw[5], True)
        if not fit[6] and not fit[5] and fit[2] is not None:
            fr = _scoring(sets, fit[0], fit[1], False, o)
            fit = fr[:4] + (fit[4] + fr[4], fr[5], False)
        return finish(fit, sets, known, z_f, physical_reason, whiteness_reason)


__all__ = ["WhittleOptions", "refine", "band_index", "time_residuals", "whiteness_reason", "physical_reason"]
