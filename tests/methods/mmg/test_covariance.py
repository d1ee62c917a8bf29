"""Parameter covariance of identified MMG models: run bootstrap and HAC."""

import numpy as np
import pytest

from shipid.io import data_root
from shipid.methods.mmg import covariance as C
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import pipeline as P
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
