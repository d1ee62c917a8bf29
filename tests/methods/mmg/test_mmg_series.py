"""MMG report series on request (shipid.methods.mmg.series.with_series): never inside identify."""

from __future__ import annotations

import json

import pytest

import shipid
from shipid.io.files import write_trial
from shipid.io.paths import data_root
from shipid.errors import InputError
from shipid.methods.mmg import report as mmg_report
from shipid.methods.mmg.series import OVERLAY_CHANNELS, with_series
from shipid.models import mmg
from shipid.result import Result


def _canon(x) -> str:
    return json.dumps(x, sort_keys=True, allow_nan=True)


@pytest.fixture(scope="module")
def made(tmp_path_factory, noisy_run):
    """Two 60-s noisy runs of the Esso Osaka model written as CSV, identified by the API (one structure)."""
    root = data_root()
    if root is None or not (root / "params").is_dir():
        pytest.skip("shared data (params/) not found (set SHIPID_DATA)")
    d = tmp_path_factory.mktemp("mmg_series")
    truth = mmg.load_published("esso_osaka_3m")
    files = []
    for s in (21, 22):
        files.append(str(d / f"run{s}.csv"))
        write_trial(noisy_run(truth, s, 60.0), files[-1])
    res = shipid.identify("mmg", files, prior="esso_osaka_3m", structure="hull+rudder+thrust")
    return files, Result.from_json(res.to_json()), res


def test_identify_makes_no_report_series(made):
    files, stored, res = made
    assert res.series == {} and "inputs" not in res.provenance
    assert [r["file"] for r in res.provenance["training_runs"]] == files


def test_with_series_from_files_and_from_trials_agree_bit_for_bit(made):
    files, stored, res = made
    a = stored.with_series()                                  # reads the recorded files
    assert set(a.series["overlays"]) == {f"run{k}_{ch}" for k in (1, 2) for ch, _, _ in OVERLAY_CHANNELS}
    assert all(e["note"].startswith("training run; sha256 ") for e in a.provenance["inputs"])
    b = stored.with_series(trials=files)                      # the same runs handed over (paths)
    assert _canon(a.to_dict()["series"]) == _canon(b.to_dict()["series"])
    assert _canon(mmg_report.enrich(stored).to_dict()["series"]) == _canon(a.to_dict()["series"])  # shipid report
    assert stored.series == {} and a.with_series() is a       # a copy was completed; done once


def test_with_series_needs_one_trial_per_training_run(made):
    files, stored, _ = made
    with pytest.raises(InputError, match="1 trials given for the 2 training runs"):
        with_series(stored, trials=files[:1])


def test_runs_read_with_the_hsva_rudder_flip_are_reread_with_it():
    """A result identified from read_kvlcc2 runs (δ = −δ_HSVA) records rudder sign −1, so the series made
    from the recorded files equal those made from the flipped runs themselves."""
    from shipid.io.basins import read_kvlcc2
    from shipid.methods.mmg.pipeline import identify as mmg_identify

    root = data_root()
    if root is None or not (root / "kvlcc2_hsva").is_dir():
        pytest.skip("KVLCC2 HSVA data not found (set SHIPID_DATA)")
    runs = [read_kvlcc2("HSVA_CPMC_KVLCC2_Z_10_05.dat"), read_kvlcc2("HSVA_CPMC_KVLCC2_Z_20_05.dat")]
    res = mmg_identify(runs, mmg.load_published("kvlcc2_hsva"), select=False)
    assert res.provenance["rudder_sign"] == -1
    stored = Result.from_json(res.to_json())
    a, b = stored.with_series(), stored.with_series(trials=runs)
    assert _canon(a.to_dict()["series"]) == _canon(b.to_dict()["series"])
