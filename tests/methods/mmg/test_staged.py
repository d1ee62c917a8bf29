"""The staged structure selection of the Esso low-speed prior (shipid.methods.mmg.staged)."""

import numpy as np
import pytest

from shipid.methods.mmg import output_error as OE
from shipid.methods.mmg import pipeline as P
from shipid.methods.mmg import staged as S
from shipid.methods.mmg.candidates_asym import ASYM_TERMS
from shipid.methods.mmg.candidates_surge import SURGE_TERMS

BASE = "hull+rudder+thrust/nondimensional"


class _Fake:
    """Stand-ins for the two CVs: scores looked up by candidate name (a fixed table), calls recorded."""

    def __init__(self, regression, refined, default=9.0):
        self.regression, self.refined, self.default, self.calls = regression, refined, default, []

    def table(self, trials, runs, prior, pool, **kw):
        return {c: {"score": self.regression.get(c, 9.0), "psi_rms": 0.0, "pos_rms": 0.0} for c in pool}

    def refinement(self, trials, runs, prior, names, **kw):
        self.calls.append((list(names), kw["folds"]))
        out = {}
        for c in names:
            reg, oe = self.refined.get(c, (self.default, self.default))
            out[c + "/regression"] = {"score": reg, "psi_rms": 0.0, "pos_rms": 0.0}
            out[c + "/output-error"] = {"score": oe, "psi_rms": 0.0, "pos_rms": 0.0}
        return out


def _run_fake(monkeypatch, prior, regression, refined, default=9.0, **kw):
    fake = _Fake(regression, refined, default)
    monkeypatch.setattr(S, "cross_validate_horizons", fake.table)
    monkeypatch.setattr(S, "cv_refinement", fake.refinement)
    runs = [type("Run", (), {"source": f"r{i}"})() for i in range(3)]
    return S.select_staged([None] * 3, runs, prior, **kw), fake


def test_stages_follow_the_rule(monkeypatch, esso_published):
    """Step 2 refines the two best of the regression CV; step 3 takes the port/starboard variants of the best
    low-speed row (a cubic-hull row scoring better is passed over); step 4 the surge variants of the best row
    so far; the choice is the lowest row, with its criterion; the output-error steps use 4 folds by default."""
    cubic = "cubic-hull+rudder+thrust/nondimensional"
    st, fake = _run_fake(monkeypatch, esso_published, {cubic: 1.0, BASE: 1.1},
                         {cubic: (1.5, 1.2), BASE: (1.6, 1.3), BASE + "+prop-side": (1.6, 1.15),
                          BASE + "+prop-side+wind-gain": (1.1, 1.13)})
    assert [c[0] for c in fake.calls] == [[cubic, BASE], [f"{BASE}+{t}" for t in ASYM_TERMS],
                                          [f"{BASE}+prop-side+{t}" for t in SURGE_TERMS]]
    assert all(k == S.STAGED_FOLDS for _, k in fake.calls)
    assert (st["chosen"], st["criterion"]) == (BASE + "+prop-side+wind-gain", "regression")
    sel = st["selection"]
    assert sel["criterion"] == "staged" and sel["chosen_criterion"] == "regression"
    assert "1.1000" in sel["why"] and f"next 1.1300 ({BASE}+prop-side+wind-gain/output-error)" in sel["why"]
    assert [s["stage"] for s in sel["stages"]] == ["refinement", "port/starboard", "surge"]
    assert st["pool"][BASE + "+prop-side+wind-gain"]["structure"] == "esso-lowspeed-ext"


def test_output_error_restricts_the_choice_to_refined_rows(monkeypatch, esso_published):
    st, fake = _run_fake(monkeypatch, esso_published, {BASE: 1.0},
                         {BASE: (1.0, 1.4), "hull+rudder+thrust": (1.2, 1.3)},
                         criteria=("output-error",), folds=3)
    assert (st["chosen"], st["criterion"]) == ("hull+rudder+thrust", "output-error")
    assert all(k == 3 for _, k in fake.calls)


def test_every_candidate_failing_is_an_error(monkeypatch, esso_published):
    from shipid.errors import ShipidError

    with pytest.raises(ShipidError, match="every candidate failed"):
        _run_fake(monkeypatch, esso_published, {}, {}, default=np.inf)


def test_enough_horizons_counts_those_of_the_default_candidate(esso_published, own_run):
    trials = [own_run(esso_published, 130.0, rudder_deg=15.0, period=40.0)]
    ok, line = S.enough_horizons(trials, esso_published, OE.OEConfig(), 5)
    assert not ok and line == "2 restarted horizons for 15 refinable coefficients"
    assert S.enough_horizons(trials, esso_published, OE.OEConfig(), 0)[0]


def test_identify_runs_the_staged_selection_and_records_it(monkeypatch, esso_published, own_run):
    """pipeline.identify with the Esso prior and (here, by a lowered threshold) enough horizons: the staged
    selection chooses structure and criterion on the training runs, MODEL.json records both and why, and the
    chosen structure (port/starboard or surge variants included) is the model fitted and validated."""
    from shipid.methods.mmg import validate as V

    fake = _Fake({BASE: 1.0}, {BASE: (1.5, 1.2), BASE + "+rudder-offset": (1.4, 1.1),
                               BASE + "+rudder-offset+wind-gain": (1.2, 1.05)})
    monkeypatch.setattr(S, "cross_validate_horizons", fake.table)
    monkeypatch.setattr(S, "cv_refinement", fake.refinement)
    monkeypatch.setattr(P, "MIN_HORIZONS_PER_COEFFICIENT", 0)
    trials = [own_run(esso_published, 130.0, rudder_deg=a, period=p) for a, p in ((15.0, 40.0), (25.0, 60.0))]
    res = P.identify(trials, esso_published, folds=2, oe_config=OE.OEConfig(max_iter=1), simex=None,
                     refine="auto")
    name = BASE + "+rudder-offset+wind-gain"
    assert res.model["structure_candidate"] == name and res.model["structure"] == "esso-lowspeed-ext"
    sel = res.diagnostics["structure_selection"]
    assert sel["criterion"] == "staged" and sel["chosen"] == name and sel["chosen_criterion"] == "output-error"
    assert name + "/output-error" in sel["refinement_table"] and "why" in sel
    assert "NR_0" in res.diagnostics["output_error"]["refined"]
    doc = res.to_dict()
    v = V.validate(V.model_from_result(doc), trials[0], horizon=60.0)
    assert np.isfinite(v.horizons["psi"]["rms"])


def test_no_staged_selection_without_enough_horizons(esso_published, own_run):
    """Two 130-s runs hold 4 horizons: the regression CV alone chooses, and MODEL.json says why."""
    trials = [own_run(esso_published, 130.0, rudder_deg=a, period=p) for a, p in ((15.0, 40.0), (25.0, 60.0))]
    res = P.identify(trials, esso_published, folds=2, simex=None, refine="auto")
    sel = res.diagnostics["structure_selection"]
    assert sel["criterion"] == "regression CV" and "refinement_table" not in sel
    assert sel["note"].startswith("staged selection not run: 4 restarted horizons for 15")
