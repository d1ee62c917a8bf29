"""DP report series on request (shipid.methods.dp.series.with_series): never inside identify."""

from __future__ import annotations

import json
import re
from dataclasses import replace

import numpy as np
import pytest

from shipid.cli import main
from shipid.io.files import read_trial, write_trial
from shipid.methods.dp.entry import REQUIRED
from shipid.methods.dp.estimator import fit_dp
from shipid.methods.dp.series import with_series
from shipid.methods.dp.trials import simulate_dp_trials
from shipid.models import dp
from shipid.result import Result
from shipid.vessels import load_vessel

KINDS = ("surge", "sway-yaw", "azimuth")


def _canon(x) -> str:
    return json.dumps(x, sort_keys=True, allow_nan=True)


def _figures(html: str) -> list[tuple[str, str]]:
    """(PNG data URI, caption) of every figure of a report."""
    return re.findall(r'<figure><img src="([^"]+)"[^>]*><figcaption>(.*?)</figcaption>', html)


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """One 200-s trial per scheme (seed 5) as CSV, read and identified; kept bare as JSON and completed in memory."""
    d = tmp_path_factory.mktemp("dp_series")
    v = dp.dp_vessel(load_vessel("supply"))
    files = {}
    for kind, trs in simulate_dp_trials(v, 5, duration=200.0, n_per_kind=1).items():
        files[kind] = [str(d / f"{kind}.csv")]
        write_trial(trs[0], files[kind][0])
    trials = {k: [read_trial(p, required=list(REQUIRED), manoeuvre=f"dp-{k}") for p in files[k]] for k in KINDS}
    fit = fit_dp(*(trials[k] for k in KINDS), v)
    stored = Result.from_json(fit.result.to_json())          # identify_dp's (and shipid.identify's) result
    full = with_series(fit)                                  # the in-memory path (CLI, demo)
    return d, files, stored, full, trials


def test_identify_makes_no_report_series_and_records_its_files(made):
    _, files, stored, full, _ = made
    assert stored.series == {}                               # no theta_true: not even the true-vs-estimated table
    assert stored.provenance["dp_call"] == {"vessel": "supply", "files": files}
    assert set(full.series["histories"]) == set(dp.THETA_NAMES)
    assert {"innovation_SI1_s", "innovation_SI2_psi", "innovation_SI3_x"} <= set(full.series["residuals"])
    assert {k: e.value for k, e in stored.estimates.items()} == {k: e.value for k, e in full.estimates.items()}


def test_with_series_of_a_stored_result_reproduces_the_series_bit_for_bit(made):
    _, _, stored, full, trials = made
    again = stored.with_series()                              # reads the recorded files, reruns SI1 -> SI3
    assert _canon(Result.from_json(again.to_json()).to_dict()["series"]) == _canon(full.to_dict()["series"])
    assert _canon(again.provenance["inputs"]) == _canon(full.provenance["inputs"])
    assert not any("report series" in w for w in again.warnings)
    assert stored.series == {}                                # a copy was completed
    assert full.with_series() is full                         # already has its series
    # a result that records no files and gets no trials is returned as it is
    nofiles = replace(stored, provenance={**stored.provenance,
                                          "dp_call": {"vessel": "supply", "files": {k: [None] for k in KINDS}}})
    assert nofiles.with_series() is nofiles


def test_with_series_refuses_trials_that_do_not_reproduce_the_estimates(made):
    _, _, stored, _, trials = made
    s = trials["surge"][0]
    other = {**trials, "surge": [s.with_channels(x=s["x"] + np.linspace(0.0, 3.0, s.t.size))]}
    out = stored.with_series(trials=other)
    assert out.series == {}
    assert any(w.startswith("report series not made: SI1 -> SI3 on these trials gives") for w in out.warnings)


@pytest.mark.slow  # ~40 s on 2 loaded cores: the report of the bare JSON reruns SI1 -> SI3
def test_shipid_report_of_the_bare_json_draws_the_same_figures(made, capsys):
    d, _, stored, full, _ = made
    htmls = []
    for name, res in (("bare", stored), ("full", full)):
        res.write_json(d / f"{name}.json")
        assert main(["report", str(d / f"{name}.json"), "--out", str(d / f"{name}.html")]) == 0
        htmls.append((d / f"{name}.html").read_text(encoding="utf-8"))
    capsys.readouterr()
    figs = [_figures(h) for h in htmls]
    assert len(figs[1]) >= 10 and figs[0] == figs[1]       # the same figures, pixel for pixel, same captions
    caps = [c for _, c in figs[0]]
    assert any("Parameter estimates versus time" in c for c in caps)                     # Fig. 8
    assert any("Innovation of heading ψ (SI2" in c for c in caps)
