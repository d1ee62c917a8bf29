"""Report series of mass-cm on request: identify does none, shipid report makes them from the recorded files."""

import json

import pytest

from shipid.io.files import read_trial, write_trial
from shipid.methods.masscm.estimator import REQUIRED, estimate_mass_cm, fit_mass_cm
from shipid.methods.masscm.report import enrich
from shipid.methods.masscm.series import with_series
from shipid.models.roll_reduced import KnownParams
from shipid.models.roll_sim import NoiseSpec, simulate_datasets
from shipid.report.html import build_report
from shipid.result import Result

KNOWN = KnownParams.from_vessel("fishing-vessel")
ZF = -0.028


@pytest.fixture(scope="module")
def datasets(tmp_path_factory):
    d = tmp_path_factory.mktemp("masscm_report")
    data = simulate_datasets("fishing-vessel", seed=6, noise=NoiseSpec(gyro_std=0.002, acc_std=0.02))
    out = []
    for cond, tr in data.items():
        p = d / f"{cond}.csv"
        write_trial(tr, p)
        out.append((cond, read_trial(str(p), required=["t", *REQUIRED], method="mass-cm")))
    return out


def test_report_series_are_made_from_the_recorded_files(datasets):
    bare = estimate_mass_cm(datasets, KNOWN, z_f=ZF)
    assert not {"overlays", "residuals", "contours"} & set(bare.series)
    stored = Result.from_json(bare.to_json())                       # what a user keeps
    enriched = enrich(stored)
    want = with_series(fit_mass_cm(datasets, KNOWN, z_f=ZF), cost_map=True)
    for kind in ("overlays", "residuals", "contours"):
        assert json.dumps(enriched.series[kind], sort_keys=True) == json.dumps(want.series[kind], sort_keys=True)
    assert "overlays" not in stored.series                           # enrich returns a copy
    via_result = stored.with_series(cost_map=True)                   # Result.with_series -> series.with_series
    assert json.dumps(via_result.series["overlays"], sort_keys=True) == json.dumps(want.series["overlays"],
                                                                                   sort_keys=True)
    assert "Fig. 4" in build_report(stored)


def test_report_says_why_when_the_files_are_gone(datasets, tmp_path):
    r = Result.from_json(estimate_mass_cm(datasets, KNOWN, z_f=ZF).to_json())
    r.provenance["mass_cm_call"]["files"][0][1] = str(tmp_path / "gone.csv")
    out = enrich(r)
    assert "overlays" not in out.series
    assert any("report series not made: dataset file not found" in w for w in out.diagnostics["warnings"])


def test_report_series_from_the_trials_given(datasets):
    """``with_series(trials=...)``: the datasets handed over (the mapping identify takes) instead of the files."""
    r = Result.from_json(estimate_mass_cm(datasets, KNOWN, z_f=ZF).to_json())
    r.provenance["mass_cm_call"]["files"] = [[c, None] for c, _ in r.provenance["mass_cm_call"]["files"]]
    assert r.with_series() is r                                      # no files recorded, no trials: unchanged
    by: dict = {}
    for cond, tr in datasets:
        by.setdefault(cond, []).append(tr)
    out = r.with_series(trials=by)
    want = with_series(fit_mass_cm(datasets, KNOWN, z_f=ZF))
    for kind in ("overlays", "residuals"):
        assert json.dumps(out.series[kind], sort_keys=True) == json.dumps(want.series[kind], sort_keys=True)
    assert not any("report series not made" in w for w in out.diagnostics["warnings"])
