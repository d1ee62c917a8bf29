"""The batched horizon cross-validation gives the reference loop's table (shipid.methods.mmg.cv_fast)."""
import warnings

import numpy as np
import pytest

from shipid.io import data_root
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import pipeline as P
from shipid.models import mmg

ROOT = data_root()


def need_params():
    if ROOT is None or not (ROOT / "params").is_dir():
        pytest.skip("shared data (params/) not found (set SHIPID_DATA)")


@pytest.fixture(scope="module")
def problem(noisy_run):
    need_params()
    truth = mmg.load_published("esso_osaka_3m")
    trials = [noisy_run(truth, s, sec) for s, sec in ((31, 130.0), (32, 70.0), (33, 40.0), (34, 20.0))]
    return truth, trials, [R.smooth_run(tr) for tr in trials]


@pytest.mark.parametrize("folds", [None, 2])
def test_batched_cv_table_equals_the_reference(problem, folds):
    """Runs of different lengths (one with two horizons, one too short for any), candidates of two
    structure groups: every score, RMS and count equal the reference loop's to round-off."""
    truth, trials, runs = problem
    c = R.CANDIDATES["esso-lowspeed"]
    cands = {k: c[k] for k in ("hull+rudder+thrust", "hull-only", "cubic-hull-only", "hull-only/nondimensional")}
    with warnings.catch_warnings(record=True) as bw:
        warnings.simplefilter("always")
        b_best, b = P.select_structure(trials, runs, truth, cands, folds=folds, batched=True)
    with warnings.catch_warnings(record=True) as rw:
        warnings.simplefilter("always")
        r_best, r = P.select_structure(trials, runs, truth, cands, folds=folds, batched=False)
    # a fold fit whose ridge iteration does not converge is reported by both paths, with the same text
    assert sorted(str(w.message) for w in bw) == sorted(str(w.message) for w in rw)
    assert b_best == r_best
    assert list(b) == list(r)
    for k in r:
        assert b[k]["count"] == r[k]["count"] and b[k]["folds"] == r[k]["folds"]
        for q in ("score", "psi_rms", "pos_rms"):
            assert b[k][q] == pytest.approx(r[k][q], rel=1e-9, abs=0), (k, q)
    assert r["hull+rudder+thrust"]["count"] == 2 + 1 + 1      # 130 s: 2 horizons; 70 s, 40 s: 1; 20 s: none


def test_batched_cv_fails_a_candidate_whose_fit_fails(problem):
    truth, trials, runs = problem
    cands = {"ok": R.CANDIDATES["esso-lowspeed"]["hull-only"],
             "broken": dict(R.CANDIDATES["esso-lowspeed"]["hull-only"], weighting="no-such")}
    _, table = P.select_structure(trials, runs, truth, cands, batched=True)
    assert np.isfinite(table["ok"]["score"]) and table["broken"]["score"] == float("inf")
