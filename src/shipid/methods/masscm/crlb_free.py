"""Noise-free (waves only) bound and maximum-likelihood estimator of the roll row of Linder et al. (2015, seed 000).

With noise-free sensors the three outputs ``p, a_s, r`` of each dataset have one noise source, the wave moment
``tau``. Eliminating ``tau`` between the sway, roll and yaw rows of (11) leaves two ``tau``-free relations and one
noisy one. With the sway and yaw rows free (as in :mod:`shipid.methods.masscm.crlb_kf`) the two ``tau``-free
relations, ``v' = lambda_v . x + kappa_v p'`` and its yaw analogue (``x = [phi, v, p, r, delta]``), are regressions
with free coefficients: they pin ``kappa_v, lambda_v`` (and the yaw ones) exactly and carry no information on
``theta``. What is left is the roll row (16), (23) with ``a_s`` eliminated by (8),

    A1 p' - B v' = -(k - K_vdot g + B g) phi - d p + (K_r + B U) r + K_delta delta + tau,

in which ``v'`` carries the current ``tau`` (through ``kappa_v p'``). Normalised by the coefficient of the current
``tau`` it is a regression with predetermined regressors (the states at the sample instant),

    p'_k = c_c(theta) . x_k + n_k,   c_c = (r_c(theta) + B lambda_v) / (A1 - B kappa_v),   n = tau / (A1 - B kappa_v)

(``r_c`` the right-hand side coefficients above), whose likelihood is exact Gaussian given ``x`` (the Jacobian of
the normalised form is 1; the noise scale is free per dataset). The wave moment is the Tustin-filtered white noise
of :func:`shipid.models.roll_sim.wave_moment`, ``a(q) n_k = s (e_k - e_{k-2})``: its zeros are at ``z = +-1``
(``2 zeta w s`` has a zero at ``s = 0``), known structure. Hence ``z_k = a(q) n_k`` summed over every other sample,
``S_k = z_k + z_{k-2} + ... = s e_k - s e_{k0}``, is white plus one constant per parity of ``k``: the exact
likelihood (given the first two samples) is least squares in the transformed data with two parity intercepts
(:func:`whiten`). Unknown sensor biases enter the equation as an intercept, a ramp (``phi = int p - b_p t``) and a
quadratic (``v`` from ``int v'``, ``v'`` from (8) with ``phi``): three free nuisance columns per dataset.

The information (:func:`free_information`) is the Gauss–Newton form ``sum_k de_k de_k^T / s^2`` of the transformed
residual (exact for this likelihood, conditional on the regressors), with the parity intercepts and bias columns
projected out (their Schur complement) and the wave ``w, zeta`` of each dataset as nuisance, averaged over
realisations of rudder and waves. The spectrum of ``n`` vanishes at ``w = 0`` while the rudder-driven regressors
(``delta``, the steady heel, yaw rate and drift) have power there: after the transform they are random walks and the
information on the steady roll balance of each dataset grows like ``N^2`` (a cointegrating regression), not ``N``.
:func:`crlb_free` returns the bounds on ``theta, m, zm_bar, rho`` (``z_f`` known) in the layout of
:func:`shipid.methods.masscm.crlb_kf.crlb_kf`.

Scope and limits. ``how="exact"`` takes ``phi, v, p, r`` and ``p'`` at the sample instants from the simulator (an
oracle: the exact states, which sampled outputs do not give); ``"sampled"`` reconstructs them from ``p, a_s, r``
(``phi``, ``v`` by trapezoidal integration of ``p`` and of ``v' = z_s p' + g phi - U r - a_s`` (8), ``p'`` by central
differences; ``nyquist="free"`` then replaces the exact ``1 + q^-1`` factor by ``1 + c q^-1``, ``c`` free). The wave
moment is linear between samples, so ``p'`` has a kink at every sample and no difference formula recovers it to
better than ~0.5 % of its std; that error, not the waves, then dominates the transformed residual and the sampled
estimator is inconsistent (300 s, ``run_free_one(i, 100, how="sampled")``, i = 0..5: m 0.46-0.91 for a true 0.4
with ``nyquist="free"``, 1.3-55 with the exact zeros; wave damping pulled from 0.1 to 0.02-0.04). The bound is therefore the bound of the roll-row regression with exact regressors, conditional on
them: the first-order hold also puts ``tau_k`` into ``x_k`` at ``O(T)``, which this likelihood ignores (a small
bias of the oracle estimator, below), and the sampled data of a known hold satisfy two deterministic relations per
sample whose form depends on ``theta`` through the hold, information this bound does not credit (the exact
noise-free likelihood of sampled data from a known hold is singular, its support moves with ``theta``: no finite
Cramér–Rao bound exists for it). :func:`estimate_free` is the maximum-likelihood estimator of the equation
(``theta`` of (30) with ``z_f`` known, ``w, zeta`` and the noise scale free per dataset, ``kappa_v, lambda_v``
from the exact ``tau``-free sway relation).

Measured (``free_study.free_study(R, 9801, duration=D)``, exact regressors, started from Algorithm 1 on the same
realisation; bound of 8 realisations at ``SeedSequence([9801, 170])``; nothing was tuned on these seeds): spread /
bound [chi-square 95 %], coverage of ±2 std, bias in standard errors of the mean, for m / zm_bar / rho:

* 300 s, 50 runs: 1.32 [1.10, 1.64] / 1.33 [1.11, 1.65] / 0.98 [0.82, 1.23]; coverage 0.96 / 0.98 / 0.94; bias
  +0.2 / -0.1 / +1.3 SE; bound 0.0031 / 0.0016 / 0.0032 against Algorithm 1's spread 0.030 / 0.014 / 0.027 on the
  same runs; mean reported std 0.0040 / 0.0020 / 0.0033 (the spread over the bound is mostly the gap between the
  inverse of the mean information and the mean of the inverses: the ``N^2`` part varies much between rudder
  realisations); 0.48 s CPU per estimate after Algorithm 1.
* 150 s, 30 runs: 1.47 [1.17, 1.98] / 1.47 / 1.15, MAD ratios 0.82 / 1.01 / 0.94; coverage 0.90 / 0.87 / 0.90.
* 600 s, 30 runs: 1.74 [1.39, 2.34] / 1.82 [1.45, 2.45] / 1.04 [0.83, 1.40]; coverage 0.83 / 0.80 / 0.97; bias
  -2.5 / -2.4 / -0.9 SE (m -0.0012, 0.45 spread); reported std 0.0021 against a spread of 0.0026 for m.
  Again at seed 9802 (30 runs): 1.24 [0.99, 1.66] / 1.22 / 1.03, coverage 0.90 / 0.93 / 0.97, bias -3.5 / -3.4 /
  -1.9 SE (m -0.0013): a bias of about -0.3 % in m and zm_bar at 600 s, not seen at 300 s (+0.2 SE); not explained
  here (a candidate: the ``O(T)`` hold feedthrough of ``tau_k`` into ``x_k`` that the conditional likelihood ignores).

Super-efficiency (``crlb_free(duration=D, n_rudder=4)``, m / zm_bar / rho / d): 150 s 0.00630 / 0.00321 / 0.00619 /
0.00200; 300 s 0.00307 / 0.00155 / 0.00355 / 0.00137; 600 s 0.00208 / 0.00108 / 0.00176 / 0.00095; 1200 s 0.00098 /
0.00050 / 0.00084 / 0.00065: the roll damping ``d`` falls as ``1/sqrt(N)``, m, zm_bar and rho about as ``1/N``.
With ``n_bias=1`` (biases as output constants, as in :mod:`~shipid.methods.masscm.crlb_kf`) m / zm_bar / rho are
0.00619 / 0.00321 / 0.00402 at 150 s, 0.00298 / 0.00154 / 0.00209 at 300 s, 0.00206 / 0.00107 / 0.00123 at 600 s;
``crlb_kf(noise=REGIMES["waves"], floor=1e-3)`` (seed 0) gives 0.0240 / 0.0126 / 0.0055, 0.0174 / 0.0091 / 0.0031 and
0.0122 / 0.0064 / 0.0018: a white floor of 1e-3 of each signal removes most of the information on m and zm_bar (their
kf bound falls as ``1/sqrt(N)``), whose noise-free part comes from the frequencies where the wave spectrum vanishes.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares
from scipy.signal import lfilter

from shipid.methods.masscm.crlb_kf import (CONDS, FREE, continuous_model, theta_covariance, true_free_theta,
                                            true_nuisance)
from shipid.models.roll import params_from_vessel, simulate_zoh
from shipid.models.roll_reduced import KnownParams, jacobian_complex_step, roll_terms
from shipid.models.roll_sim import NoiseSpec, rudder_prbs, wave_moment
from shipid.vessels import load_vessel

H_CS = 1e-30
N_BIAS = 3                                 # intercept, ramp, quadratic per dataset


def realisation(vessel="fishing-vessel", *, seed=0, duration=300.0, fs=50.0, noise: NoiseSpec | None = None) -> dict:
    """The three datasets of :func:`shipid.models.roll_sim.simulate_datasets` (same seed streams) with their states.

    Per condition: ``t, delta, tau`` (the scaled wave moment), ``X`` (states ``phi, psi, v, p, r``), ``Xdot``, the
    outputs ``p, a_s, r`` (noise-free; equal to those of ``simulate_datasets(vessel, seed=seed, duration=duration,
    noise=noise)``) and ``scale`` (the factor applied to the unit wave moment).
    """
    noise = NoiseSpec(wave_roll_deg=0.5) if noise is None else noise
    v = load_vessel(vessel)
    ex = v.values("excitation")
    delta_amp, delta_clock = ex["delta_amp"], ex["delta_clock"]
    dt = 1.0 / fs
    n = int(round(duration * fs))
    ss = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
    out = {}
    for cond, child in zip(CONDS, ss.spawn(3)):
        th = params_from_vessel(v, cond)
        r_rud, r_wave, _ = (np.random.default_rng(s) for s in child.spawn(3))
        delta = rudder_prbs(n, dt, delta_amp, delta_clock, r_rud)
        w = wave_moment(n, dt, noise, r_wave)
        Xw, _ = simulate_zoh(th, np.zeros(n), dt, tau=w)
        scale = np.deg2rad(noise.wave_roll_deg) / np.std(Xw[:, 0])
        tau = w * scale
        X, Xd = simulate_zoh(th, delta, dt, tau=tau)
        a_s = th.z_s * Xd[:, 3] + th.g * X[:, 0] - Xd[:, 2] - th.U * X[:, 4]
        out[cond] = {"t": np.arange(n) * dt, "delta": delta, "tau": tau, "X": X, "Xdot": Xd, "scale": scale,
                     "p": X[:, 3].copy(), "a_s": a_s, "r": X[:, 4].copy(), "z_s": th.z_s}
    return out


def regressors(d: dict, known: KnownParams, how: str = "exact") -> tuple[np.ndarray, np.ndarray]:
    """``(y, X)``: ``y = p'`` and ``X = [phi, v, p, r, delta]`` (N, 5) of one dataset of :func:`realisation`."""
    if how == "exact":
        X = d["X"]
        return d["Xdot"][:, 3].copy(), np.column_stack([X[:, 0], X[:, 2], X[:, 3], X[:, 4], d["delta"]])
    if how != "sampled":
        raise ValueError("regressors must be 'exact' or 'sampled'")
    T = d["t"][1] - d["t"][0]
    p, r, a_s = d["p"], d["r"], d["a_s"]
    pd = np.gradient(p, T, edge_order=2)
    phi = _cumtrapz(p, T)
    vd = d["z_s"] * pd + known.g * phi - known.U * r - a_s
    return pd, np.column_stack([phi, _cumtrapz(vd, T), p, r, d["delta"]])


