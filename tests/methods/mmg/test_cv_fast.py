"""The batched horizon cross-validation gives the reference loop's table (shipid.methods.mmg.cv_fast)."""

import numpy as np
import pytest

from shipid.data import data_root
from shipid.data.trial import Trial
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import pipeline as P
from shipid.models import mmg

ROOT = data_root()


def need_params():
    if ROOT is None or not (ROOT / "params").is_dir():
        pytest.skip("shared data (params/) not found (set SHIPID_DATA)")


def _sim_trial(model, seed, seconds, noise=1.0):
    """Random rudder/propeller orders with a steady wind, seeded measurement noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, 0.1)
    k = np.arange(t.size) // 80
    U = np.zeros((t.size, 4))
    U[:, 0] = np.deg2rad(rng.uniform(-30, 30, k.max() + 1))[k]
    U[:, 1] = rng.uniform(6, 12, k.max() + 1)[k]
    U[:, 2], U[:, 3] = 1.0, 0.7
    X = mmg.simulate_batch(model, t, np.array([[0, 0, 0, 0.35, 0, 0]]), U)[0]
    ch = {c: X[:, i] + noise * s * rng.standard_normal(t.size)
          for i, (c, s) in enumerate(zip(mmg.STATE_NAMES, (0.02, 0.02, 0.005, 0.01, 0.01, 0.003)))}
    ch.update(delta=U[:, 0], n=U[:, 1], wind_speed=U[:, 2], wind_dir=U[:, 3])
    return Trial(t, ch, {}, {"source": f"sim {seed}"})


@pytest.fixture(scope="module")
def problem():
    need_params()
    truth = mmg.load_published("esso_osaka_3m")
    trials = [_sim_trial(truth, s, sec) for s, sec in ((31, 130.0), (32, 70.0), (33, 40.0), (34, 20.0))]
    return truth, trials, [R.smooth_run(tr) for tr in trials]


@pytest.mark.parametrize("folds", [None, 2])
def test_batched_cv_table_equals_the_reference(problem, folds):
    """Runs of different lengths (one with two horizons, one too short for any), candidates of two
    structure groups: every score, RMS and count equal the reference loop's to round-off."""
    truth, trials, runs = problem
    c = R.CANDIDATES["esso-lowspeed"]
    cands = {k: c[k] for k in ("hull+rudder+thrust", "hull-only", "cubic-hull-only", "hull-only/nondimensional")}
    b_best, b = P.select_structure(trials, runs, truth, cands, folds=folds, batched=True)
    r_best, r = P.select_structure(trials, runs, truth, cands, folds=folds, batched=False)
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
