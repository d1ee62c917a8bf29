"""Decision rule of the heldout9 follow-up variants (shipid.methods.mmg.study_ext2.decide)."""

from shipid.methods.mmg import study_ext2 as X


def _s(score, folds):
    return {"score": score, "fold_scores": folds}


def test_a_variant_must_gain_in_pool_and_in_most_folds_beyond_the_fold_spread():
    base = _s(1.345, [0.97, 1.50, 1.40, 1.37])
    ok = X.decide(base, _s(1.288, [0.93, 1.43, 1.33, 1.31]))
    assert ok["passes"] and ok["folds_better"] == 4 and ok["gain"] > X.MIN_GAIN
    small = X.decide(base, _s(1.335, [0.96, 1.49, 1.39, 1.36]))       # every fold better, pooled gain 0.010
    assert not small["passes"] and small["folds_better"] == 4
    two = X.decide(base, _s(1.30, [0.80, 1.30, 1.45, 1.42]))            # large gain from two folds only
    assert not two["passes"] and two["folds_better"] == 2
    noisy = X.decide(base, _s(1.32, [0.50, 1.49, 1.39, 1.90]))          # 3 of 4 better but mean difference +
    assert not noisy["passes"] and noisy["folds_better"] == 3 and noisy["mean_fold_difference"] > 0


def test_retimed_cv_of_runs_without_offsets_is_the_plain_cv(esso_published, own_run):
    """On runs a model made itself (no channel offsets) the offsets come out 0 in every fold and the CV on
    re-timed runs repeats study_oe.cv_refinement's output-error scores, fold by fold."""
    import numpy as np
    import pytest

    from shipid.methods.mmg import candidates_ext2 as E2
    from shipid.methods.mmg import output_error as OE

    trials = [own_run(esso_published, 130.0, rudder_deg=a, period=p) for a, p in ((15.0, 40.0), (25.0, 60.0))]
    cand = {E2.BASE_NAME: E2.base_candidate()}
    cfg = OE.OEConfig(max_iter=1)
    plain = X.cv_variants(trials, [E2.BASE_NAME], cand, folds=2, oe_config=cfg)[E2.BASE_NAME]
    moved = X.cv_retimed(trials, E2.BASE_NAME, cand[E2.BASE_NAME], folds=2, oe_config=cfg)
    assert all((lg["psi"], lg["uv"], lg["r"]) == (0.0, 0.0, 0.0) for lg in moved["lags"])
    assert len(plain["fold_scores"]) == 2 and np.all(np.isfinite(plain["fold_scores"]))
    assert moved["fold_scores"] == pytest.approx(plain["fold_scores"], rel=1e-6)
    assert moved["score"] == pytest.approx(plain["score"], rel=1e-6)
