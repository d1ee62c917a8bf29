"""Coverage of the DP standard deviations with unknown noise levels (seed 001, issue 15).

Data: :func:`shipid.methods.dp.coverage.study_noise` -- measurement and process noise each scaled
by a factor drawn from {0.5, 1, 2}, a wandering (Gauss-Markov) bias, 0.2° heading noise; the
estimator is told none of it. Campaign seed 3 (never used to choose the method's settings; those
were chosen on seed 1).
"""

from __future__ import annotations

import numpy as np
import pytest

from shipid.methods.dp.estimator import DPOptions, run_stage
from shipid.methods.dp.coverage import ACCURACY_BAND, SCALES, study_noise, summarise
from shipid.methods.dp.trials import simulate_dp_trial
from shipid.models import dp
from shipid.vessels import load_vessel


@pytest.fixture(scope="module")
def supply():
    return dp.dp_vessel(load_vessel("supply"))


def si2_errors_over_std(supply, n_real: int, covariance: str, seed: int = 3, duration: float = 600.0):
    """(θ̂ − θ)/std of the six SI2 parameters over ``n_real`` seeded realisations (θ1, θ6, θ9 at the truth)."""
    out = []
    for i in range(n_real):
        rng = np.random.default_rng(np.random.SeedSequence([seed, i]))
        s_m, s_p = float(rng.choice(SCALES)), float(rng.choice(SCALES))
        seeds = rng.integers(0, 2 ** 31 - 1, size=2)
        noise = study_noise(s_m, s_p)
        trials = [simulate_dp_trial(supply, "sway-yaw", duration, int(s), noise=noise) for s in seeds]
        theta = np.array(DPOptions().theta0)
        theta[[0, 5, 8]] = supply.theta[[0, 5, 8]]
        st = run_stage("SI2", trials, supply, theta, DPOptions(passes=1, covariance=covariance))
        f = list(st.free)
        out.append((st.theta_full[f] - supply.theta[f]) / np.sqrt(np.diag(st.theta_cov)[f]))
    return np.array(out)


@pytest.mark.slow  # ~10 s per realisation on an idle core (PEM: ~900 filter evaluations)
def test_si2_std_cover_the_error_with_unknown_noise(supply):
    """5 realisations, 30 errors/std: RMS within [0.55, 1.6] and ≥ 80 % inside ±2 std.

    The bound fails for the filter's P_θθ with assumed noise (``covariance="ekf"``, the method
    before issue 15): RMS of error/std 4.2 and 40 % inside ±2 std on these realisations; with
    ``"observed"`` it measured RMS 1.11 and 93 %.
    """
    z = si2_errors_over_std(supply, 5, "observed")
    rms = float(np.sqrt(np.mean(z ** 2)))
    assert 0.55 <= rms <= 1.6, z
    assert np.mean(np.abs(z) <= 2.0) >= 0.8, z


@pytest.mark.slow
def test_full_pipeline_coverage_campaign():
    """12 realisations of the whole study (six 1200-s trials each) through the campaign engine."""
    from shipid.campaign.engine import run_campaign

    # two workers (CI has two cores); the engine's results do not depend on the number of workers
    res = run_campaign("shipid.methods.dp.coverage:run_one", 12, seed=3, workers=2, progress=False)
    s = summarise(res.outputs)
    assert s["ok"] == 12
    assert s["pooled"]["cover_2sd"] >= 0.85
    assert 0.6 <= s["pooled"]["rms_error_over_std"] <= 1.5
    for p in s["parameters"].values():
        assert p["cover_2sd"] >= 0.65


def test_summary_counts_errors_within_the_accuracy_band():
    """``within_band`` counts |relative error| ≤ 10 % (θ3: 25 %) per θ; a run that failed is not counted."""
    rel = np.array([[0.05] * 9, [0.12] * 9, [-0.2] * 9, [0.3] * 9])
    outs = [{"error_sigma": [0.5] * 9, "relative_error": r.tolist(), "status": ["estimated"] * 9,
             "settled": {"SI1": True}, "seconds": 1.0} for r in rel] + [None]
    s = summarise(outs)
    assert s["ok"] == 4 and s["failed"] == 1
    for j in range(9):
        p = s["parameters"][f"theta{j + 1}"]
        assert p["band_pct"] == pytest.approx(100 * ACCURACY_BAND[j])
        assert p["within_band"] == (3 if j == 2 else 1)  # θ3: 5, 12 and -20 % (not 30 %); the rest: 5 % only
        assert p["mean_abs_rel_error_pct"] == pytest.approx(100 * np.mean(np.abs(rel[:, j])))
