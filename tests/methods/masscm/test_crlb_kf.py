"""Cramér–Rao bound of the data-generating model (shipid.methods.masscm.crlb_kf)."""

import numpy as np
import pytest
from scipy.stats import chi2

from shipid.methods.masscm import crlb_kf as K
from shipid.models.roll import imu_outputs, params_from_vessel, simulate_zoh, state_space
from shipid.models.roll_reduced import KnownParams
from shipid.models.roll_sim import NoiseSpec, rudder_prbs, simulate_condition

VESSEL = "fishing-vessel"
Z_F = -0.028


def _ar1(a):
    return np.array([[a]]), np.array([1.0]), np.array([[1.0]]), np.array([0.0]), np.zeros((1, 1))


def test_kalman_mean_information_of_ar1_noise_is_the_closed_form():
    """y = b u + n, n AR(1) from its stationary law: I_b = (1 - a^2) u_0^2 + sum (u_k - a u_{k-1})^2 (exact)."""
    a = 0.8
    u = np.random.default_rng(1).standard_normal(400)
    info = K.whiten(*_ar1(a), u[:, None, None])[0, 0]
    exact = (1 - a * a) * u[0] ** 2 + np.sum((u[1:] - a * u[:-1]) ** 2)
    assert info == pytest.approx(exact, rel=1e-12)


def test_whittle_covariance_information_closed_forms():
    """AR(1) coefficient: I_a -> N / (1 - a^2); white-noise variance: I = N / (2 s^4) exactly."""
    a, n = 0.7, 4000
    Ia = K.spectral_info(*_ar1(a), [(np.ones((1, 1)), np.zeros(1), np.zeros((1, 1)), np.zeros(1), np.zeros((1, 1)))], n)
    assert Ia[0, 0] == pytest.approx(n / (1 - a * a), rel=2e-3)         # O(1) against O(N)
    s2 = 0.3
    white = (np.zeros((0, 0)), np.zeros(0), np.zeros((1, 0)), np.zeros(1), np.array([[s2]]))
    Iv = K.spectral_info(*white, [(np.zeros((0, 0)), np.zeros(0), np.zeros((1, 0)), np.zeros(1), np.ones((1, 1)))], n)
    assert Iv[0, 0] == pytest.approx(n / (2 * s2 ** 2), rel=1e-12)


def test_bound_is_met_by_an_efficient_estimator_and_not_beaten_by_an_inefficient_one():
    """Monte Carlo on y = b u + AR(1) noise: GLS (efficient) has variance = bound, OLS above it (chi-square)."""
    a, b, n, reps = 0.9, 0.5, 300, 400
    rng = np.random.default_rng(20261201)
    u = rng.standard_normal(n)
    bound = 1.0 / K.whiten(*_ar1(a), u[:, None, None])[0, 0]

    def filt(x):                                        # exact whitening: the innovations of the stationary AR(1)
        return np.concatenate([[np.sqrt(1 - a * a) * x[0]], x[1:] - a * x[:-1]])
    uw = filt(u)
    gls, ols = [], []
    for _ in range(reps):
        e = rng.standard_normal(n)
        noise = np.empty(n)
        noise[0] = e[0] / np.sqrt(1 - a * a)
        for k in range(1, n):
            noise[k] = a * noise[k - 1] + e[k]
        y = b * u + noise
        gls.append(uw @ filt(y) / (uw @ uw))
        ols.append(u @ y / (u @ u))
    lo, hi = chi2.ppf([0.0005, 0.9995], reps - 1) / (reps - 1)
    r_gls, r_ols = np.var(gls, ddof=1) / bound, np.var(ols, ddof=1) / bound
    assert lo < r_gls < hi                               # efficient: at the bound within sampling error
    assert r_ols > lo                                    # never below it beyond sampling error
    assert r_ols > 1.5                                   # and OLS is clearly inefficient under AR(1) noise


