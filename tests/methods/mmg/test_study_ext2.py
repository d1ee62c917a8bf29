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


def _fake_cv(scores):
    """A stand-in for study_ext2.cv_retimed: the summary it returns for a name (base when no '/' or '+')."""
    calls = []

    def cv(trials, name, cand, *, folds=4, inputs=False, transform=None, progress=None, **kw):
        calls.append((name, cand, transform))
        key = name.split(" / ")[-1] if " / " in name else name.rsplit("+", 1)[-1] if "+astern" in name else "base"
        s, f, pos = scores[key]
        return {"score": s, "fold_scores": f, "pos_rms": pos}
    return cv, calls


def test_cv_current_keeps_the_best_current_only_when_it_passes_and_the_position_is_not_worse(monkeypatch):
    base = (1.2335, [0.908, 1.343, 1.296, 1.266], 0.515)
    scores = {"base": base, **{f"current {c.factor:g} x wind, tau {c.tau:g} s": (1.6, [1.6] * 4, 0.7)
                               for c in X.CURRENT_GRID}}
    scores["current 0.01 x wind, tau 60 s"] = (1.2295, [0.857, 1.466, 1.299, 1.151], 0.506)     # as measured
    cv, calls = _fake_cv(scores)
    monkeypatch.setattr(X, "cv_retimed", cv)
    res = X.cv_current([])
    assert res["decision"]["best"] == "current 0.01 x wind, tau 60 s" and not res["decision"]["passes"]
    assert len(calls) == 1 + len(X.CURRENT_GRID) and calls[0][2] is None and all(c[2] is not None for c in calls[1:])
    scores["current 0.01 x wind, tau 60 s"] = (1.18, [0.86, 1.29, 1.24, 1.21], 0.52)            # better, but pos worse
    assert not X.cv_current([])["decision"]["passes"]
    scores["current 0.01 x wind, tau 60 s"] = (1.18, [0.86, 1.29, 1.24, 1.21], 0.50)
    assert X.cv_current([])["decision"]["passes"]


def test_cv_astern_frees_the_reversed_propeller_terms_and_applies_the_rule(monkeypatch):
    base = (1.2335, [0.908, 1.343, 1.296, 1.266], 0.515)
    scores = {"base": base, "astern-moment": (1.2426, [0.897, 1.345, 1.265, 1.343], 0.515),
              "astern-side": (1.2467, [0.896, 1.352, 1.270, 1.348], 0.510)}
    cv, calls = _fake_cv(scores)
    monkeypatch.setattr(X, "cv_retimed", cv)
    res = X.cv_astern([])
    assert res["chosen"] is None and not any(d["passes"] for d in res["decisions"].values())
    cands = {name.rsplit("+", 1)[-1]: cand for name, cand, _ in calls[1:]}
    base_cand = X.chosen_candidate()
    assert cands["astern-moment"]["N"] == base_cand["N"] + tuple(f"NP_b{i}" for i in range(5))
    assert cands["astern-moment"]["Y"] == base_cand["Y"]
    assert cands["astern-side"]["Y"] == base_cand["Y"] + tuple(f"YP_a{i}" for i in range(5))
    scores["astern-side"] = (1.20, [0.88, 1.30, 1.26, 1.22], 0.51)
    assert X.cv_astern([])["chosen"] == "astern-side"


def _summary(score, folds, run_score, run_folds):
    """A CV summary whose mean-over-runs score is ``run_score`` (ψ̄ / 10° + p̄ / 1 m with p̄ = 0.5 m)."""
    return {"score": score, "fold_scores": folds, "psi_mean_of_runs": 10.0 * (run_score - 0.5),
            "pos_mean_of_runs": 0.5, "run_score": run_score, "fold_run_scores": run_folds}


def test_run_mean_score_is_the_targets_metric():
    assert X.run_mean_score({"psi_mean_of_runs": 6.5, "pos_mean_of_runs": 0.55}) == 0.65 + 0.55


def test_cv_robust_rule_on_the_mean_over_runs_with_a_pooled_guard(monkeypatch):
    """cv_robust scores least squares against Huber weights with the same folds and keeps Huber only when it
    passes rules 1-3 on the mean over left-out runs and its pooled score is not worse by more than 0.02."""
    from shipid.methods.mmg import output_error as OE

    def run(base, var):
        calls = []

        def cv(trials, name, cand, *, folds=4, inputs=False, oe_config=None, progress=None, **kw):
            calls.append(oe_config)
            return var if oe_config.robust is not None else base
        monkeypatch.setattr(X, "cv_retimed", cv)
        out = X.cv_robust([], k=2.0)
        assert calls[0] == OE.LEAST_SQUARES and calls[1].robust == 2.0 and calls[1].robust_passes == 2
        return out["decision"]

    base = _summary(1.2335, [0.908, 1.343, 1.296, 1.266], 1.1243, [0.868, 1.072, 1.357, 1.201])
    measured = _summary(1.2169, [0.861, 1.332, 1.285, 1.258], 1.1016, [0.809, 1.068, 1.344, 1.185])
    assert run(base, measured)["passes"]
    worse_pooled = dict(measured, score=1.26)
    assert not run(base, worse_pooled)["passes"]
    one_pass = _summary(1.2213, [0.868, 1.344, 1.286, 1.256], 1.1051, [0.817, 1.075, 1.344, 1.185])
    d = run(base, one_pass)                                   # as measured with one pass: gain 0.019 < 0.02
    assert not d["passes"] and d["folds_better"] == 3
