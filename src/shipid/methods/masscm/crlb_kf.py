"""Cramér–Rao bound of the data-generating model of the mass / CM experiment (Linder et al. 2015).

The data of each dataset ``c`` (nominal, calibration, loaded) are the sampled outputs ``y = [p, a_s, r]`` of the
linear ship (11) driven by the measured rudder ``delta`` (a known, deterministic input) and the wave roll moment
``tau``, plus white sensor noise and constant biases, exactly as :func:`shipid.models.roll_sim.simulate_condition`
makes them:

* ship, states ``x = [phi, v, p, r]`` (the yaw angle does not feed back in (11)), ``x' = A_c x + B_c [delta, tau]``,
  sampled exactly with both inputs piecewise linear between samples (first-order hold, as the simulator);
* outputs ``p = x_3``, ``r = x_4`` and ``a_s = z_s p' + g phi - v' - U r`` (8) with ``p'``, ``v'`` from the model
  at the sample instant (so ``a_s`` has a direct feedthrough of ``delta`` and ``tau``);
* wave moment ``tau_k = sigma_c W(q) e_k``, ``W`` the Tustin-discretised ``2 zeta w s / (s^2 + 2 zeta w s + w^2)``
  of :func:`shipid.models.roll_sim.wave_moment`, ``e`` unit white; ``sigma_c`` makes the stationary roll std of
  dataset ``c`` equal to ``wave_roll_deg`` (the simulator scales each realisation to it);
* sensor noise ``N(0, diag(gyro^2, acc^2, gyro^2))`` and a bias per channel.

**Parameterisation.** The roll row of the model is (23) in the unknowns ``theta`` of (30) with ``z_f`` known
(``k, A_x, d, K_r, K_vdot, K_delta, m, zm_bar``); with ``a_s`` eliminated it reads

    A1 p' = -(k - K_vdot g + B g) phi - d p + B v' + (K_r + B U) r + K_delta delta + tau,   B = K_vdot + M z_g + m z_m

(``A1`` of (16)), which is the roll row of (11) when ``K_|u|v = K_rdot = 0`` (the vessel file's values). The sway
and yaw rows, ``v' = c_v [phi, v, p, r, delta, tau]`` and ``r' = c_r [...]``, are **free per dataset** (12 nuisance
parameters each): Algorithm 1 uses only (23) and is consistent whatever the sway-yaw dynamics, so the bound that
applies to it must not credit information from a sway-yaw model it does not use (with the sway row of (11) known,
``m`` would enter through ``M + m`` and noise-free sensors would determine it exactly). The other nuisance
parameters, per dataset: the three biases; with waves, ``w, zeta, sigma_c`` of the wave filter; with sensor
noise, the three noise variances. ``nuisance="known-ship"`` fixes ``c_v, c_r`` at their true values (a smaller
bound, for an estimator that knew the sway-yaw model).

**Likelihood and Fisher information.** The outputs are Gaussian, ``y = mu(theta) + n``, with the rudder response
``mu`` (plus the biases) and the stationary noise ``n`` of the state-space model ``s_{k+1} = F s_k + G e_k``,
``n_k = H s_k + J e_k + v_k`` (``s`` = ship states driven by the waves and the wave-filter states; see
:func:`noise_model`). The Fisher information of a Gaussian vector is the sum of a mean and a covariance part
(e.g. Kay 1993, eq. 3.31),

    I = sum_k  d eps_k^T Lambda_k^-1 d eps_k   +   1/2 sum_j tr(S_j^-1 dS_j S_j^-1 dS_j),

* mean part, exact: ``d eps`` are the derivatives of ``mu`` (complex-step through the matrix exponential and the
  sampled recursion) whitened by the time-varying Kalman filter of the noise model from its stationary
  covariance (``Lambda_k`` the innovation covariances), i.e. the Kalman-filter form of the exact likelihood;
* covariance part, Whittle's form on the DFT grid ``w_j = 2 pi j / N``: ``S_j`` the 3x3 spectral density of ``n``,
  ``dS_j`` from the exact derivatives of the transfer ``T(z) = H (zI - F)^-1 G + J``. Its error is O(1) against the
  O(N) information (edge effects of the stationary approximation).

Nuisance parameters are eliminated by the Schur complement; ``m``, ``zm_bar``, ``rho = m z_m / (m_c z_c)`` follow by
the delta method. The bound is conditional on the rudder realisation; ``n_rudder`` averages the information over
independent rudders, and the inverse of the mean information is below the mean of the inverses, so it stays a bound
on the variance over random rudders.

With noise-free sensors (waves only) the three outputs have one noise source, the covariance is singular and the
sway-yaw rows are noise-free; a white sensor-noise floor of ``floor`` times each output's wave-driven std is then
assumed. The model is singular in that limit and the bound keeps falling as the floor goes to zero (300 s, 0.5 deg:
m 0.0182 / 0.0173 / 0.0144 for ``floor`` 1e-2 / 1e-3 / 3e-4, zm_bar 0.0095 / 0.0091 / 0.0075, rho 0.0053 / 0.0031 /
0.0030; rho also falls faster than 1/sqrt(N) with record length), so in that regime read it as the bound for
sensors whose noise is ``floor`` of the signal (1e-3 by default; a hundred times below the sensor regime's noise),
not as the noise-free limit. Checked by Monte Carlo (:mod:`shipid.methods.masscm.coverage`, 300-s records, 100 runs per regime at a seed not
used before): Algorithm 1's spread over this bound is 0.95-0.99 with sensor noise alone (chi-square 95 % intervals
include 1), 1.37-1.52 with waves and sensor noise (intervals 1.21-1.76) and 1.9 (zm_bar) with waves alone (former
"auto" noise model; the Box-Jenkins default: :mod:`shipid.methods.masscm.coverage`); no
spread is below it beyond sampling error. Not modelled: the simulator starts the ship at rest (the filter starts from the stationary covariance) and
scales each wave realisation by its own sample std (here by the stationary std); both are O(1/N).
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import expm, solve_discrete_lyapunov

from shipid.models.roll import params_from_vessel, state_space
from shipid.models.roll_reduced import THETA_NAMES, KnownParams, bilinear_tf, roll_terms
from shipid.models.roll_sim import NoiseSpec, rudder_prbs
from shipid.vessels import load_vessel
from shipid.models.roll_reduced import jacobian_complex_step

CONDS = ("nominal", "calibration", "loaded")
#: the free unknowns of (30) with z_f known
FREE = tuple(n for n in THETA_NAMES if n != "z_f")
_X = (0, 2, 3, 4)                      # phi, v, p, r in the state of (11)
H_CS = 1e-30


def true_nuisance(vessel, cond: str) -> tuple[np.ndarray, np.ndarray]:
    """True sway and yaw rows ``c_v, c_r`` (coefficients of ``[phi, v, p, r, delta, tau]``) of (11) for ``cond``."""
    Ac, Bc = state_space(params_from_vessel(vessel, cond))
    rows = [np.concatenate([Ac[i, list(_X)], Bc[i]]) for i in (2, 4)]
    return rows[0], rows[1]


def continuous_model(theta_free, cv, cr, known: KnownParams, z_f: float, cond: str):
    """``(Ac, Bc, C, D)`` of the ship with the roll row (23) in ``theta`` and free sway/yaw rows.

    States ``[phi, v, p, r]``, inputs ``[delta, tau]``, outputs ``[p, a_s, r]``; any numeric dtype (complex step).
    """
    th = list(theta_free[:6]) + [z_f + 0 * theta_free[0]] + list(theta_free[6:])
    t = roll_terms(np.array(th), known, [cond])
    B, A1, kp, d, Kr, Kd = (t[n][0] for n in ("B", "A1", "kp", "d", "K_r", "K_delta"))
    zs = t["z_s"][0]
    dt = complex if any(np.iscomplexobj(a) for a in (theta_free, cv, cr)) else float
    g, U = known.g, known.U
    vrow = np.asarray(cv, dtype=dt)
    rrow = np.asarray(cr, dtype=dt)
    prow = (np.array([-(kp + B * g), 0.0, -d, Kr + B * U, Kd, 1.0], dtype=dt) + B * vrow) / A1
    M = np.zeros((4, 6), dtype=dt)
    M[0, 2] = 1.0
    M[1], M[2], M[3] = vrow, prow, rrow
    Ac, Bc = M[:, :4], M[:, 4:]
    arow = zs * prow - vrow
    arow = arow + np.array([g, 0, 0, -U, 0, 0])
    C = np.zeros((3, 4), dtype=dt)
    D = np.zeros((3, 2), dtype=dt)
    C[0, 2] = 1.0
    C[2, 3] = 1.0
    C[1], D[1] = arow[:4], arow[4:]
    return Ac, Bc, C, D


def foh(Ac, Bc, T: float):
    """Exact sampling with inputs linear between samples: ``x+ = Ad x + B0 u_k + B1 u_{k+1}`` (as simulate_zoh)."""
    nx, nu = Bc.shape
    big = np.zeros((nx + 2 * nu, nx + 2 * nu), dtype=np.result_type(Ac, Bc))
    big[:nx, :nx], big[:nx, nx:nx + nu] = Ac, Bc
    big[nx:nx + nu, nx + nu:] = np.eye(nu)
    E = expm(big * T)
    Ad, G1, G2 = E[:nx, :nx], E[:nx, nx:nx + nu], E[:nx, nx + nu:] / T
    return Ad, G1 - G2, G2


def noise_matrices(p, known: KnownParams, z_f: float, cond: str, T: float, waves: bool, R_floor=None):
    """Ship ``(Ad, B0, B1, C, D)`` (:func:`continuous_model`, :func:`foh`) and noise model ``(F, G, H, J, R)`` of
    the 26-vector ``p`` (see :class:`DatasetModel`): the wave states driven through the ship, ``s+ = F s + G e``,
    ``n = H s + J e + v``, ``v`` white with covariance ``R = diag(p[23:26]) + diag(R_floor)``; ``F`` empty without
    waves. Real or complex ``p`` (complex-step derivatives)."""
    Ac, Bc, C, D = continuous_model(p[:8], p[8:14], p[14:20], known, z_f, cond)
    Ad, B0, B1 = foh(Ac, Bc, T)
    return noise_from_ship((Ad, B0, B1, C, D), p, T, waves, R_floor)


def noise_from_ship(ship, p, T: float, waves: bool, R_floor=None):
    """:func:`noise_matrices` given its ship part ``(Ad, B0, B1, C, D)`` (the ship of ``p[:20]``): the same
    ``(ship, (F, G, H, J, R))``, without recomputing the ship when only the wave or sensor-noise entries of ``p``
    change."""
    Ad, B0, B1, C, D = ship
    R = np.diag(p[23:26]) + np.diag(np.zeros(3) if R_floor is None else R_floor)
    if not waves:
        z = np.zeros((0, 0), dtype=Ad.dtype)
        return (Ad, B0, B1, C, D), (z, np.zeros((0,), Ad.dtype), np.zeros((3, 0), Ad.dtype), np.zeros(3, Ad.dtype), R)
    Aw, Bw, Cw, Dw = wave_ss(p[20], p[21], T)
    s = p[22]
    Bt = Ad @ B1[:, 1] + B0[:, 1]                 # xi = x - B1_tau tau removes the u_{k+1} term of the FOH
    Ct = C @ B1[:, 1] + D[:, 1]
    F = np.zeros((6, 6), dtype=Ad.dtype)
    F[:4, :4], F[:4, 4:], F[4:, 4:] = Ad, s * np.outer(Bt, Cw), Aw
    G = np.concatenate([s * Dw * Bt, Bw])
    H = np.concatenate([C, s * np.outer(Ct, Cw)], axis=1)
    return (Ad, B0, B1, C, D), (F, G, H, s * Dw * Ct, R)


def wave_ss(w, zeta, T):
    """Tustin wave filter of :func:`shipid.models.roll_sim.wave_moment` as ``(Aw, Bw, Cw, Dw)`` (transposed DF II)."""
    b, a = _bilinear2([2 * zeta * w, 0.0 * w], [1.0 + 0 * w, 2 * zeta * w, w * w], T)
    Aw = np.array([[-a[1], 1.0 + 0 * a[1]], [-a[2], 0 * a[1]]])
    Bw = np.array([b[1] - a[1] * b[0], b[2] - a[2] * b[0]])
    return Aw, Bw, np.array([1.0, 0.0]), b[0]


def _bilinear2(num_s, den_s, T):
    """:func:`~shipid.models.roll_reduced.bilinear_tf` for complex-step arguments (same formula)."""
    c = 2.0 / T

    def poly(p):
        p2, p1, p0 = (np.zeros(3 - len(p)).tolist() + list(p))
        return [p2 * c * c + p1 * c + p0, -2 * p2 * c * c + 2 * p0, p2 * c * c - p1 * c + p0]
    b, a = poly(num_s), poly(den_s)
    return [x / a[0] for x in b], [x / a[0] for x in a]


class DatasetModel:
    """Parameter layout of one dataset: ``theta (8) | c_v (6) | c_r (6) | wave (w, zeta, sigma) | sensor var (3)``."""

    def __init__(self, vessel, cond, known, z_f, noise: NoiseSpec, T: float):
        self.cond, self.known, self.z_f, self.T = cond, known, z_f, T
        self.waves = noise.wave_roll_deg > 0
        self.R_floor = np.zeros(3)
        cv, cr = true_nuisance(vessel, cond)
        w = 2 * np.pi / noise.wave_period
        self.p0 = np.concatenate([true_free_theta(vessel), cv, cr, [w, noise.wave_damping, 1.0],
                                  [noise.gyro_std ** 2, noise.acc_std ** 2, noise.gyro_std ** 2]])
        if self.waves:   # scale so that the stationary roll std is wave_roll_deg
            self.p0[22] = np.deg2rad(noise.wave_roll_deg) / np.sqrt(self.roll_var(self.p0))
        self.floor_rel = self.waves and noise.gyro_std == 0 and noise.acc_std == 0

    def ship(self, p):
        Ac, Bc, C, D = continuous_model(p[:8], p[8:14], p[14:20], self.known, self.z_f, self.cond)
        Ad, B0, B1 = foh(Ac, Bc, self.T)
        return Ad, B0, B1, C, D

    def noise_ss(self, p):
        """``(F, G, H, J, R)`` of the noise (waves through the ship, sensor noise); ``F`` empty without waves."""
        return noise_matrices(p, self.known, self.z_f, self.cond, self.T, self.waves, self.R_floor)[1]

    def roll_var(self, p):
        """Stationary variance of the roll angle (rad²) the ship and wave model of ``p`` imply."""
        Ad, B0, B1, C, D = self.ship(p)
        F, G, H, J, _ = self.noise_ss(p)
        Pi = solve_discrete_lyapunov(F, np.outer(G, G))
        Aw, Bw, Cw, Dw = wave_ss(p[20], p[21], self.T)
        h = np.concatenate([np.eye(4)[0], p[22] * B1[0, 1] * Cw])
        return float(h @ Pi @ h + (p[22] * B1[0, 1] * Dw) ** 2)

    def mean_response(self, p, delta):
        """Rudder response ``mu`` (N, 3) from rest (the simulator's initial state)."""
        Ad, B0, B1, C, D = self.ship(p)
        n = delta.size
        dn = np.concatenate([delta[1:], delta[-1:]])
        bu = np.outer(delta, B0[:, 0]) + np.outer(dn, B1[:, 0])
        X = np.zeros((n, 4), dtype=Ad.dtype)
        x = np.zeros(4, dtype=Ad.dtype)
        for k in range(n):
            X[k] = x
            x = Ad @ x + bu[k]
        return X @ C.T + np.outer(delta, D[:, 0])

    def mean_derivatives(self, p, delta, idx):
        """Complex-step derivatives of :meth:`mean_response` w.r.t. ``p[idx]``, (N, 3, len(idx)), in one pass."""
        mats = []
        for i in idx:
            pc = p.astype(complex)
            pc[i] += 1j * H_CS
            mats.append(self.ship(pc))
        Ad = np.stack([m[0] for m in mats])                                   # (P, 4, 4)
        b0, b1 = np.stack([m[1][:, 0] for m in mats]), np.stack([m[2][:, 0] for m in mats])
        C, D = np.stack([m[3] for m in mats]), np.stack([m[4][:, 0] for m in mats])
        dn = np.concatenate([delta[1:], delta[-1:]])
        n, P = delta.size, len(idx)
        X = np.zeros((n, P, 4), dtype=complex)
        x = np.zeros((P, 4), dtype=complex)
        for k in range(n):
            X[k] = x
            x = np.matmul(Ad, x[:, :, None])[:, :, 0] + delta[k] * b0 + dn[k] * b1
        Y = np.einsum("kpj,pij->kip", X, C) + delta[:, None, None] * D.T[None]
        return np.imag(Y) / H_CS


def true_free_theta(vessel) -> np.ndarray:
    """The packaged true θ of ``vessel`` (its ``table3_true`` values) for the names in :data:`FREE`."""
    t = load_vessel(vessel).values("table3_true")
    return np.array([t[n] for n in FREE], dtype=float)


def _cs(fun, p, idx):
    """Complex-step derivatives of ``fun(p)`` (array or tuple of arrays) w.r.t. ``p[idx]``: list over ``idx``."""
    out = []
    for i in idx:
        pc = p.astype(complex)
        pc[i] += 1j * H_CS
        r = fun(pc)
        out.append(tuple(np.imag(a) / H_CS for a in r) if isinstance(r, tuple) else np.imag(r) / H_CS)
    return out


def whiten(F, G, H, J, R, signals):
    """Kalman-filter innovations of ``signals`` (N, ny, P) under the noise model, and their information.

    Time-varying filter from the stationary covariance ``P = F P F^T + G G^T`` (predictor form with the
    correlated process/measurement noise ``E[G e (J e)^T] = G J^T``): returns ``sum_k eps_k^T Lambda_k^-1 eps_k``.
    """
    N, ny, npar = signals.shape
    if F.shape[0] == 0:
        Rinv = np.linalg.inv(R + np.outer(J, J))
        return np.einsum("kip,ij,kjq->pq", signals, Rinv, signals)
    Q, S, Rt = np.outer(G, G), np.outer(G, J), R + np.outer(J, J)
    P = solve_discrete_lyapunov(F, Q)
    shat = np.zeros((F.shape[0], npar))
    info = np.zeros((npar, npar))
    steady = False
    for k in range(N):
        if not steady:
            Lam = H @ P @ H.T + Rt
            Lam = 0.5 * (Lam + Lam.T)
            Li = np.linalg.inv(Lam)
            K = (F @ P @ H.T + S) @ Li
            Pn = F @ P @ F.T + Q - K @ Lam @ K.T
            Pn = 0.5 * (Pn + Pn.T)
            steady = np.max(np.abs(Pn - P)) <= 1e-14 * max(np.max(np.abs(P)), 1e-300)
            P = Pn
        eps = signals[k] - H @ shat
        info += eps.T @ Li @ eps
        shat = F @ shat + K @ eps
    return info


def spectral_info(F, G, H, J, R, dmats, N):
    """Whittle covariance part ``1/2 sum_j tr(S^-1 dS_a S^-1 dS_b)`` over the N-point DFT grid.

    ``dmats`` lists ``(dF, dG, dH, dJ, dR)`` per parameter.
    """
    npar, ny = len(dmats), H.shape[0]
    info = np.zeros((npar, npar))
    w = 2 * np.pi * np.arange(N // 2 + 1) / N
    wt = np.full(w.size, 2.0)
    wt[0] = 1.0
    if N % 2 == 0:
        wt[-1] = 1.0                                   # j and N - j are conjugate: count each real pair once
    z = np.exp(1j * w)
    for sl in np.array_split(np.arange(w.size), max(1, w.size // 2000)):
        zs = z[sl]
        nz = zs.size
        if F.shape[0]:
            Mz = zs[:, None, None] * np.eye(F.shape[0]) - F
            X = np.linalg.solve(Mz, np.broadcast_to(G, (nz, G.size))[..., None])[..., 0]       # (nz, ns)
            Y = np.linalg.solve(np.swapaxes(Mz, 1, 2), np.broadcast_to(H, (nz,) + H.shape).swapaxes(1, 2))
            Y = np.swapaxes(Y, 1, 2)                                                          # H (zI-F)^-1
            Tz = X @ H.T + J
        else:
            Tz = np.broadcast_to(J, (nz, ny)).astype(complex)
        Sz = Tz[:, :, None] * Tz.conj()[:, None, :] + R
        Si = np.linalg.inv(Sz)
        A = np.empty((npar, nz, ny, ny), dtype=complex)
        for a, (dF, dG, dH, dJ, dR) in enumerate(dmats):
            if F.shape[0]:
                dT = X @ dH.T + np.einsum("nij,jk,nk->ni", Y, dF, X) + Y @ dG + dJ
            else:
                dT = np.broadcast_to(dJ, (nz, ny)).astype(complex)
            dS = dT[:, :, None] * Tz.conj()[:, None, :] + Tz[:, :, None] * dT.conj()[:, None, :] + dR
            A[a] = Si @ dS
        Aflat = A.reshape(npar, nz, ny * ny)
        At = np.swapaxes(A, 2, 3).reshape(npar, nz, ny * ny)
        info += 0.5 * np.real(np.einsum("anx,bnx,n->ab", Aflat, At, wt[sl]))
    return 0.5 * (info + info.T)


def fisher_information(vessel="fishing-vessel", *, duration=300.0, fs=50.0, delta_amp=np.deg2rad(5.0),
                       delta_clock=0.5, noise: NoiseSpec = NoiseSpec.combined(), seed=0, n_rudder: int = 1,
                       nuisance: str = "free-rows", floor: float = 1e-3) -> dict:
    """Fisher information of ``[theta (8) | per dataset: c_v, c_r, wave, sensor variances, biases]``.

    Returns ``info`` (the full matrix), ``theta_index``, ``nuisance_index`` and ``names``.
    """
    if nuisance not in ("free-rows", "known-ship"):
        raise ValueError("nuisance must be 'free-rows' or 'known-ship'")
    known = KnownParams.from_vessel(vessel)
    z_f = float(load_vessel(vessel).value("general", "z_f"))
    T = 1.0 / fs
    n = int(round(duration * fs))
    conds = [DatasetModel(vessel, c, known, z_f, noise, T) for c in CONDS]
    # per-dataset local parameters that enter the model: theta 0..7, c_v 8..13, c_r 14..19, wave 20..22, R 23..25
    local_noise = ([20, 21, 22] if conds[0].waves else []) + ([23, 24, 25] if noise.gyro_std or noise.acc_std else [])
    rows = list(range(8, 20)) if nuisance == "free-rows" else []
    if not conds[0].waves:                             # without waves the tau columns of c_v, c_r do not enter
        rows = [i for i in rows if i not in (13, 19)]
    names = list(FREE)
    gidx = []                                          # per dataset: global index of each local parameter used
    for c in conds:
        loc = {i: i for i in range(8)}
        for i in rows + local_noise:
            loc[i] = len(names)
            names.append(f"{c.cond}:{_LOCAL_NAMES[i]}")
        for b in ("p", "a_s", "r"):
            loc[f"bias_{b}"] = len(names)
            names.append(f"{c.cond}:bias_{b}")
        gidx.append(loc)
    P = len(names)
    info = np.zeros((P, P))
    rngs = [np.random.default_rng(s) for s in np.random.SeedSequence([int(seed), 17]).spawn(n_rudder * 3)]
    for ci, c in enumerate(conds):
        if c.floor_rel:                                # waves, noise-free sensors: a vanishing sensor floor
            F, G, H, J, _ = c.noise_ss(c.p0)
            var = np.real(np.diag(H @ solve_discrete_lyapunov(F, np.outer(G, G)) @ H.T + np.outer(J, J)))
            c.R_floor = (floor ** 2) * var
        loc = gidx[ci]
        mean_par = list(range(8)) + rows
        # covariance part
        cov_par = [i for i in list(range(8)) + rows + local_noise if c.waves or i in (23, 24, 25)]
        if cov_par:
            dm = _cs(c.noise_ss, c.p0, cov_par)
            Ic = spectral_info(*c.noise_ss(c.p0), dm, n)
            g = [loc[i] for i in cov_par]
            info[np.ix_(g, g)] += Ic
        # mean part (rudder response and biases), averaged over rudder realisations
        Im = np.zeros((len(mean_par) + 3, len(mean_par) + 3))
        nm = c.noise_ss(c.p0)
        for rep in range(n_rudder):
            delta = rudder_prbs(n, T, delta_amp, delta_clock, rngs[3 * rep + ci])
            dmu = c.mean_derivatives(c.p0, delta, mean_par)
            sig = np.concatenate([dmu, np.broadcast_to(np.eye(3), (n, 3, 3))], axis=-1)
            Im += whiten(*nm, sig) / n_rudder
        g = [loc[i] for i in mean_par] + [loc[f"bias_{b}"] for b in ("p", "a_s", "r")]
        info[np.ix_(g, g)] += Im
    info = 0.5 * (info + info.T)
    return {"info": info, "names": names, "theta_index": list(range(8)), "nuisance_index": list(range(8, P))}


_LOCAL_NAMES = {**{8 + j: f"c_v[{s}]" for j, s in enumerate(("phi", "v", "p", "r", "delta", "tau"))},
                **{14 + j: f"c_r[{s}]" for j, s in enumerate(("phi", "v", "p", "r", "delta", "tau"))},
                20: "wave_w", 21: "wave_zeta", 22: "wave_sigma", 23: "var_p", 24: "var_a_s", 25: "var_r"}


def theta_covariance(info: np.ndarray, theta_index, nuisance_index) -> np.ndarray:
    """Cramér–Rao covariance of ``theta`` with the nuisance eliminated (inverse of the Schur complement).

    The information is scaled to unit diagonal first (the nuisance blocks span many orders of magnitude);
    raises ``ValueError`` if the Schur complement is not positive definite.
    """
    dg = np.diag(info)
    if not np.all(np.isfinite(info)) or np.any(dg <= 0):
        raise ValueError("Fisher information is not finite or has a zero diagonal: a parameter does not enter")
    s = 1.0 / np.sqrt(dg)
    In = info * np.outer(s, s)
    t, n = list(theta_index), list(nuisance_index)
    schur = In[np.ix_(t, t)] - In[np.ix_(t, n)] @ np.linalg.solve(In[np.ix_(n, n)], In[np.ix_(n, t)]) if n \
        else In[np.ix_(t, t)]
    schur = 0.5 * (schur + schur.T)
    try:
        np.linalg.cholesky(schur)
    except np.linalg.LinAlgError:
        raise ValueError("Fisher information is not positive definite: the parameters are not identifiable")
    c = np.linalg.inv(schur) * np.outer(s[t], s[t])
    return 0.5 * (c + c.T)


def crlb_kf(vessel="fishing-vessel", *, duration: float = 300.0, fs: float = 50.0,
            delta_amp: float = np.deg2rad(5.0), noise: NoiseSpec = NoiseSpec.combined(), seed=0,
            n_rudder: int = 1, nuisance: str = "free-rows", floor: float = 1e-3) -> dict:
    """Bounds on the standard deviations of ``theta``, ``m``, ``zm_bar`` and ``rho`` (z_f known).

    Same return layout as :func:`shipid.methods.masscm.crlb.crlb` (``bounds``, ``names``, ``covariance``).
    """

    fi = fisher_information(vessel, duration=duration, fs=fs, delta_amp=delta_amp, noise=noise, seed=seed,
                            n_rudder=n_rudder, nuisance=nuisance, floor=floor)
    cov = theta_covariance(fi["info"], fi["theta_index"], fi["nuisance_index"])
    known = KnownParams.from_vessel(vessel)
    z_f = float(load_vessel(vessel).value("general", "z_f"))
    th = true_free_theta(vessel)
    bounds = {nm: {"true": float(th[k]), "std": float(np.sqrt(cov[k, k])),
                   "rel": float(np.sqrt(cov[k, k]) / abs(th[k])) if th[k] else float("nan")}
              for k, nm in enumerate(FREE)}
    rho_f = lambda t: t[6] * (t[7] + z_f) / (known.m_c * (known.zc_bar + z_f))   # noqa: E731
    grad = jacobian_complex_step(rho_f, th)
    rv, rs = float(rho_f(th)), float(np.sqrt(grad @ cov @ grad))
    bounds["rho"] = {"true": rv, "std": rs, "rel": rs / abs(rv)}
    return {"method": "kf", "vessel": vessel, "duration": duration, "fs": fs, "delta_amp": delta_amp,
            "noise": noise.__dict__, "z_f": "known", "bounds": bounds, "names": list(FREE),
            "covariance": cov.tolist(), "nuisance": nuisance, "n_rudder": n_rudder,
            "n_parameters": len(fi["names"]),
            "definition": ("Cramér–Rao bound of the data-generating state-space model (11) + wave filter + sensor "
                           "noise + biases: exact Kalman-filter form (mean part) and Whittle form (covariance part) "
                           f"of the Gaussian likelihood of p, a_s, r; nuisance: {nuisance} sway/yaw rows, wave "
                           "filter, sensor variances and biases per dataset, eliminated by the Schur complement")}


__all__ = ["crlb_kf", "fisher_information", "theta_covariance", "continuous_model", "true_nuisance", "whiten",
           "spectral_info", "foh", "noise_from_ship", "wave_ss", "FREE", "CONDS", "DatasetModel", "true_free_theta"]