def _cumtrapz(x, T):
    return np.concatenate([[0.0], np.cumsum(0.5 * T * (x[1:] + x[:-1]))])


def sway_constants(vessel, known: KnownParams, z_f: float) -> dict:
    """True ``(kappa_v, lambda_v)`` per condition: the ``tau``-free sway relation ``v' = lambda_v . x + kappa_v p'``."""
    th = true_free_theta(vessel)
    out = {}
    for c in CONDS:
        cv, cr = true_nuisance(vessel, c)
        Ac, Bc, _, _ = continuous_model(th, cv, cr, known, z_f, c)
        prow = np.concatenate([Ac[2], Bc[2]])          # coefficients of [phi, v, p, r, delta, tau]
        kap = cv[5] / prow[5]
        out[c] = (kap, cv[:5] - kap * prow[:5])
    return out


def estimate_sway_constants(d: dict, known: KnownParams, how: str = "exact") -> tuple[float, np.ndarray]:
    """``(kappa_v, lambda_v)`` by least squares of ``v'`` on ``[x, p']`` (exact with noise-free sensors)."""
    y, X = regressors(d, known, how)
    if how == "exact":
        vd = d["Xdot"][:, 2]
    else:
        vd = d["z_s"] * y + known.g * X[:, 0] - known.U * X[:, 3] - d["a_s"]
    A = np.column_stack([X, y])
    coef = np.linalg.lstsq(A, vd, rcond=None)[0]
    return float(coef[5]), coef[:5]


