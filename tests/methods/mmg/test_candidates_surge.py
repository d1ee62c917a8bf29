"""Surge and slipstream-rudder terms of the Esso structure (esso-lowspeed-ext; shipid.methods.mmg.candidates_surge)."""

import numpy as np
import pytest

from shipid.io.trial import Trial
from shipid.methods.mmg import candidates as C
from shipid.methods.mmg import candidates_asym as A
from shipid.methods.mmg import candidates_surge as SG
from shipid.methods.mmg import estimator as R
from shipid.models import mmg
from shipid.models.mmg_esso_ext import EXT_COEFS, slipstream_share

BASE = "hull+rudder+thrust/nondimensional"


def _ext(prior, terms="surge-hull+rudder-drag+rudder-slipstream", base=None, **coef):
    cand = base if base is not None else C.CANDIDATES["esso-lowspeed"][BASE]
    m, free = C.apply_candidate(prior, SG.surge_variant(cand, terms))
    return m.with_coef(coef), free


def test_zero_extra_terms_give_the_low_speed_model(esso_published, esso_states):
    """With the extra coefficients of EXT_COEFS (and the port/starboard ones) at zero the forces are esso-lowspeed's."""
    m, _ = _ext(esso_published)
    assert m.structure == SG.STRUCTURE
    s = esso_states(0, 300, 16.0)
    for a, b in zip(mmg.forces(m, *s), mmg.forces(esso_published, *s)):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)


def test_surge_hull_terms_are_half_rho_L_d_v2_and_rL2(esso_published, esso_states):
    p = esso_published.particulars
    m, _ = _ext(esso_published, "surge-hull", X_vv=-0.3, X_rr=0.02)
    u, v, r, d, n = esso_states(1, 300, 16.0)
    dX = mmg.forces(m, u, v, r, d, n)[0] - mmg.forces(esso_published, u, v, r, d, n)[0]
    q = 0.5 * p["rho"] * p["L"] * p["d"]
    np.testing.assert_allclose(dX, q * (-0.3 * v * v + 0.02 * (r * p["L"]) ** 2), rtol=1e-10, atol=1e-13)
    dYN = [mmg.forces(m, u, v, r, d, n)[i] - mmg.forces(esso_published, u, v, r, d, n)[i] for i in (1, 2)]
    assert all(np.max(np.abs(x)) == 0.0 for x in dYN)


def test_rudder_drag_is_a_drag_in_the_rudder_inflow(esso_published, esso_states):
    """XR_D > 0 lowers X when the rudder inflow is ahead, by XR_D 1/2 rho A_R U_R^2 at zero drift."""
    p = esso_published.particulars
    m, _ = _ext(esso_published, "rudder-drag", XR_D=0.05)
    u, v, r, d, n = esso_states(2, 300, 16.0)
    keep = (u > 0.05) & (n > 1.0)
    u, v, r, d, n = u[keep], v[keep], 0 * r[keep], d[keep], n[keep]
    v = 0 * v
    dX = mmg.forces(m, u, v, r, d, n)[0] - mmg.forces(esso_published, u, v, r, d, n)[0]
    U_R = mmg.basis(esso_published, u, v, r, d, n)["aux"]["U_R"]
    np.testing.assert_allclose(dX, -0.05 * 0.5 * p["rho"] * p["A_R"] * U_R ** 2, rtol=1e-10)


def test_slipstream_gain_scales_the_rudder_force_by_the_slipstream_share(esso_published, esso_states):
    """YR_s = c adds c phi times the rudder's own Y column; phi is in [0, 1], 0 astern or at rest, and rises
    with the propeller rate at a fixed speed."""
    m, _ = _ext(esso_published, "rudder-slipstream", YR_s=0.4, NR_s=-0.5, XR_s=0.3)
    u, v, r, d, n = esso_states(3, 300, 16.0)
    b = mmg.basis(esso_published, u, v, r, d, n)
    phi = slipstream_share(esso_published.particulars, u, n, b["aux"]["J"], b["aux"]["U_R"])
    assert np.all((phi >= 0) & (phi <= 1)) and np.all(phi[(n <= 0) | (u <= 0)] == 0)
    F1, F0 = mmg.forces(m, u, v, r, d, n), mmg.forces(esso_published, u, v, r, d, n)
    col = b["Y"][0][..., -1]                      # -F_N cos(delta), the column of YR_gain
    np.testing.assert_allclose(F1[1] - F0[1], 0.4 * phi * col, rtol=1e-10, atol=1e-13)
    np.testing.assert_allclose(F1[2] - F0[2], -0.5 * phi * col, rtol=1e-10, atol=1e-13)
    uu, nn = np.full(5, 0.3), np.array([4.0, 6.0, 8.0, 12.0, 16.0])
    z = np.zeros(5)
    bb = mmg.basis(esso_published, uu, z, z, z + 0.2, nn)
    s = slipstream_share(esso_published.particulars, uu, nn, bb["aux"]["J"], bb["aux"]["U_R"])
    assert np.all(np.diff(s) > 0)


