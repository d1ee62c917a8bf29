"""The output-error refinement with the compiled simulation against the reference path (compiled=False).

Both refine the same start on the same two short runs (random orders in wind, seeded noise) and must
give the same fit to round-off. The refinement amplifies round-off: the Levenberg–Marquardt step solves
normal equations whose condition is large, so a one-ulp change anywhere moves the refined coefficients
by ~1e-9 to 1e-7 relative (measured on the 32 Esso training runs: 4.8e-8 for the reference path itself
with its start states moved by one ulp, 2.1e-8 between the paths). The test therefore requires the
paths to agree to 1e-6 relative on the coefficients and the cost, and to be no further apart than the
reference is from itself after a one-ulp change of its start states, times 100.
"""

from dataclasses import replace

import numpy as np
import pytest

from shipid.methods.mmg import output_error as OE

NAMES = ("X_0F", "N_r", "NR_arm", "Y_v", "YR_gain", "XP_k0")


@pytest.fixture(scope="module")
def setup(esso_published, noisy_run):
    truth = esso_published
    runs = [noisy_run(truth, s, 70.0) for s in (41, 42)]
    start = truth.with_coef({c: 1.1 * truth.coef[c] for c in NAMES})
    cfg = OE.OEConfig(max_iter=3, decimate=2)
    H = OE.stack_horizons(runs, cfg.horizon, cfg.decimate)
    return start, runs, cfg, H


def test_predictions_agree_to_round_off(setup):
    start, _, _, H = setup
    vals = np.array([[start.coef[c] for c in NAMES]]) * np.array([[1.0], [1.05], [0.9]])
    a = OE.simulate(start, NAMES, vals, H)
    b = OE.simulate(start, NAMES, vals, H, compiled=False)
    assert np.all(np.isfinite(b))
    assert np.max(np.abs(a - b)) <= 1e-12 * np.max(np.abs(b))


def test_refinement_agrees_with_the_reference(setup):
    start, runs, cfg, H = setup
    fast = OE.refine(start, NAMES, runs, config=cfg, H=H)
    ref = OE.refine(start, NAMES, runs, config=cfg, H=H, compiled=False)
    ulp = OE.refine(start, NAMES, runs, config=cfg, H=replace(H, x0=H.x0 * (1 + 2.0 ** -52)), compiled=False)
    assert fast.iterations == ref.iterations and fast.names == ref.names
    assert ref.cost < 0.5 * ref.cost0                        # the refinement did move
    d = np.abs(fast.theta - ref.theta)
    assert np.all(d <= 1e-6 * np.abs(ref.theta)), d / np.abs(ref.theta)
    assert np.max(d) <= 100 * max(np.max(np.abs(ulp.theta - ref.theta)), 1e-15 * np.max(np.abs(ref.theta)))
    assert abs(fast.cost / ref.cost - 1) < 1e-9 and abs(fast.cost0 / ref.cost0 - 1) < 1e-12
    fin = np.isfinite(ref.cov)
    assert np.array_equal(fin, np.isfinite(fast.cov))
    np.testing.assert_allclose(fast.cov[fin], ref.cov[fin], rtol=1e-5)
