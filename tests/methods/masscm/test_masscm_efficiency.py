"""Issue 3, beyond the paper: Algorithm 1 against the Cramér–Rao bound with noise, biases and wave roll.

Small seeded version here (6 realisations); the 100-realisation comparison is the slow test below and
``benchmarks/bench_masscm_efficiency.py``.
"""

import numpy as np
import pytest

from shipid.methods.masscm.crlb import crlb
from shipid.methods.masscm.study import efficiency_run
from shipid.models.roll_sim import NoiseSpec


@pytest.fixture(scope="module")
def bound():
    # the optimal-IV bound this test was calibrated on (spread/bound ~0.85); crlb_kf is checked in test_crlb_kf
    return crlb(duration=300.0, noise=NoiseSpec.combined(), method="spectrum")["bounds"]


def _spread(outs, k):
    v = np.array([o[k] for o in outs])
    return v.mean(), v.std(ddof=1)


def test_small_efficiency_check(bound):
    outs = [efficiency_run(i, 2024) for i in range(6)]
    plain = [efficiency_run(i, 2024, prefilter=False) for i in range(6)]
    assert all(o["converged"] for o in outs)
    for k in ("zm_bar", "m"):
        mu, sd = _spread(outs, k)
        # 6 samples: the sample std can exceed sigma by 1.74x (99 %, chi2 with 5 dof); the estimator's
        # measured ratio is about 0.85 (benchmark), so 2.0 x the bound is the small-sample limit here
        assert sd < 2.0 * bound[k]["std"], (k, sd, bound[k]["std"])
        assert abs(mu - bound[k]["true"]) < sd                    # means within one spread (issue 3)
        # the ARMA prefilters are what buys this: plain IV is clearly wider
        assert _spread(plain, k)[1] > 1.3 * sd


@pytest.mark.slow
def test_full_efficiency_100_runs(bound):
    outs = [efficiency_run(i, 11) for i in range(100)]
    for k in ("zm_bar", "m"):
        mu, sd = _spread(outs, k)
        assert sd < 1.3 * bound[k]["std"]                          # issue 3 target
        assert abs(mu - bound[k]["true"]) < sd
