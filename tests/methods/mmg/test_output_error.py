"""Output-error refinement on restarted horizons (shipid.methods.mmg.output_error) and its use in identify."""

import numpy as np
import pytest

from shipid.io import data_root
from shipid.errors import InputError
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import output_error as OE
from shipid.methods.mmg import pipeline as P
from shipid.models import mmg

ROOT = data_root()
NAMES = ("X_0F", "N_r", "NR_arm", "Y_v")


def need_params():
    if ROOT is None or not (ROOT / "params").is_dir():
        pytest.skip("shared data (params/) not found (set SHIPID_DATA)")


@pytest.fixture(scope="module")
def truth():
    need_params()
    return mmg.load_published("esso_osaka_3m")


@pytest.fixture(scope="module")
def runs_of_truth(truth, noisy_run):
    return [noisy_run(truth, s, 70.0) for s in (41, 42)]


def test_simulate_rows_equal_the_validation_simulator(truth, own_run):
    """Each horizon predicted by the batch is mmg.simulate_batch from the same measured start and inputs."""
    tr = own_run(truth, 130.0)
    H = OE.stack_horizons([tr], horizon=60.0, decimate=2)
    P1 = OE.simulate(truth, (), np.zeros((1, 0)), H)[0]
    t = tr.t[::2]
    U = np.stack([tr["delta"][::2], tr["n"][::2], np.zeros(t.size), np.zeros(t.size)], axis=-1)
    L = H.U.shape[1]
    for b in range(H.count):
        ref = mmg.simulate_batch(truth, t[0] + 0.2 * np.arange(L), H.x0[b][None], U[b * (L - 1):b * (L - 1) + L])[0]
        np.testing.assert_allclose(P1[b], ref, rtol=1e-10, atol=1e-12)
    # a noise-free run of the model itself, on its own time step: zero residuals
    H1 = OE.stack_horizons([tr], horizon=60.0, decimate=1)
    assert np.max(np.abs(OE.residuals(OE.simulate(truth, (), np.zeros((1, 0)), H1), H1))) < 1e-9


@pytest.mark.slow
def test_refine_recovers_perturbed_coefficients(truth, own_run):
    """From the truth with four coefficients 20 % off, LM on noise-free zig-zags of the truth comes back
    to the truth: errors below 4 % (the refinement integrates at 0.2 s, the runs were made at 0.1 s: a
    discretisation bias; measured 0.2-2.7 %),
    the cost falls by two orders of magnitude; with 2 horizons for 4 coefficients the horizon-cluster
    covariance is singular, so it is NaN (not determined)."""
    runs = [own_run(truth, 70.0, rudder_deg=a, period=p) for a, p in ((15.0, 40.0), (25.0, 30.0))]
    start = truth.with_coef({c: 1.2 * truth.coef[c] for c in NAMES})
    oe = OE.refine(start, NAMES, runs, config=OE.OEConfig(max_iter=8, decimate=2, rtol=1e-6))
    assert oe.cost < 1e-2 * oe.cost0
    true = np.array([truth.coef[c] for c in NAMES])
    assert np.all(np.abs(oe.theta - true) < 0.04 * np.abs(true)), (oe.theta, true)
    assert oe.horizons == 2 and np.all(np.isnan(oe.cov))


def test_refine_is_deterministic(truth, runs_of_truth):
    start = truth.with_coef({c: 1.1 * truth.coef[c] for c in NAMES})
    a = OE.refine(start, NAMES, runs_of_truth, config=OE.OEConfig(max_iter=2))
    b = OE.refine(start, NAMES, runs_of_truth, config=OE.OEConfig(max_iter=2))
    assert np.array_equal(a.theta, b.theta) and np.array_equal(a.cov, b.cov, equal_nan=True)


def test_excluded_prefixes_are_not_refined(truth, runs_of_truth):
    oe = OE.refine(truth, ("X_0F", "YP_a0", "NP_b3"), runs_of_truth, config=OE.OEConfig(max_iter=1))
    assert oe.names == ("X_0F",)


def test_identify_with_refinement_reports_sandwich_errors(truth, runs_of_truth):
    """identify(refine='output-error'): the refined coefficients say so and keep a finite SE; the
    horizon error of the training runs is not larger than the regression's."""
    base = P.identify(runs_of_truth, truth, structure="hull+rudder+thrust", select=False)
    ref = P.identify(runs_of_truth, truth, structure="hull+rudder+thrust", select=False, refine="output-error",
                     oe_config=OE.OEConfig(max_iter=2))
    d = ref.diagnostics["output_error"]
    assert d["cost_end"] <= d["cost_start"]
    for c in d["refined"]:
        e = ref.estimates[c]
        assert "output-error" in e.note
        assert (np.isfinite(e.std) and e.status == "estimated") or e.status == "not determined"
    assert "output_error" not in base.diagnostics
    assert len(ref.covariance_names) == len(base.covariance_names)
    cov = np.asarray(ref.covariance)
    np.testing.assert_allclose(cov, cov.T, atol=0)
    # the refined block is the sandwich, with no cross terms to the coefficients that were not refined
    names = list(ref.covariance_names)
    ii = [names.index(c) for c in d["refined"]]
    jj = [k for k in range(len(names)) if k not in ii]
    assert np.all(cov[np.ix_(ii, jj)] == 0.0)
    for c in d["refined"]:
        k = names.index(c)
        assert ref.estimates[c].std == np.sqrt(cov[k, k]) or not np.isfinite(cov[k, k])
    assert "sandwich" in ref.diagnostics["covariance"]["kind"]


