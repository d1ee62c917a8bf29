"""Tests of shipid.methods.masscm.plausibility.judge (the one plausibility judgement of Algorithm 1's result and of
a refined one)."""

import numpy as np

from shipid.methods.masscm.plausibility import Judgement, judge
from shipid.models.roll_reduced import THETA_NAMES, KnownParams
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
