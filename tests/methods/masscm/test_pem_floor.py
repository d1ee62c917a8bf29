"""Tests of the floor-regularised ML refinement for noise-free sensors (PEMOptions.sensor_floor, refine="pem-floor")."""

import numpy as np
import pytest

from shipid.methods.masscm import pem
from shipid.methods.masscm.coverage import REGIMES
from shipid.methods.masscm.crlb_kf import true_free_theta
from shipid.methods.masscm.estimator import MassCMOptions, estimate_mass_cm
from shipid.methods.masscm.pem_initial import without_initial_state
from shipid.methods.masscm.pem_result import refine_result_floor
from shipid.models.roll_reduced import KnownParams
from shipid.models.roll_sim import simulate_datasets
from shipid.vessels import load_vessel

VESSEL = "fishing-vessel"


def test_defaults_unchanged():
    assert pem.PEMOptions().sensor_floor is None          # None: the sensor variances are estimated, as before
    assert MassCMOptions().refine == "auto"                # the floor refinement is opt-in, never auto's engine
    assert pem.floor_schedule(1e-3) == pytest.approx([0.1, 0.01, 1e-3])
    assert pem.floor_schedule(0.5) == [0.5]


def _predictor(rng, ns=4):
    """A random stable predictor: error dynamics A = F - K H with spectral radius 0.97, and Lam."""
    F = rng.standard_normal((ns, ns))
    F *= 0.97 / np.max(np.abs(np.linalg.eigvals(F)))
    H, K = rng.standard_normal((3, ns)), np.zeros((ns, 3))
    Lam = np.diag([1.0, 1e-4, 1e-6])                       # ill-conditioned, as with a sensor floor
    return F, K, H, Lam


def _response(F, K, H, s0, n):
    A, z, out = F - K @ H, s0.copy(), np.empty((n, 3))
    for k in range(n):
        out[k] = -H @ z
        z = A @ z
    return out


def test_initial_state_response_is_removed_exactly():
    rng = np.random.default_rng(20261202)
    F, K, H, Lam = _predictor(rng)
    s0 = rng.standard_normal(4)
    eps = _response(F, K, H, s0, 3000)                     # innovations that are an initial-state transient only
    out = without_initial_state(eps, F, K, H, Lam)
    assert np.max(np.abs(out)) < 1e-8 * np.max(np.abs(eps))


def test_initial_state_removal_is_the_weighted_least_squares_solution():
    rng = np.random.default_rng(20261203)
    F, K, H, Lam = _predictor(rng)
    n = 2000
    e = rng.standard_normal((n, 3)) * np.sqrt(np.diag(Lam))
    eps = e + _response(F, K, H, rng.standard_normal(4), n)
    out = without_initial_state(eps, F, K, H, Lam)
    # the same fit by explicit least squares on the whitened response matrix
    Phi = np.stack([_response(F, K, H, np.eye(4)[j], n) for j in range(4)], axis=-1)      # (n, 3, 4)
    w = 1 / np.sqrt(np.diag(Lam))
    s0 = np.linalg.lstsq((Phi * w[None, :, None]).reshape(-1, 4), (eps * w).reshape(-1), rcond=None)[0]
    ref = eps - np.einsum("kij,j->ki", Phi, s0)
    assert np.allclose(out, ref, rtol=0, atol=1e-9 * np.max(np.abs(eps)))
    q = lambda x: float(np.sum(x * x / np.diag(Lam)))    # noqa: E731
    assert q(out) <= q(eps)


@pytest.mark.slow
def test_floor_refinement_recovers_truth_with_noise_free_sensors():
    """Waves, noise-free sensors, 300 s (the study's records): the refinement finishes, keeps the waves, and is
    within 3 of its standard errors of the truth; its std is near the bound at the same floor, not Algorithm 1's."""
    known = KnownParams.from_vessel(VESSEL)
    z_f = float(load_vessel(VESSEL).value("general", "z_f"))
    d = simulate_datasets(VESSEL, seed=np.random.SeedSequence([4249, 8]), duration=300.0, noise=REGIMES["waves"])
    r0 = estimate_mass_cm(list(d.items()), known, z_f=z_f, noise_check=False, options=MassCMOptions(compute="fast"))
    r = refine_result_floor(r0, list(d.items()), known, z_f, 1e-3)
    rec = r.diagnostics["refine"]
    assert rec["method"] == "pem-floor" and rec["sensor_floor"] == 1e-3
    assert rec["applied"], rec["reason"]
    assert rec["waves"]
    th = true_free_theta(VESSEL)
    truth = {"m": th[pem.I_M], "zm_bar": th[pem.I_ZM], "rho": pem.rho_of(th, known, z_f)}
    for k, v in truth.items():
        assert np.isfinite(r.std(k)) and r.std(k) > 0
        assert abs(r.value(k) - v) < 3 * r.std(k), k
    assert r.std("m") < r0.std("m")


def test_pem_floor_is_an_opt_in_engine_not_the_auto_one():
    from shipid.methods.masscm import refine
    assert "pem-floor" in refine.REFINE_MODES and "pem-floor" not in refine.AUTO_ENGINES