def test_default_refine_per_structure(truth):
    assert P.default_refine(truth) == "output-error"
    assert P.default_refine(truth, "none") == "none"
    need_params()
    assert P.default_refine(mmg.load_published("kvlcc2_hsva")) == "none"


def test_unknown_refinement_is_an_input_error(truth, runs_of_truth):
    with pytest.raises(InputError, match="unknown refinement"):
        P.identify(runs_of_truth[:1], truth, structure="hull-only", select=False, refine="magic")


def test_broyden_jacobian_lowers_the_cost_and_gives_the_exact_covariance(truth, runs_of_truth):
    """jacobian='broyden': the cost falls and the covariance is the finite-difference one at the end
    point: refine restarted there with no iteration gives it again (to 5 %: its forward-difference step
    scales with the new start values, so the two Jacobians differ at the step's order)."""
    one = ("N_r",)                    # 2 horizons: enough clusters for one coefficient
    start = truth.with_coef({"N_r": 1.1 * truth.coef["N_r"]})
    b = OE.refine(start, one, runs_of_truth, config=OE.OEConfig(max_iter=2, jacobian="broyden"))
    assert b.cost < b.cost0
    again = OE.refine(b.model, one, runs_of_truth, config=OE.OEConfig(max_iter=0))
    assert np.isfinite(b.cov).all() and b.cov[0, 0] > 0
    np.testing.assert_allclose(np.sqrt(np.diag(b.cov)), np.sqrt(np.diag(again.cov)), rtol=0.05)
    with pytest.raises(InputError, match="unknown jacobian"):
        OE.refine(start, NAMES, runs_of_truth, config=OE.OEConfig(jacobian="secant"))


def test_cli_has_the_refine_option_and_no_heldout9_study():
    from click.testing import CliRunner

    from shipid.cli import cli

    out = CliRunner().invoke(cli, ["identify", "mmg", "--help"]).output
    assert "--refine" in out and "output-error" in out
    assert CliRunner().invoke(cli, ["study", "esso-osaka-heldout9", "--help"]).exit_code != 0


def test_auto_refines_only_with_enough_horizons(truth, runs_of_truth):
    """refine='auto' on two 70-s runs (2 horizons for 15 coefficients): the regression estimate, with the
    reason recorded; the same call with refine='output-error' does refine."""
    auto = P.identify(runs_of_truth, truth, structure="hull+rudder+thrust", select=False, refine="auto")
    reg = P.identify(runs_of_truth, truth, structure="hull+rudder+thrust", select=False, refine="none")
    assert auto.diagnostics["output_error"]["refined"] == []
    assert "2 restarted horizons for 15 coefficients" in auto.diagnostics["output_error"]["note"]
    assert {k: e.value for k, e in auto.estimates.items()} == {k: e.value for k, e in reg.estimates.items()}
    assert P.MIN_HORIZONS_PER_COEFFICIENT * 15 > 2


def test_overlapping_training_horizons_cluster_by_run(truth, runs_of_truth):
    """OEConfig.stride shorter than the horizon: about twice the horizons from the same runs, and the
    sandwich takes whole runs as clusters (2 runs for 4 coefficients: singular, so NaN, not determined);
    the default stride gives the non-overlapping horizons of the validation."""
    H60 = OE.stack_horizons(runs_of_truth, 15.0, 2)
    H15 = OE.stack_horizons(runs_of_truth, 15.0, 2, stride=7.5)
    assert H15.count >= 2 * H60.count - len(runs_of_truth)
    np.testing.assert_array_equal(H15.x0[0], H60.x0[0])
    cfg = OE.OEConfig(horizon=15.0, max_iter=1)
    a = OE.refine(truth, NAMES, runs_of_truth, config=cfg)
    b = OE.refine(truth, NAMES, runs_of_truth, config=OE.OEConfig(horizon=15.0, max_iter=1, stride=7.5))
    assert np.all(np.isfinite(a.cov)) and np.all(np.isnan(b.cov)) and b.horizons == H15.count
    # refine='auto' counts the clusters, not the overlapping horizons: 2 runs for 15 coefficients
    auto = P.identify(runs_of_truth, truth, structure="hull+rudder+thrust", select=False, refine="auto",
                      oe_config=OE.OEConfig(horizon=15.0, stride=7.5))
    assert auto.diagnostics["output_error"]["refined"] == []
    assert "2 runs of overlapping horizons for 15 coefficients" in auto.diagnostics["output_error"]["note"]
    np.testing.assert_array_equal(OE.cluster_index(H60, cfg), np.arange(H60.count))