def coefficients(theta, known: KnownParams, z_f: float, cond: str, kap: float, lam) -> np.ndarray:
    """``c_c(theta)`` of the normalised roll row (module docstring) for ``x = [phi, v, p, r, delta]``; complex OK."""
    th = list(theta[:6]) + [z_f + 0 * theta[0]] + list(theta[6:])
    t = roll_terms(np.array(th), known, [cond])
    B, A1, kp, dd, Kr, Kd = (t[n][0] for n in ("B", "A1", "kp", "d", "K_r", "K_delta"))
    rr = np.array([-(kp + B * known.g), 0.0 * B, -dd, Kr + B * known.U, Kd])
    return (rr + B * np.asarray(lam)) / (A1 - B * kap)


def wave_den(w, zeta, T):
    """Denominator ``a(q)`` of the Tustin wave filter (:func:`shipid.models.roll_sim.wave_moment`); complex OK."""
    c = 2.0 / T
    a0 = c * c + 2 * zeta * w * c + w * w
    return np.array([1.0 + 0 * a0, (-2 * c * c + 2 * w * w) / a0, (c * c - 2 * zeta * w * c + w * w) / a0])


def whiten(Y, a, c=None):
    """``S_k`` of the module docstring for the columns of ``Y`` (N, P) or (N,): ``a(q)``, then sums of every other
    sample, from ``k = 2`` on (N - 2 rows). With ``c`` (``|c| < 1``) the Nyquist factor is ``1 + c q^-1`` instead of
    ``1 + q^-1``: ``a(q)``, then ``1 / (1 + c q^-1)`` (from rest), then a plain cumulative sum."""
    Y = np.asarray(Y)
    z = a[0] * Y[2:] + a[1] * Y[1:-1] + a[2] * Y[:-2]
    if c is not None:
        return np.cumsum(lfilter(np.array([1.0 + 0 * c]), np.array([1.0 + 0 * c, c]), z, axis=0), axis=0)
    S = np.empty_like(z)
    S[0::2] = np.cumsum(z[0::2], axis=0)
    S[1::2] = np.cumsum(z[1::2], axis=0)
    return S


