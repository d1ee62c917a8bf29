"""Parameter covariance of identified MMG models: run bootstrap, HAC, and the split-half check."""

import numpy as np
import pytest

from shipid.io import data_root
from shipid.io.basins import read_kvlcc2
from shipid.methods.mmg import covariance as C
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import pipeline as P
from shipid.methods.mmg.candidates import CANDIDATES, apply_candidate, candidate_config
from shipid.models import mmg

ROOT = data_root()
FREE = {"X": ("R_0", "XP_gain", "XR_gain"), "Y": ("Y_v", "Y_r", "YR_gain"), "N": ("N_v", "N_r", "NR_arm")}


def need(path):
    if ROOT is None or not (ROOT / path).exists():
        pytest.skip("shared data not found (set SHIPID_DATA)")


@pytest.fixture(scope="module")
def sim_runs(noisy_run):
    need("params")
    truth = mmg.load_published("kvlcc2_hsva")
    trials = [noisy_run(truth, seed, 120.0) for seed in range(6)]
    return truth, [R.smooth_run(t) for t in trials]


def test_bootstrap_draws_are_refits_on_resampled_runs(sim_runs):
    """Each bootstrap draw (from per-run moments) is the stacked fit on the same resample of runs;
    seeded; the covariance is their sample covariance times R/(R-1) and is positive definite."""
    truth, runs = sim_runs
    f = R.fit(runs, truth, FREE)
    B = C.bootstrap_draws(f, runs, truth, draws=5, seed=7)
    np.testing.assert_array_equal(B, C.bootstrap_draws(f, runs, truth, draws=5, seed=7))
    idx = np.random.default_rng(7).integers(0, len(runs), len(runs))
    ref = R.fit([runs[i] for i in idx], truth, FREE).model
    np.testing.assert_allclose(B[0], [ref.coef[n] for n in C.free_names(f)], rtol=1e-7)
    B = C.bootstrap_draws(f, runs, truth, draws=60, seed=1)
    S = C.parameter_covariance(f, runs, truth, options=C.CovarianceOptions("run-bootstrap", 60, 1))
    np.testing.assert_allclose(S, np.cov(B, rowvar=False) * 6 / 5, rtol=1e-10)
    assert np.linalg.eigvalsh(S).min() > 0
    H = C.parameter_covariance(f, runs, truth, options=C.CovarianceOptions("hac"))
    Rg = C.ridge_covariance(f)
    assert H.shape == Rg.shape == S.shape
    assert np.linalg.eigvalsh(H).min() > 0
    # block-diagonal over modes, as the per-mode sandwich is
    assert np.all(H[:3, 3:] == 0) and np.all(H[3:6, 6:] == 0)


def test_identify_stores_the_run_bootstrap_and_falls_back_to_hac(sim_runs, noisy_run):
    """MODEL.json carries the bootstrap covariance (its std are the estimates' std) from 5 runs on,
    the HAC sandwich below; the ridge SE stays in the diagnostics."""
    truth = sim_runs[0]
    trials = [noisy_run(truth, seed, 120.0) for seed in range(6)]
    res = P.identify(trials, truth, structure="linear-hull+rudder", select=False)
    d = res.diagnostics["covariance"]
    assert d["kind"].startswith("run-bootstrap")
    sd = np.sqrt(np.diag(res.covariance))
    for n, s in zip(res.covariance_names, sd):
        assert res.estimates[n].std == pytest.approx(s)
        assert d["se_ridge"][n] > 0
    res2 = P.identify(trials[:2], truth, structure="linear-hull+rudder", select=False)
    assert res2.diagnostics["covariance"]["kind"].startswith("HAC")


@pytest.mark.realdata
def test_split_half_ridge_is_optimistic_bootstrap_is_not():
    """Real HSVA zig-zags (the ten training runs of the frozen study) split at random into halves:
    the coefficient differences between halves are many ridge SEs apart (RMS z >> 1) but about
    one run-bootstrap SE (RMS z within [0.5, 2])."""
    need("kvlcc2_hsva")
    from shipid.methods.mmg.study import KVLCC2_TRAIN

    runs = [R.smooth_run(read_kvlcc2(f)) for f in KVLCC2_TRAIN]
    prior = mmg.load_published("kvlcc2_hsva")
    cand = CANDIDATES["yasukawa2015"]["full/symmetric-gamma_R"]
    cp, free = apply_candidate(prior, cand)
    z = C.split_half_z(runs, cp, free, candidate_config(R.FitConfig(), cand), splits=4, seed=0, draws=100)
    assert z["ridge"]["rms_z"] > 3.0
    assert z["hac"]["rms_z"] > 1.3
    assert 0.5 < z["run-bootstrap"]["rms_z"] < 2.0