def test_huber_weights_downweight_only_horizons_beyond_k_times_the_median():
    """Weights ``min(1, c / e_h)``, ``c = k · median(e_h)``; ``e_h`` counts only the valid samples."""
    B, L = 5, 4
    valid = np.ones((B, L), bool)
    valid[4, 2:] = False                                  # a horizon cut short: 2 valid samples
    e = np.array([1.0, 1.0, 2.0, 6.0, 3.0])
    r = np.zeros((B, L, 3))
    r[..., 0] = e[:, None] * valid                        # RMS over valid samples = e
    H = OE.Horizons(x0=np.zeros((B, 6)), U=np.zeros((B, L, 4)), Z=np.zeros((B, L, 6)), valid=valid,
                    h=np.zeros((B, L - 1)), run=np.arange(B))
    np.testing.assert_allclose(OE.horizon_errors(r, H), e)
    w = OE.huber_weights(r, H, 2.0)                       # median 2, c = 4
    np.testing.assert_allclose(w, [1.0, 1.0, 1.0, 4.0 / 6.0, 1.0])
    assert np.all(OE.huber_weights(np.zeros_like(r), H, 2.0) == 1.0)   # all exact: least squares


def test_robust_refinement_resists_a_horizon_the_structure_cannot_follow(truth, own_run):
    """Six noise-free runs of the truth and one of a ship whose rudder moment is 40 % weaker: least squares
    pulls NR_arm towards the odd run, Huber's weights (``OEConfig.robust``) pull it less; the odd horizon
    is the one down-weighted, and the costs compare under the final weights."""
    good = [own_run(truth, 70.0, rudder_deg=a, period=p) for a, p in
            ((10, 30), (15, 40), (20, 30), (25, 40), (30, 30), (35, 40))]
    odd = own_run(truth.with_coef({"NR_arm": 0.6 * truth.coef["NR_arm"]}), 70.0, rudder_deg=20.0, period=35.0)
    runs = good + [odd]
    names = ("NR_arm",)
    # decimate=1: integrated on the runs' own 0.1-s step, so the good runs are exact at the truth
    ls = OE.refine(truth, names, runs, config=OE.OEConfig(robust=None, max_iter=6, rtol=1e-6, decimate=1))
    hub = OE.refine(truth, names, runs, config=OE.OEConfig(robust=2.0, max_iter=6, rtol=1e-6, decimate=1))
    true = truth.coef["NR_arm"]
    assert abs(hub.theta[0] - true) < 0.5 * abs(ls.theta[0] - true), (ls.theta, hub.theta, true)
    assert hub.cost <= hub.cost0
    H = OE.stack_horizons(runs, 60.0, 1)
    r = OE.residuals(OE.simulate(ls.model, (), np.zeros((1, 0)), H), H)[0]
    w = OE.huber_weights(r, H, 2.0)
    assert w[H.run == 6].max() < 1.0 and np.all(w[H.run < 6] == 1.0), w


def test_robust_threshold_must_be_positive(truth, runs_of_truth):
    with pytest.raises(InputError, match="robust"):
        OE.refine(truth, ("N_r",), runs_of_truth, config=OE.OEConfig(robust=0.0))


def test_refined_std_count_the_shift_from_the_regression(truth, noisy_run):
    """identify(refine='output-error'): each refined coefficient's variance holds its shift from the regression
    start squared (the shift counts as one std, pipeline._covariance), the start is recorded, and the
    coefficients moved beyond 2 sandwich SE are named in one warning line."""
    runs = [noisy_run(truth, s, 300.0) for s in (51, 52, 53, 54)]          # 20 horizons for 15 coefficients
    ref = P.identify(runs, truth, structure="hull+rudder+thrust", select=False, refine="output-error",
                     oe_config=OE.OEConfig(max_iter=2))
    d = ref.diagnostics["output_error"]
    assert set(d["start"]) == set(d["refined"]) and d["horizons"] == 20
    names = list(ref.covariance_names)
    cov = np.asarray(ref.covariance)
    for c in d["refined"]:
        shift = ref.estimates[c].value - d["start"][c]
        k = names.index(c)
        assert np.isfinite(cov[k, k]) and cov[k, k] >= shift * shift * (1 - 1e-12)
        assert "shift from the regression" in ref.estimates[c].note
    assert "shift from the regression estimate counted as one standard deviation" in ref.diagnostics["covariance"]["kind"]
    lines = [w for w in ref.diagnostics["warnings"] if w.startswith("output-error refinement moved")]
    assert len(lines) == (1 if d["moved_over_2se"] else 0)
    assert set(d["moved_over_2se"]) <= set(d["refined"])
