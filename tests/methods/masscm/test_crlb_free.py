"""Noise-free roll-row bound and estimator (shipid.methods.masscm.crlb_free)."""

import numpy as np
import pytest
from scipy.signal import lfilter

from shipid.methods.masscm import crlb_free as F
from shipid.methods.masscm.crlb_kf import true_free_theta
from shipid.models.roll_reduced import KnownParams, bilinear_tf
from shipid.models.roll_sim import NoiseSpec, simulate_datasets
from shipid.vessels import load_vessel

VESSEL = "fishing-vessel"
KNOWN = KnownParams.from_vessel(VESSEL)
Z_F = float(load_vessel(VESSEL).value("general", "z_f"))
WAVES = NoiseSpec(wave_roll_deg=0.5)


def test_realisation_is_the_simulators_datasets_bit_for_bit():
    d = F.realisation(VESSEL, seed=np.random.SeedSequence([7, 3]), duration=20.0, noise=WAVES)
    tr = simulate_datasets(VESSEL, seed=np.random.SeedSequence([7, 3]), duration=20.0, noise=WAVES)
    for c in F.CONDS:
        for k in ("p", "a_s", "r", "delta"):
            assert np.array_equal(d[c][k], tr[c][k]), (c, k)


def test_normalised_roll_row_leaves_exactly_the_scaled_wave_moment():
    """With the exact states and the true sway constants, p' - c(theta) x = tau / (A1 - B kappa_v) at every sample."""
    d = F.realisation(VESSEL, seed=np.random.SeedSequence([7, 4]), duration=30.0, noise=WAVES)
    kap = F.sway_constants(VESSEL, KNOWN, Z_F)
    th = true_free_theta(VESSEL)
    for c in F.CONDS:
        y, X = F.regressors(d[c], KNOWN, "exact")
        res = y - X @ F.coefficients(th, KNOWN, Z_F, c, *kap[c])
        ratio = res / d[c]["tau"]
        assert np.std(ratio) <= 1e-9 * abs(np.mean(ratio))
        # the tau-free sway relation is exact too: least squares recovers the true constants
        k_hat, l_hat = F.estimate_sway_constants(d[c], KNOWN, "exact")
        assert k_hat == pytest.approx(kap[c][0], rel=1e-8)
        np.testing.assert_allclose(l_hat, kap[c][1], atol=1e-9)


def test_whitening_turns_tustin_wave_noise_into_white_noise_plus_one_constant_per_parity():
    T, w, zeta = 0.02, 2 * np.pi, 0.1
    b, a = bilinear_tf([2 * zeta * w, 0.0], [1.0, 2 * zeta * w, w * w], T)
    np.testing.assert_allclose(F.wave_den(w, zeta, T), a, rtol=1e-14)
    e = np.random.default_rng(5).standard_normal(2000)
    n = 3.0 * lfilter(b, a, e)
    S = F.whiten(n, a)
    white = 3.0 * b[0] * e[2:]
    d = S - white
    assert np.ptp(d[0::2]) <= 1e-9 * np.std(white) and np.ptp(d[1::2]) <= 1e-9 * np.std(white)
    # Nyquist factor free: noise with the numerator b0 (1 - q^-1)(1 + c q^-1) becomes white plus one constant (after
    # the start-up transient of 1 / (1 + c q^-1), which decays like c^k)
    c = 0.8
    nc = 3.0 * lfilter(b[0] * np.convolve([1.0, -1.0], [1.0, c]), a, e)
    dc = F.whiten(nc, a, c) - white
    assert np.ptp(dc[200:]) <= 1e-9 * np.std(white)


def test_estimator_recovers_theta_within_its_standard_errors_from_a_perturbed_start():
    d = F.realisation(VESSEL, seed=np.random.SeedSequence([11, 0]), duration=120.0, noise=WAVES)
    th = true_free_theta(VESSEL)
    th0 = th * (1 + 0.05 * np.random.default_rng(2).standard_normal(th.size))
    f = F.estimate_free(d, VESSEL, theta0=th0, wave0=(6.0, 0.15))
    assert f["success"]
    z = (f["theta"] - th) / np.sqrt(np.diag(f["cov"]))
    assert np.all(np.abs(z) < 4), z
    np.testing.assert_allclose(f["wave"][:, 0], 2 * np.pi, rtol=0.05)
    assert abs(f["m"]["value"] - 0.4) < 4 * f["m"]["std"]


def test_noise_free_bound_falls_faster_than_one_over_root_n():
    """The wave spectrum vanishes at w = 0, the rudder-driven regressors do not: information ~ N^2 on part of theta.

    From 150 s to 600 s a regular bound falls by sqrt(4) = 2; this one by more (measured 3.0 for m, 3.5 for rho
    with 4 realisations), while the roll damping d, informed away from w = 0, falls by about 2.
    """
    b1 = F.crlb_free(VESSEL, duration=150.0, n_rudder=4)["bounds"]
    b4 = F.crlb_free(VESSEL, duration=600.0, n_rudder=4)["bounds"]
    assert b1["m"]["std"] / b4["m"]["std"] > 2.5
    assert b1["rho"]["std"] / b4["rho"]["std"] > 2.5
    assert 1.7 < b1["d"]["std"] / b4["d"]["std"] < 2.4