def _nuisance_cols(n, T, n_bias=N_BIAS):
    """The first ``n_bias`` of the bias columns ``1, t, t^2`` (t in units of the record length)."""
    t = np.arange(n) * T
    t = t / max(t[-1], T)
    return np.column_stack([np.ones(n), t, t * t])[:, :n_bias]


def _parity(m):
    P = np.zeros((m, 2))
    P[0::2, 0] = 1.0
    P[1::2, 1] = 1.0
    return P


class Equation:
    """The transformed roll row of one dataset: residual and Jacobian in ``(theta, eta)``.

    ``eta = (w, zeta)`` with the exact zeros at ``+-1`` (``nyquist="exact"``) or ``(w, zeta, c)`` with the Nyquist
    factor ``1 + c q^-1`` free (``"free"``; for regressors whose error does not vanish at the Nyquist frequency).
    """

    def __init__(self, y, X, T, known, z_f, cond, kap, lam, nyquist: str = "exact", n_bias: int = N_BIAS):
        if nyquist not in ("exact", "free"):
            raise ValueError("nyquist must be 'exact' or 'free'")
        self.y, self.X, self.T = y, X, T
        self.known, self.z_f, self.cond, self.kap, self.lam = known, z_f, cond, kap, lam
        self.N = _nuisance_cols(y.size, T, n_bias)
        self.n_eta = 2 if nyquist == "exact" else 3

    def _w(self, Y, eta):
        a = wave_den(eta[0], eta[1], self.T)
        return whiten(Y, a, None if self.n_eta == 2 else eta[2])

    def _nuisance(self, eta):
        """Transformed bias columns and the constants of the summed noise (``(N - 2, q)``, columns scaled to unit
        norm at the real part; complex ``eta`` for complex-step derivatives)."""
        m = self.y.size - 2
        const = _parity(m) if self.n_eta == 2 else np.ones((m, 1))
        Z = np.column_stack([self._w(self.N.astype(np.result_type(self.N, np.asarray(eta))), eta), const])
        return Z / np.linalg.norm(Z.real, axis=0)

    def _residual(self, theta, eta):
        c = coefficients(theta, self.known, self.z_f, self.cond, self.kap, self.lam)
        e = self._w(self.y - self.X @ c, eta)
        Z = self._nuisance(eta)
        return e - Z @ np.linalg.solve(Z.T @ Z, Z.T @ e)       # analytic in eta: no conjugate

    def residual(self, theta, eta):
        """Transformed residual with the nuisance columns projected out (their least-squares fit removed)."""
        return self._residual(np.asarray(theta, float), np.asarray(eta, float))

    def jacobian(self, theta, eta):
        """``(e, J)``: residual and its derivatives (N - 2, 8 + len(eta)) w.r.t. ``theta (8), eta`` (complex step,
        through the projection)."""
        theta, eta = np.asarray(theta, float), np.asarray(eta, float)
        dc = np.empty((5, theta.size))
        for j in range(theta.size):
            tc = theta.astype(complex)
            tc[j] += 1j * H_CS
            dc[:, j] = np.imag(coefficients(tc, self.known, self.z_f, self.cond, self.kap, self.lam)) / H_CS
        Z = self._nuisance(eta)
        Jt = -self._w(self.X @ dc, eta)                           # the projection does not depend on theta
        Jt = Jt - Z @ np.linalg.solve(Z.T @ Z, Z.T @ Jt)
        cols = []
        for j in range(eta.size):
            ec = eta.astype(complex)
            ec[j] += 1j * H_CS
            cols.append(np.imag(self._residual(theta.astype(complex), ec)) / H_CS)
        return self._residual(theta, eta), np.column_stack([Jt] + cols)