def test_model_is_the_simulator_ship_and_its_rudder_response():
    known = KnownParams.from_vessel(VESSEL)
    idx = [0, 2, 3, 4]
    for cond in K.CONDS:
        cv, cr = K.true_nuisance(VESSEL, cond)
        Ac, Bc, C, D = K.continuous_model(K.true_free_theta(VESSEL), cv, cr, known, Z_F, cond)
        A0, B0 = state_space(params_from_vessel(VESSEL, cond))
        assert np.allclose(Ac, A0[np.ix_(idx, idx)], atol=1e-12) and np.allclose(Bc, B0[idx], atol=1e-12)
    c = K.DatasetModel(VESSEL, "loaded", known, Z_F, NoiseSpec(gyro_std=0.002), 0.02)
    d = rudder_prbs(1500, 0.02, np.deg2rad(5.0), 0.5, np.random.default_rng(3))
    th = params_from_vessel(VESSEL, "loaded")
    X, Xd = simulate_zoh(th, d, 0.02)
    io = imu_outputs(th, X, Xd)
    mu = c.mean_response(c.p0, d)
    for i, ch in enumerate(("p", "a_s", "r")):
        assert np.max(np.abs(mu[:, i] - io[ch])) <= 1e-12 * np.max(np.abs(io[ch]))


def test_noise_model_matches_simulated_wave_records():
    """Stationary variance and lag-1 correlation of p, a_s, r of the noise model against the simulator."""
    known = KnownParams.from_vessel(VESSEL)
    noise = NoiseSpec(wave_roll_deg=0.5)
    c = K.DatasetModel(VESSEL, "calibration", known, Z_F, noise, 0.02)
    from scipy.linalg import solve_discrete_lyapunov
    F, G, H, J, _ = c.noise_ss(c.p0)
    Pi = solve_discrete_lyapunov(F, np.outer(G, G))
    var = np.diag(H @ Pi @ H.T) + J * J
    lag1 = np.diag(H @ F @ Pi @ H.T + np.outer(H @ G, J)) / var
    th = params_from_vessel(VESSEL, "calibration")
    Y = np.vstack([np.column_stack([t["p"], t["a_s"], t["r"]])[1000:]
                   for t in (simulate_condition(th, duration=600.0, noise=noise, delta_amp=0.0, seed=s)
                             for s in (11, 12))])
    assert np.rad2deg(np.sqrt(c.roll_var(c.p0))) == pytest.approx(0.5, rel=1e-9)
    assert Y.var(axis=0) == pytest.approx(var, rel=0.12)
    sim_lag1 = [np.mean(Y[1:, i] * Y[:-1, i]) / Y[:, i].var() for i in range(3)]
    assert sim_lag1 == pytest.approx(lag1, abs=2e-3)


def test_bound_shrinks_as_one_over_root_length_and_knowing_the_ship_only_lowers_it():
    sensors = NoiseSpec(gyro_std=0.002, acc_std=0.02)
    short = K.crlb_kf(VESSEL, duration=40.0, noise=sensors)["bounds"]
    long = K.crlb_kf(VESSEL, duration=160.0, noise=sensors)["bounds"]
    ks = K.crlb_kf(VESSEL, duration=40.0, noise=sensors, nuisance="known-ship")["bounds"]
    for k in ("m", "zm_bar", "rho"):
        assert 1.6 < short[k]["std"] / long[k]["std"] < 2.5          # ~ sqrt(4); rudder realisations differ
        assert ks[k]["std"] < short[k]["std"]                          # less nuisance, more information
    s2 = K.crlb_kf(VESSEL, duration=40.0, noise=NoiseSpec(gyro_std=0.004, acc_std=0.04))["bounds"]
    assert s2["m"]["std"] == pytest.approx(2 * short["m"]["std"], rel=1e-6)   # white noise only: bound ~ noise std


@pytest.mark.slow
def test_waves_only_bound_falls_with_the_sensor_floor_and_stays_finite():
    """Noise-free sensors: the model is singular; less assumed sensor noise can only add information."""
    waves = NoiseSpec(wave_roll_deg=0.5)
    b = [K.crlb_kf(VESSEL, duration=60.0, noise=waves, floor=f)["bounds"]["m"]["std"] for f in (1e-2, 1e-3)]
    assert 0 < b[1] <= b[0] * (1 + 1e-6)
