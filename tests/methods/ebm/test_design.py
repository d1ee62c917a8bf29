"""D-optimal PRBS design (seed 002 §5.1.4, Figs. 7–8)."""

import numpy as np
import pytest

from shipid.methods.ebm.design import log_det_criterion, prbs_criterion, prbs_grid


def test_log_det_of_orthogonal_and_collinear_regressors():
    rng = np.random.default_rng(0)
    Qm, _ = np.linalg.qr(rng.normal(size=(200, 4)))
    assert log_det_criterion(Qm) == pytest.approx(0.0, abs=1e-10)  # |W'W| = 1 at best
    a = rng.normal(size=200)
    H = np.column_stack([a, a + 1e-3 * rng.normal(size=200), rng.normal(size=200)])
    assert log_det_criterion(H) < -4


def test_larger_prbs_amplitude_is_more_informative():
    lo = prbs_criterion(10, 105, duration=500, seed=0)
    hi = prbs_criterion(35, 105, duration=500, seed=0)
    assert hi["sway"] > lo["sway"] and hi["surge"] > lo["surge"]


def test_uniform_current_does_not_change_relative_motion():
    # eqs. 1-3: at fixed speed through the water, W does not depend on the current
    a = prbs_criterion(35, 105, duration=400, seed=0, current_speed=0.0)
    b = prbs_criterion(35, 105, duration=400, seed=0, current_speed=2.0)
    assert a["sway"] == pytest.approx(b["sway"], abs=1e-8)
    # with the approach fixed over ground it does (Fig. 8)
    c = prbs_criterion(35, 105, duration=400, seed=0, current_speed=2.0, ground_speed=True)
    assert abs(c["sway"] - a["sway"]) > 1e-3


def test_grid_optimum_is_reported():
    g = prbs_grid(amplitudes=(10, 35), periods=(60, 105), duration=400, seeds=(0,))
    a, T, v = g.optimum("sway")
    i, j = np.unravel_index(np.argmax(g.sway), g.sway.shape)     # the argmax of what was computed
    assert (a, T, v) == (g.amplitudes[i], g.periods[j], g.sway[i, j])
    assert a == 35                                                # the criterion grows with the amplitude
    d = g.to_dict()
    assert d["optimum_sway"]["amplitude_deg"] == 35
