"""Tests of shipid.methods.masscm.plausibility.judge (the one plausibility judgement of Algorithm 1's result and of
a refined one)."""

import numpy as np

from shipid.methods.masscm.plausibility import Judgement, judge
from shipid.models.roll_reduced import THETA_NAMES, KnownParams, roll_terms
from shipid.result import Estimate
from shipid.vessels import load_vessel

VESSEL = "fishing-vessel"
KNOWN = KnownParams.from_vessel(VESSEL)
CONDS = ["nominal", "calibration", "loaded"]
TRUE = np.array([load_vessel(VESSEL).values("table3_true")[n] for n in THETA_NAMES], dtype=float)


def _estimates():
    return {n: Estimate(1.0, 0.1, "-", "estimated", "a note" if n == "m" else "") for n in ("m", "zm_bar", "rho", "k")}


def test_the_true_theta_is_plausible_and_writes_nothing():
    v = judge(TRUE, KNOWN, CONDS, {"m": 0.01, "zm_bar": 0.01})
    assert not v.implausible and v.nuisance == [] and v.warnings() == []
    assert v.diagnostics() == {"implausible": False, "implausible_reasons": [], "nuisance_outside_physical": []}
    est = _estimates()
    assert v.mark(est) == est


def test_the_nuisance_line_names_its_source():
    a, r = Judgement([], ["A_x <= 0", "d <= 0"]), Judgement([], ["A_x <= 0", "d <= 0"], refined=True)
    assert not a.implausible and a.diagnostics()["nuisance_outside_physical"] == ["A_x <= 0", "d <= 0"]
    (la,), (lr,) = a.warnings(), r.warnings()
    prefix = "nuisance coefficients outside their physical range (A_x <= 0, d <= 0"
    assert la.startswith(prefix + "): K_vdot, K_r, K_delta carry a finite-sample IV bias under sensor noise")
    assert lr == prefix + ") after the refinement; m, zm_bar and rho are judged on their own and not flagged"
    assert Judgement(["x"], ["A_x <= 0"]).warnings() == ["implausible solution: x"]    # the flag says it all


def test_a_negative_a_x_is_an_unphysical_roll_mode_and_in_the_nuisance_split():
    th = TRUE.copy()
    th[THETA_NAMES.index("A_x")] = -abs(th[THETA_NAMES.index("A_x")])
    v = judge(th, KNOWN, CONDS, {})
    assert "A_x <= 0" in v.nuisance and any("roll mode not physical" in w for w in v.reasons)


def test_an_implausible_estimate_is_flagged_and_its_load_entries_relabelled():
    th = TRUE.copy()
    th[THETA_NAMES.index("m")] = -1.0
    v = judge(th, KNOWN, CONDS, {"m": 0.01})
    assert v.implausible and v.warnings() == ["implausible solution: " + ", ".join(v.reasons)]
    est = v.mark(_estimates())
    assert [est[n].status for n in ("m", "zm_bar", "rho", "k")] == ["not determined"] * 3 + ["estimated"]
    assert est["m"].note.startswith("implausible solution (") and est["m"].note.endswith("; a note")
    back = v.unmark(est)
    assert [back[n].status for n in ("m", "zm_bar", "rho")] == ["estimated", "estimated", "derived"]
    assert back["m"].note == "a note" and back["zm_bar"].note == "" and back["k"] == est["k"]
    assert Judgement().unmark(est) == est              # a plausible judgement labelled nothing
    assert not judge(th, KNOWN, CONDS, {"m": 1.0}).implausible      # within 2 std of zero: not flagged
    assert Judgement(["x"]).implausible and not Judgement().implausible


def test_identified_mode_physical_is_the_judgement_of_implausible_identifiable():
    """The scalar judgement of the iteration's physical-region test gives the boolean of
    implausible_identifiable (no standard errors) at every theta: draws from far inside to far outside the
    physical region (each entry scaled by a factor in [-3, 3]), the iterates of the degenerate minimum, and
    the edge cases (non-finite, m <= 0, |zm_bar| > 10, overflowing terms, A2 = 0 and next to it)."""
    from shipid.methods.masscm.plausibility import identified_mode_physical, implausible_identifiable

    rng = np.random.default_rng(7)
    thetas = [TRUE * rng.uniform(-3, 3, TRUE.size) for _ in range(3000)]
    thetas += [TRUE * rng.uniform(0.8, 1.2, TRUE.size) for _ in range(1000)]
    for i in range(TRUE.size):
        for v in (np.nan, np.inf, 0.0, -0.0, 1e300, -1e300, 1e-300, 11.0, -11.0):
            th = TRUE.copy()
            th[i] = v
            thetas.append(th)
    # A2 = 0 exactly in the nominal dataset (A_x cancels the other terms of (22)), then A2 one step away
    th0 = TRUE.copy()
    z_f = th0[6]
    zg, zs = KNOWN.zg_bar + z_f, KNOWN.zs_bar + z_f
    th0[1] = th0[4] * zs - KNOWN.M * zg * (KNOWN.zg_bar - KNOWN.zs_bar)
    assert roll_terms(th0, KNOWN, CONDS)["A2"][0] == 0.0
    thetas += [th0, th0 * np.r_[np.ones(1), 1 + 2e-16, np.ones(7)], th0 * np.r_[np.ones(1), 1 - 2e-16, np.ones(7)]]
    flips = 0
    for th in thetas:
        with np.errstate(all="ignore"):       # both overflow alike at the extreme draws
            ref = not implausible_identifiable(th, KNOWN, CONDS)
            assert identified_mode_physical(th, KNOWN, CONDS) == ref, th
        flips += ref
    assert 0 < flips < len(thetas)            # both verdicts occur
