"""Port/starboard terms of the Esso structure (esso-lowspeed-asym; shipid.methods.mmg.candidates_asym)."""

import numpy as np
import pytest

from shipid.methods.mmg import candidates as C
from shipid.methods.mmg import candidates_asym as A
from shipid.methods.mmg import estimator as R
from shipid.models import mmg

BASE = "hull+rudder+thrust/nondimensional"


def _asym(prior, terms="prop-side+rudder-offset", **coef):
    m, free = C.apply_candidate(prior, A.asym_variant(C.CANDIDATES["esso-lowspeed"][BASE], terms))
    return m.with_coef(coef), free


def test_zero_asymmetry_terms_give_the_low_speed_model(esso_published, esso_states):
    """With YP_n = NP_n = YR_0 = NR_0 = 0 the forces are those of esso-lowspeed, state by state."""
    m, _ = _asym(esso_published)
    s = esso_states()
    for a, b in zip(mmg.forces(m, *s), mmg.forces(esso_published, *s)):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)


def test_propeller_side_force_is_rho_n2_D4_ahead_only(esso_published, esso_states):
    """YP_n, NP_n add rho n^2 D^4 (times L for the moment) for n > 0 and nothing astern."""
    p = esso_published.particulars
    m, _ = _asym(esso_published, "prop-side", YP_n=0.02, NP_n=-0.01)
    u, v, r, d, n = esso_states(1)
    dY = mmg.forces(m, u, v, r, d, n)[1] - mmg.forces(esso_published, u, v, r, d, n)[1]
    dN = mmg.forces(m, u, v, r, d, n)[2] - mmg.forces(esso_published, u, v, r, d, n)[2]
    q = np.where(n > 0, p["rho"] * p["D_p"] ** 4 * n * n, 0.0)
    np.testing.assert_allclose(dY, 0.02 * q, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(dN, -0.01 * q * p["L"], rtol=1e-10, atol=1e-12)


def test_rudder_offset_is_the_normal_force_slope_times_the_angle(esso_published, esso_states):
    """A small YR_0 = NR_0 / L = YR_gain x delta0 reproduces the rudder force of a rudder turned by
    delta0 to first order (the offset term is the normal-force slope times the angle)."""
    d0 = 1e-4
    g = esso_published.coef["YR_gain"]
    m, _ = _asym(esso_published, "rudder-offset", YR_0=-g * d0, NR_0=0.0)
    u, v, r, d, n = esso_states(2)
    keep = u > 0.05
    u, v, r, d, n = u[keep], v[keep], r[keep], d[keep], n[keep]
    shifted = mmg.forces(esso_published, u, v, r, d + d0, n)[1] - mmg.forces(esso_published, u, v, r, d, n)[1]
    # the rudder's Y force is -YR_gain F_N cos(delta); turning it by d0 changes F_N by its slope times d0
    # and cos(delta) by -sin(delta) d0 (a term the offset model leaves out): compare the F_N part only
    b = mmg.basis(esso_published, u, v, r, d, n)
    FN = -b["Y"][0][..., -1] / np.cos(d)
    part_cos = -g * FN * (np.cos(d + d0) - np.cos(d))
    extra = mmg.forces(m, u, v, r, d, n)[1] - mmg.forces(esso_published, u, v, r, d, n)[1]
    np.testing.assert_allclose(extra, shifted - part_cos, rtol=2e-3, atol=1e-9)


def test_variants_add_the_terms_and_refuse_the_cubic_hull(esso_published):
    cands = C.CANDIDATES["esso-lowspeed"]
    v = A.asym_variants(BASE, cands[BASE])
    assert set(v) == {f"{BASE}+{t}" for t in A.ASYM_TERMS}
    both = v[f"{BASE}+prop-side+rudder-offset"]
    assert both["structure"] == A.STRUCTURE and both["weighting"] == "nondimensional"
    assert both["N"][-2:] == ("NP_n", "NR_0") and both["X"] == tuple(cands[BASE]["X"])
    with pytest.raises(ValueError):
        A.asym_variant(cands["cubic-hull+rudder+thrust"], "prop-side")


def test_regression_recovers_a_propeller_yaw_moment(esso_published, own_run):
    """Noise-free zig-zags of a model with NP_n = -0.01 (the rest esso_published): the step-2 regression with
    NP_n free (and N_v, Y_v, X_0F) finds it within 5 % and the esso_published N_v within 5 %."""
    truth, _ = _asym(esso_published, "prop-side", NP_n=-0.01)
    trials = [own_run(truth, 120.0, rudder_deg=a, period=p) for a, p in ((15.0, 40.0), (25.0, 60.0))]
    runs = [R.smooth_run(tr) for tr in trials]
    free = {"X": ("X_0F",), "Y": ("Y_v",), "N": ("N_v", "NP_n")}
    f = R.fit(runs, truth.with_coef({"NP_n": 0.0}), free, R.FitConfig(weighting="nondimensional"))
    est = dict(zip(f.free["N"], f.fits["N"].theta))
    assert est["NP_n"] == pytest.approx(-0.01, rel=0.05)
    assert est["N_v"] == pytest.approx(esso_published.coef["N_v"], rel=0.05)


@pytest.mark.parametrize("kind, terms", [("asym", "prop-side"),
                                         pytest.param("surge", "surge-hull+wind-gain", marks=pytest.mark.slow)])
def test_refinement_cv_takes_the_variants_from_a_pool(esso_published, own_run, kind, terms):
    """staged.cv_refinement looks the port/starboard (and the surge / wind, candidates_surge) variants
    up in ``pool``; on runs the esso_published model made itself both criteria of the variant predict them
    (scores finite, rows for both)."""
    from shipid.methods.mmg import candidates_surge as SG
    from shipid.methods.mmg import output_error as OE
    from shipid.methods.mmg import staged as S

    pool = dict(C.CANDIDATES["esso-lowspeed"])
    pool.update((A.asym_variants if kind == "asym" else SG.surge_variants)(BASE, pool[BASE]))
    name = f"{BASE}+{terms}"
    trials = [own_run(esso_published, 130.0, rudder_deg=a, period=p) for a, p in ((15.0, 40.0), (25.0, 60.0))]
    runs = [R.smooth_run(tr) for tr in trials]
    ref = S.cv_refinement(trials, runs, esso_published, [name], folds=2, pool=pool,
                          oe_config=OE.OEConfig(max_iter=1))
    assert set(ref) == {name + "/regression", name + "/output-error"}
    assert all(np.isfinite(r["score"]) and r["runs"] == 2 for r in ref.values())
