"""Observability rank test of seed 002 eq. 11 and the §3.2 absolute-position counter-example."""

import numpy as np
import pytest

from shipid.analysis.observability import ebm_observability, numerical_rank, observability_matrix
from shipid.methods.ebm.trials import simulate_trial
from shipid.models import abkowitz as ab
from shipid.models.ebm_state import EbmModel


def test_rank_of_known_systems():
    # double integrator, position measured: observable; velocity measured only: not
    F = np.array([[0.0, 1.0], [0.0, 0.0]])
    assert numerical_rank(observability_matrix(F, np.array([[1.0, 0.0]])))[0] == 2
    assert numerical_rank(observability_matrix(F, np.array([[0.0, 1.0]])))[0] == 1


@pytest.fixture(scope="module")
def zigzag_truth():
    tr = simulate_trial("zigzag-20", 400.0, seed=3, noise=False)
    p = ab.params_from_vessel()
    tc = ab.trial_conditions()
    cx, cy = tr.meta["current_speed"] * np.cos(tr.meta["current_dir"]), tr.meta["current_speed"] * np.sin(tr.meta["current_dir"])
    t = tr.t
    X = np.zeros((t.size, 17))
    X[:, 0], X[:, 1], X[:, 2] = tr["true_u_r"], tr["true_v_r"], tr["true_r"]
    X[:, 3], X[:, 4], X[:, 5] = tr["true_x"] - cx * t, tr["true_y"] - cy * t, tr["true_psi"]
    X[:, 6], X[:, 9], X[:, 12] = tr["true_X"], tr["true_Y"], tr["true_N"]
    X[:, 15], X[:, 16] = cx, cy
    model = EbmModel.from_abkowitz(p, tc["x_D"], tc["y_D"], tc["y_S"])
    std = np.array([10, 10, 0.01, 0.01, np.deg2rad(0.0008), 0.01])
    return model, t, X, std


def test_relative_position_state_is_observable_along_zigzag(zigzag_truth):
    model, t, X, std = zigzag_truth
    o = ebm_observability(model, t, X, std, every=40)
    assert np.all(o["relative"].rank == 17)
    # seed 002 §3.2: absolute position instead of relative loses one rank
    assert np.all(o["absolute"].rank == 16)
    # and the decision is not marginal: ~1e-7 vs ~1e-16 relative singular values
    assert np.min(o["relative"].min_rel_sv) > 1e-8
    assert np.max(o["absolute"].min_rel_sv) < 1e-12
