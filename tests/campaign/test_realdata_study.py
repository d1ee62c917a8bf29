"""Held-out studies on the Esso Osaka and KVLCC2 data (issue 6).

Unmarked: the zig-zag measures on constructed headings, the integrity of the splits,
the frozen configuration (fingerprint) and, on the real data (``realdata``, skipped
when absent), the freeze-before-evaluate property: the selection functions receive
training runs only, and every selection happens before the first test run is read
(evaluation stubbed, so these are fast), plus a small honest CV on three training runs.
Marked ``slow``: the full studies, asserting the issue's targets where they are met and
the measured numbers where they are not.
"""

from pathlib import Path

import numpy as np
import pytest

from shipid.io import data_root
from shipid.io.trial import Trial
from shipid.errors import InputError
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import pipeline as P
from shipid.methods.mmg import study as S

ROOT = data_root()


def need(sub):
    if ROOT is None or not (ROOT / sub).is_dir():
        pytest.skip("shared data not found (set SHIPID_DATA)")


def test_overshoots_of_a_constructed_heading():
    # heading: +12 deg peak after crossing +10, then -15 deg trough after crossing -10, then back past +10
    t = np.linspace(0, 60, 601)
    psi = np.deg2rad(np.interp(t, [0, 5, 10, 20, 30, 40, 50, 60], [0, 10, 12, 0, -15, 0, 11, 0]))
    o = S.overshoots(t, psi, 0, np.deg2rad(10), side=1)
    np.testing.assert_allclose(np.degrees(o), [2.0, 5.0], atol=1e-9)
    # first to port: mirror image
    o = S.overshoots(t, -psi, 0, np.deg2rad(10), side=-1)
    np.testing.assert_allclose(np.degrees(o), [2.0, 5.0], atol=1e-9)


def test_reversal_delay_of_a_constructed_autopilot():
    t = np.arange(0, 40, 0.05)
    psi = np.deg2rad(np.interp(t, [0, 1, 10, 15, 25, 40], [0, 0, 12, 14, -12, -14]))   # psi = 0 at execute
    k_cross = np.flatnonzero(np.degrees(psi) >= 10)[0]
    delta = np.where(t < 1, 0.0, np.deg2rad(20))
    delta = np.where(t >= t[k_cross] + 0.3, np.deg2rad(-20), delta)
    tr = Trial(t, {"psi": psi, "delta": delta}, {"psi": "rad", "delta": "rad"}, {})
    d = S.reversal_delays(tr, np.deg2rad(10))
    assert d[0] == pytest.approx(0.3, abs=0.051)


def test_zigzag_angles_from_names():
    assert np.degrees(S.zigzag_angles("HSVA_CPMC_KVLCC2_Z_20_10_P.dat")) == pytest.approx((20, 10))
    assert np.degrees(S.zigzag_angles("HSVA_CPMC_KVLCC2_Z_35_05.dat")) == pytest.approx((35, 5))


def test_splits_are_disjoint_and_match_the_readme_counts():
    # README_upstream.md: Miyauchi Train-TRZ has 6 runs and 5 test runs; Wakita Train-TZRB+ 35, test 6
    for name, n_train, n_test in (("miyauchi2022", 6, 5), ("wakita2022", 35, 6)):
        sp = S.SPLITS[name]
        assert len(sp["train"]) == n_train and len(sp["test"]) == n_test
        assert not set(sp["train"]) & set(sp["test"])
    assert not set(S.KVLCC2_TRAIN) & set(S.KVLCC2_TEST) and len(S.KVLCC2_TRAIN) + len(S.KVLCC2_TEST) == 13


@pytest.mark.realdata
def test_split_files_exist():
    need("esso_osaka_3m")
    for sp in S.SPLITS.values():
        for f in sp["train"] + sp["test"]:
            assert (ROOT / "esso_osaka_3m" / "data" / f).is_file(), f