def test_wind_gains_scale_the_fixed_air_force(esso_published, esso_states):
    """XW_g, YW_g, NW_g add that fraction of Fujiwara's air force (shipid.models.mmg.wind_forces) per component."""
    m, _ = _ext(esso_published, "wind-gain", XW_g=0.5, YW_g=-0.2, NW_g=1.0)
    g = np.random.default_rng(4)
    UA, gA = g.uniform(0.0, 5.0, 300), g.uniform(-np.pi, np.pi, 300)
    s = esso_states(4, 300, 16.0)
    F1, F0 = mmg.forces(m, *s, UA, gA), mmg.forces(esso_published, *s, UA, gA)
    W = mmg.wind_forces(esso_published.particulars, UA, gA)
    for a, b, k, w in zip(F1, F0, (0.5, -0.2, 1.0), W):
        np.testing.assert_allclose(a - b, k * w, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(mmg.forces(m, *s)[1], mmg.forces(esso_published, *s)[1], rtol=0, atol=1e-12)


def test_variants_extend_the_low_speed_and_port_starboard_candidates(esso_published):
    cands = C.CANDIDATES["esso-lowspeed"]
    v = SG.surge_variants(BASE, cands[BASE])
    assert set(v) == {f"{BASE}+{t}" for t in SG.SURGE_TERMS}
    allv = v[f"{BASE}+surge-hull+rudder-drag+rudder-slipstream"]
    assert allv["structure"] == SG.STRUCTURE and allv["weighting"] == "nondimensional"
    assert allv["X"][-4:] == EXT_COEFS["X"][:4] and allv["N"][-1] == "NR_s"
    assert v[f"{BASE}+surge-hull+wind-gain"]["N"][-1] == "NW_g"
    ps = A.asym_variant(cands[BASE], "prop-side")
    w = SG.surge_variant(ps, "surge-hull")
    assert "NP_n" in w["N"] and w["X"][-2:] == ("X_vv", "X_rr")
    m, free = _ext(esso_published, "surge-hull", base=ps)
    assert set(mmg.COEFS[m.structure]["X"]) >= set(free["X"])
    with pytest.raises(ValueError):
        SG.surge_variant(cands["cubic-hull+rudder+thrust"], "surge-hull")


def _exact_run(model, trial):
    """A SmoothedRun of a noise-free model run with the model's own accelerations (no step-1 smoothing)."""
    ch = trial.channels
    X = np.stack([ch[c] for c in mmg.STATE_NAMES], axis=-1)
    U = np.stack([ch["delta"], ch["n"], 0 * ch["n"], 0 * ch["n"]], axis=-1)
    acc = mmg.dynamics(0.0, X, U, model)[:, 3:]
    z = np.zeros((trial.t.size, 9))
    return R.SmoothedRun(t=trial.t, s=np.concatenate([X, acc], axis=1), s_std=z, inputs=U, source="exact",
                         nis_mean=float("nan"), loglik=float("nan"), sigma=np.zeros(6))


@pytest.mark.slow
def test_regression_recovers_surge_and_slipstream_terms(esso_published):
    """Zig-zags at two propeller rates of a model with X_vv, X_rr, YR_s, NR_s set (the rest esso_published), with
    the model's exact accelerations: the step-2 regression with them free (and X_0F, Y_v, N_r) finds each
    within 2 %. (Through step-1 smoothing of the square-wave rudder the rudder terms come out some 30 % low:
    the smoother's lag at each rudder switch, not the regression.)"""
    truth, _ = _ext(esso_published, "surge-hull+rudder-slipstream", X_vv=-0.4, X_rr=0.03, YR_s=0.3, NR_s=-0.45)
    runs = []
    t = np.arange(0.0, 120.0, 0.1)
    for a, per, n in ((15.0, 40.0, 6.0), (30.0, 60.0, 14.0)):
        Uin = np.zeros((t.size, 4))
        Uin[:, 0], Uin[:, 1] = np.deg2rad(a) * np.sign(np.sin(2 * np.pi * t / per)), n
        X = mmg.simulate_batch(truth, t, np.array([[0, 0, 0, 0.4, 0, 0]]), Uin)[0]
        ch = {c: X[:, i] for i, c in enumerate(mmg.STATE_NAMES)}
        ch.update(delta=Uin[:, 0], n=Uin[:, 1])
        runs.append(_exact_run(truth, Trial(t, ch, {}, {})))
    free = {"X": ("X_0F", "X_vv", "X_rr"), "Y": ("Y_v", "YR_s"), "N": ("N_r", "NR_s")}
    start = truth.with_coef({"X_vv": 0.0, "X_rr": 0.0, "YR_s": 0.0, "NR_s": 0.0})
    f = R.fit(runs, start, free, R.FitConfig(weighting="nondimensional"))
    est = {c: th for m in mmg.MODES for c, th in zip(f.free[m], f.fits[m].theta)}
    for c, true in (("X_vv", -0.4), ("X_rr", 0.03), ("YR_s", 0.3), ("NR_s", -0.45)):
        assert est[c] == pytest.approx(true, rel=0.02), c