def _setup(data, vessel, known, z_f, how, kappas, nyquist="exact", n_bias=N_BIAS):
    eqs = []
    for c in CONDS:
        d = data[c]
        y, X = regressors(d, known, how)
        kap, lam = kappas[c] if kappas is not None else estimate_sway_constants(d, known, how)
        eqs.append(Equation(y, X, d["t"][1] - d["t"][0], known, z_f, c, kap, lam, nyquist, n_bias))
    return eqs


def free_information(vessel="fishing-vessel", *, duration=300.0, fs=50.0, noise: NoiseSpec | None = None,
                     seed=0, n_rudder: int = 1, how: str = "exact", n_bias: int = N_BIAS) -> dict:
    """Mean information of ``[theta (8) | per dataset w, zeta]`` over ``n_rudder`` realisations, at the truth.

    ``n_bias``: how many of the bias columns ``1, t, t^2`` are nuisance (3 for an estimator that integrates biased
    gyros; 0 credits the sensors' zero biases)."""
    known = KnownParams.from_vessel(vessel)
    z_f = float(load_vessel(vessel).value("general", "z_f"))
    noise = NoiseSpec(wave_roll_deg=0.5) if noise is None else noise
    th = true_free_theta(vessel)
    kap = sway_constants(vessel, known, z_f)
    w0 = 2 * np.pi / noise.wave_period
    P = 8 + 2 * len(CONDS)
    info = np.zeros((P, P))
    for ss in np.random.SeedSequence([int(seed), 170]).spawn(n_rudder):
        data = realisation(vessel, seed=ss, duration=duration, fs=fs, noise=noise)
        for ci, eq in enumerate(_setup(data, vessel, known, z_f, how, kap, "exact", n_bias)):
            e, J = eq.jacobian(th, (w0, noise.wave_damping))
            s2 = float(e @ e) / (e.size - 2 - n_bias)
            g = list(range(8)) + [8 + 2 * ci, 9 + 2 * ci]
            info[np.ix_(g, g)] += J.T @ J / s2 / n_rudder
    return {"info": 0.5 * (info + info.T), "theta_index": list(range(8)), "nuisance_index": list(range(8, P))}