def test_configuration_is_the_frozen_one():
    """Candidates, fitting weights, hyper-parameters and splits are those committed before the held-out
    evaluation (shipid.methods.mmg.study docstring). Changing any of them changes the fingerprint:
    then the held-out numbers in docs/validation/mmg.md no longer belong to the code, and must be recomputed."""
    assert S.config_fingerprint() == S.FROZEN_FINGERPRINT


def test_a_test_run_is_refused_for_training():
    sp = S.SPLITS["miyauchi2022"]
    with pytest.raises(InputError, match="test run"):
        S.check_only_training(sp["train"] + sp["test"][:1], sp["test"])
    with pytest.raises(InputError, match="test run"):
        S.kvlcc2_train(train=S.KVLCC2_TRAIN + S.KVLCC2_TEST[:1])


def _stub_evaluate(log):
    def evaluate(models, trials, horizon=60.0, progress=None):
        log.append(("evaluate", [str(t.meta.get("source")) for t in trials]))
        z = {q: {"rms": 0.0, "max": 0.0} for q in ("psi", "r", "u", "v", "pos")}
        return {"per_run": {m: {} for m in models}, "pooled": {m: dict(z, count=0) for m in models}}
    return evaluate


@pytest.mark.realdata
@pytest.mark.parametrize("split", ["miyauchi2022", "wakita2022"])
def test_esso_selection_sees_training_runs_only_and_precedes_every_test_read(split, monkeypatch):
    need("esso_osaka_3m")
    log = []
    read = S.read_esso

    def spy_read(rel, root=None):
        log.append(("read", rel))
        return read(rel, root)

    def spy_select(trials, runs, prior, candidates=None, **kw):
        log.append(("select", [str(t.meta.get("source")) for t in trials] + [r.source for r in runs]))
        return "hull-only", {"hull-only": {"score": 0.0, "folds": 0}}

    monkeypatch.setattr(S, "read_esso", spy_read)
    monkeypatch.setattr(P, "select_structure", spy_select)
    monkeypatch.setattr(S, "evaluate", _stub_evaluate(log))
    sp = S.SPLITS[split]
    st = S.esso_heldout(split, max_train=2)
    kinds = [e[0] for e in log]
    assert kinds.count("select") == 1 and "evaluate" in kinds
    first_test_read = min(i for i, e in enumerate(log) if e[0] == "read" and e[1] in sp["test"])
    assert kinds.index("select") < first_test_read
    seen = log[kinds.index("select")][1]
    assert seen and all(any(src.endswith(tr) for tr in sp["train"][:2]) for src in seen)
    assert not any(src.endswith(te) for src in seen for te in sp["test"])
    assert st["selection"]["training_runs"] == [s for s in log[kinds.index("select")][1][2:]]
    assert st["result"]["provenance"]["config_fingerprint"] == S.config_fingerprint()


@pytest.mark.realdata
def test_kvlcc2_selection_sees_training_zigzags_only_and_precedes_every_test_read(monkeypatch):
    need("kvlcc2_hsva")
    log = []
    read = S.read_kvlcc2

    def spy_read(name, root=None):
        log.append(("read", name))
        return read(name, root)

    def spy_select(trials, runs, prior, candidates, config, folds):
        log.append(("select", [Path(str(t.meta.get("source"))).name for t in trials]))
        return "hull-only", {"hull-only": {"score": 0.0, "folds": 0}}, "spy"

    def stub_overshoots(model, tr, name, autopilot):
        log.append(("zigzag", name))
        return {"side": 1, "measured": [1.0], "predicted": [1.0], "error": [0.0]}

    monkeypatch.setattr(S, "read_kvlcc2", spy_read)
    monkeypatch.setattr(S, "select_by_overshoots", spy_select)
    monkeypatch.setattr(S, "zigzag_overshoots", stub_overshoots)
    monkeypatch.setattr(S, "evaluate", _stub_evaluate(log))
    S.kvlcc2_zigzag(train=S.KVLCC2_TRAIN[:2])
    kinds = [e[0] for e in log]
    assert kinds.count("select") == 1
    assert log[kinds.index("select")][1] == list(S.KVLCC2_TRAIN[:2])
    first_test_read = min(i for i, e in enumerate(log) if e[0] == "read" and e[1] in S.KVLCC2_TEST)
    assert kinds.index("select") < first_test_read
    assert {e[1] for e in log if e[0] == "zigzag"} == set(S.KVLCC2_TEST)


