"""The DP result of ``shipid demo``'s report step when no real data are at hand (Fossen et al. 1996)."""

from __future__ import annotations

from shipid.methods.dp.estimator import fit_dp
from shipid.methods.dp.series import with_series
from shipid.methods.dp.trials import TrialNoise, simulate_dp_trials
from shipid.models.dp import dp_vessel
from shipid.vessels import load_vessel


def fallback(seed: int):
    """Fossen et al. (1996): the six simulated supply-vessel trials, shortened to 400 s."""
    v = dp_vessel(load_vessel("supply"))
    trials = simulate_dp_trials(v, seed, duration=400.0, n_per_kind=2, noise=TrialNoise())
    return with_series(fit_dp(trials["surge"], trials["sway-yaw"], trials["azimuth"], v, theta_true=v.theta,
                              provenance={"seed": seed,
                                          "command": "shipid demo (report step: simulated DP trials, 400 s)"}))
