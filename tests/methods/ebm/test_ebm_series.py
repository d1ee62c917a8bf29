"""EBM report series on request (shipid.methods.ebm.series.with_series): never inside identify."""

from __future__ import annotations

import json
import re
from dataclasses import replace

import numpy as np
import pytest

import shipid
from shipid.cli import main
from shipid.io.files import read_trial, write_trial
from shipid.methods.ebm import estimator as ebm
from shipid.methods.ebm.series import with_series
from shipid.methods.ebm.trials import simulate_trial
from shipid.result import Result


def _canon(x) -> str:
    return json.dumps(x, sort_keys=True, allow_nan=True)


def _figures(html: str) -> list[tuple[str, str]]:
    """(PNG data URI, caption) of every figure of a report."""
    return re.findall(r'<figure><img src="([^"]+)"[^>]*><figcaption>(.*?)</figcaption>', html)


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """One 300-s zig-zag written as Parquet; identified once in memory (with its states) and kept bare as JSON."""
    d = tmp_path_factory.mktemp("ebm_series")
    path = d / "zz.parquet"
    write_trial(simulate_trial("zigzag-20", 300.0, seed=7), path)
    bare = shipid.identify("ebm", [str(path)])                # the API: no report work
    trials = [read_trial(str(path), required=list(ebm.REQUIRED), method="ebm", vessel="esso-osaka")]
    run = ebm.identify_run(trials)
    stored = Result.from_json(run.result.to_json())          # what a --json of identify would hold
    full = with_series(run)                                  # the in-memory path (CLI, demo)
    return d, path, bare, stored, full, trials


def test_identify_makes_no_report_series_and_records_its_files(made):
    _, path, bare, stored, full, _ = made
    assert bare.series == {} and stored.series == {}
    assert bare.provenance["ebm_call"]["files"] == [str(path.resolve())]
    assert stored.provenance["ebm_call"]["config"]["q_force"] == list(ebm.EbmConfig().q_force)
    assert {"signals", "matrices", "tables", "overlays", "residuals"} <= set(full.series)
    # the estimates do not depend on whether series were made
    assert {k: e.value for k, e in bare.estimates.items()} == {k: e.value for k, e in full.estimates.items()}


def test_with_series_of_a_stored_result_reproduces_the_series_bit_for_bit(made):
    _, _, _, stored, full, trials = made
    again = stored.with_series()                              # reads the recorded file, reruns both steps
    assert _canon(Result.from_json(again.to_json()).to_dict()["series"]) == _canon(full.to_dict()["series"])
    assert _canon(again.provenance["inputs"]) == _canon(full.provenance["inputs"])
    assert not any("report series" in w for w in again.warnings)
    given = stored.with_series(trials=trials)                 # the trials handed over instead of the files
    assert _canon(given.to_dict()["series"]) == _canon(full.to_dict()["series"])
    assert stored.series == {}                                # a copy was completed, not the stored result
    assert full.with_series() is full                         # already has its series


def test_with_series_refuses_trials_that_do_not_reproduce_the_estimates(made):
    _, _, _, stored, _, trials = made
    other = trials[0].with_channels(x=trials[0]["x"] + np.linspace(0.0, 5.0, trials[0].t.size))
    out = stored.with_series(trials=[other])
    assert out.series == {}
    assert any(w.startswith("report series not made: EBM on these trials gives") for w in out.warnings)


def test_with_series_says_when_the_recorded_file_is_gone(made):
    _, _, _, stored, _, _ = made
    gone = replace(stored, provenance={**stored.provenance,
                                       "ebm_call": {**stored.provenance["ebm_call"], "files": ["/nonexistent/zz.csv"]}})
    out = gone.with_series()
    assert out.series == {} and out.warnings[-1] == ("report series not made: trial file not found: /nonexistent/zz.csv "
                                                     "(give the trials: with_series(trials=...))")


def test_shipid_report_of_the_bare_json_draws_the_same_figures(made, capsys):
    d, _, _, stored, full, _ = made
    bare_json, full_json = d / "bare.json", d / "full.json"
    stored.write_json(bare_json)
    full.write_json(full_json)
    htmls = []
    for src in (bare_json, full_json):
        out = d / f"{src.stem}.html"
        assert main(["report", str(src), "--out", str(out)]) == 0
        htmls.append(out.read_text(encoding="utf-8"))
    capsys.readouterr()
    figs = [_figures(h) for h in htmls]
    assert len(figs[1]) >= 5 and figs[0] == figs[1]        # the same figures, pixel for pixel, same captions
    for title in ("Figs 4, 9", "Table 4", "innovation"):
        assert (title in htmls[0]) and (title in htmls[1])