@pytest.mark.realdata
def test_small_esso_cross_validation_on_three_training_runs(monkeypatch):
    """A small honest version of the CV: 2 candidates, 3 Miyauchi training runs, leave one run out.
    Every score is finite, the chosen one is the argmin, and the low-speed hull beats the cubic
    hull expanded about forward speed on these runs (they include a random run at low speed)."""
    need("esso_osaka_3m")
    es = R.CANDIDATES["esso-lowspeed"]
    monkeypatch.setitem(R.CANDIDATES, "esso-lowspeed",
                        {k: es[k] for k in ("hull+rudder+thrust", "cubic-hull+rudder+thrust")})
    st = S.esso_train("miyauchi2022", max_train=3)
    tab = st["selection"]["table"]
    assert set(tab) == {"hull+rudder+thrust", "cubic-hull+rudder+thrust"}
    assert all(np.isfinite(r["score"]) and r["folds"] == 3 for r in tab.values())
    assert st["structure"] == min(tab, key=lambda c: tab[c]["score"])
    assert tab["hull+rudder+thrust"]["score"] < tab["cubic-hull+rudder+thrust"]["score"]
    assert "heldout" not in st


@pytest.mark.slow
@pytest.mark.realdata
@pytest.mark.parametrize("split", ["miyauchi2022", "wakita2022"])
def test_esso_split_beats_published_set(split):
    """Issue 6 target: lower pooled heading and position RMS over restarted 60-s horizons
    (the frozen protocol: leave-one-run-out CV on the training runs, then held-out once)."""
    need("esso_osaka_3m")
    st = S.esso_heldout(split)
    p = st["heldout"]["pooled"]
    assert p["identified"]["psi"]["rms"] < p["published"]["psi"]["rms"]
    assert p["identified"]["pos"]["rms"] < p["published"]["pos"]["rms"]
    assert st["result"]["provenance"]["test_runs_never_used"] == S.SPLITS[split]["test"]
    trained = {r["file"].split("data/")[-1] for r in st["result"]["provenance"]["training_runs"]}
    assert not trained & set(S.SPLITS[split]["test"])


@pytest.mark.slow
@pytest.mark.realdata
def test_kvlcc2_overshoots_close_to_measured():
    """Issue 6 target: every 1st and 2nd overshoot within 2 deg of the measured one (the frozen
    configuration gave 1.70 deg at most, 2nd overshoot of 20/10 starboard; the bound is the target)."""
    need("kvlcc2_hsva")
    st = S.kvlcc2_zigzag()
    assert st["structure"] == "full/symmetric-gamma_R"       # chosen by the overshoot CV (table in docs/validation/mmg.md)
    errs = [e for row in st["overshoots"] for e in row["identified_error_deg"]]
    assert len(errs) == 6
    assert max(abs(e) for e in errs) <= 2.0
    p = st["heldout"]["pooled"]
    assert p["identified"]["psi"]["rms"] < p["published"]["psi"]["rms"]


def test_study_cli_bad_split_and_missing_data_are_one_line(tmp_path, monkeypatch, capsys):
    from shipid.cli import main

    assert main(["study", "esso-osaka-heldout", "--split", "bogus"]) == 2
    monkeypatch.setenv("SHIPID_DATA", str(tmp_path))          # a folder without the data sets
    assert main(["study", "kvlcc2-zigzag"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("shipid: error:") and "SHIPID_DATA" in err[-1]