def _derived(theta, cov, known, z_f) -> dict:
    """``m, zm_bar, rho`` with delta-method standard deviations (``theta`` in :data:`FREE` order)."""
    rho_f = lambda t: t[6] * (t[7] + z_f) / (known.m_c * (known.zc_bar + z_f))   # noqa: E731
    grad = jacobian_complex_step(rho_f, theta)
    out = {n: {"value": float(theta[k]), "std": float(np.sqrt(cov[k, k]))} for k, n in enumerate(FREE)}
    out["rho"] = {"value": float(rho_f(theta)), "std": float(np.sqrt(grad @ cov @ grad))}
    return out


def crlb_free(vessel="fishing-vessel", *, duration: float = 300.0, fs: float = 50.0,
              noise: NoiseSpec | None = None, seed=0, n_rudder: int = 4, how: str = "exact",
              n_bias: int = N_BIAS) -> dict:
    """Bounds on the standard deviations of ``theta``, ``m``, ``zm_bar``, ``rho`` (``z_f`` known), noise-free.

    Same ``bounds`` layout as :func:`shipid.methods.masscm.crlb_kf.crlb_kf`.
    """
    fi = free_information(vessel, duration=duration, fs=fs, noise=noise, seed=seed, n_rudder=n_rudder, how=how,
                          n_bias=n_bias)
    cov = theta_covariance(fi["info"], fi["theta_index"], fi["nuisance_index"])
    known = KnownParams.from_vessel(vessel)
    z_f = float(load_vessel(vessel).value("general", "z_f"))
    th = true_free_theta(vessel)
    d = _derived(th, cov, known, z_f)
    bounds = {n: {"true": v["value"], "std": v["std"], "rel": v["std"] / abs(v["value"]) if v["value"] else
                  float("nan")} for n, v in d.items()}
    return {"method": "free", "vessel": vessel, "duration": duration, "fs": fs, "bounds": bounds,
            "names": list(FREE), "covariance": cov.tolist(), "n_rudder": n_rudder, "regressors": how,
            "definition": ("noise-free reduced-rank bound: the roll row normalised by its current-tau coefficient, "
                           "exact likelihood of the Tustin wave noise (zeros at z = +-1), biases, wave w, zeta and "
                           "noise scale per dataset as nuisance")}


def estimate_free(data: dict, vessel="fishing-vessel", *, theta0=None, how: str = "exact", wave0=(2 * np.pi, 0.1),
                  nyquist: str = "exact", max_passes: int = 4) -> dict:
    """Maximum-likelihood ``theta`` (``z_f`` known) of the normalised roll row of each dataset of ``data``.

    ``theta0`` (:data:`FREE` order) is the start (e.g. Algorithm 1's estimate); ``wave0`` the start of ``w, zeta``.
    The noise scale of each dataset is profiled (least squares reweighted by each dataset's residual variance until
    the weights settle). Returns ``theta``, ``cov`` (inverse Gauss–Newton information), ``m, zm_bar, rho`` with
    standard deviations, ``wave`` and ``success``.
    """
    known = KnownParams.from_vessel(vessel)
    z_f = float(load_vessel(vessel).value("general", "z_f"))
    eqs = _setup(data, vessel, known, z_f, how, None, nyquist)
    th0 = true_free_theta(vessel) if theta0 is None else np.asarray(theta0, float)
    scale = np.abs(th0) + 1e-3
    L = eqs[0].n_eta
    eta0 = tuple(wave0) + (() if L == 2 else (0.9,))
    x0 = np.concatenate([th0 / scale, np.tile(eta0, len(eqs))])
    wts = np.ones(len(eqs))

    def unpack(x):
        return x[:8] * scale, x[8:].reshape(-1, L)

    def fun(x):
        th, wv = unpack(x)
        return np.concatenate([eq.residual(th, wv[i]) * wts[i] for i, eq in enumerate(eqs)])

    def jac(x):
        th, wv = unpack(x)
        blocks = []
        for i, eq in enumerate(eqs):
            _, J = eq.jacobian(th, wv[i])
            Jf = np.zeros((J.shape[0], x.size))
            Jf[:, :8] = J[:, :8] * scale
            Jf[:, 8 + L * i: 8 + L * (i + 1)] = J[:, 8:]
            blocks.append(Jf * wts[i])
        return np.vstack(blocks)

    sol = None
    for _ in range(max_passes):
        sol = least_squares(fun, x0, jac=jac, method="lm", xtol=1e-12, ftol=1e-14, max_nfev=200)
        th, wv = unpack(sol.x)
        s2 = np.array([np.mean(eq.residual(th, wv[i]) ** 2) for i, eq in enumerate(eqs)])
        new = 1.0 / np.sqrt(s2)
        done = np.allclose(new * s2.max() ** 0.5, wts * s2.max() ** 0.5, rtol=1e-3) if _ else False
        wts, x0 = new, sol.x
        if done:
            break
    th, wv = unpack(sol.x)
    info = np.zeros((8 + L * len(eqs),) * 2)
    for i, eq in enumerate(eqs):
        e, J = eq.jacobian(th, wv[i])
        s2 = float(e @ e) / (e.size - 2 - N_BIAS)
        g = list(range(8)) + list(range(8 + L * i, 8 + L * (i + 1)))
        info[np.ix_(g, g)] += J.T @ J / s2
    try:
        cov = theta_covariance(0.5 * (info + info.T), list(range(8)), list(range(8, info.shape[0])))
        ok = bool(sol.success)
    except ValueError:
        cov, ok = np.full((8, 8), np.nan), False
    out = _derived(th, cov, known, z_f)
    return {"theta": th, "cov": cov, "wave": wv, "success": ok, "nfev": int(sol.nfev),
            **{k: out[k] for k in ("m", "zm_bar", "rho")}}


__all__ = ["realisation", "regressors", "sway_constants", "estimate_sway_constants", "coefficients", "wave_den",
           "whiten", "Equation", "free_information", "crlb_free", "estimate_free"]
