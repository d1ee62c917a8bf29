"""The ``refine="auto"`` rule of shipid.methods.masscm.refine (when to refine Algorithm 1's mass / CM estimate).

The cases here are at seeds the thresholds were not chosen on (those were SeedSequence([s, 0]), s = 100..199)."""

import warnings

import numpy as np
import pytest
from click.testing import CliRunner

from shipid.cli import cli

from shipid.methods.masscm import plausibility, refine
from shipid.methods.masscm.assemble import estimate_mass_cm as algorithm1
from shipid.methods.masscm.coverage import REGIMES, run_one
from shipid.methods.masscm.estimator import MassCMOptions, estimate_mass_cm
from shipid.models.roll_reduced import KnownParams
from shipid.models.roll_sim import NoiseSpec, simulate_datasets
from shipid.vessels import load_vessel

VESSEL = "fishing-vessel"
KNOWN = KnownParams.from_vessel(VESSEL)
ZF = float(load_vessel(VESSEL).value("general", "z_f"))


def _data(regime, duration=120.0, seed=(5150, 0)):
    noise = NoiseSpec() if regime == "none" else REGIMES[regime]
    return list(simulate_datasets(VESSEL, seed=np.random.SeedSequence(list(seed)), duration=duration,
                                  noise=noise).items())


def _alg1(d):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return algorithm1(d, KNOWN, z_f=ZF, noise_check=False, options=MassCMOptions(compute="fast", refine="none"))


def test_sensor_noise_test_separates_noise_free_from_noisy_sensors():
    # noise-free sensors leave the discretisation / model floor (~1e-3); the issue-3 gyro noise ~0.02
    levels = {g: refine.sensor_noise_level(_data(g))["level"] for g in ("none", "waves", "sensors", "both")}
    assert levels["none"] < refine.SENSOR_NOISE_MIN and levels["waves"] < refine.SENSOR_NOISE_MIN, levels
    assert levels["sensors"] > refine.SENSOR_NOISE_MIN and levels["both"] > refine.SENSOR_NOISE_MIN, levels
    # and the statistic measures the gyro noise over the signal: ten times less noise, about ten times lower level
    lo = refine.sensor_noise_level(list(simulate_datasets(VESSEL, seed=np.random.SeedSequence([5150, 0]),
                                                          duration=120.0, noise=NoiseSpec(gyro_std=0.0002,
                                                                                          acc_std=0.002)).items()))
    assert 0.05 < lo["level"] / levels["sensors"] < 0.2, (lo["level"], levels["sensors"])


def test_table3_data_are_noise_free_for_the_rule():
    # the 60-s noise-free datasets of Table 3 (data seed 0)
    s = refine.sensor_noise_level(list(simulate_datasets(VESSEL, seed=0).items()))
    assert not s["detected"] and s["level"] < 0.5 * refine.SENSOR_NOISE_MIN


def test_wave_colour_test_separates_waves_from_white_sensor_noise():
    sens, both = (refine.wave_colour(_data(g))["level"] for g in ("sensors", "both"))
    assert sens < refine.WAVE_Z_MIN < both, (sens, both)
    # a white residual gives z ~ N(0, 1)
    rng = np.random.default_rng(5)
    z = [refine.portmanteau_z(rng.standard_normal(6000), 10, 150) for _ in range(20)]
    assert abs(np.mean(z)) < 1.0 and 0.4 < np.std(z) < 1.8, z


def test_rule_refines_waves_with_sensor_noise_only():
    both = _data("both")
    engine, rec = refine.choose(both, _alg1(both), ZF)
    assert engine == refine.auto_engine(both) == "pem", rec          # 120-s records: the exact likelihood
    assert rec["sensor_test"]["detected"] and rec["wave_test"]["detected"]
    engine, rec = refine.choose(both, None, None)          # z_f unknown: nothing to refine
    assert engine == "none" and rec["decision_reason"] == "z_f not known"
    for regime, why in (("waves", "no sensor noise"), ("sensors", "no wave colour"), ("none", "no sensor noise")):
        engine, rec = refine.choose(_data(regime), None, ZF)
        assert engine == "none" and why in rec["decision_reason"], (regime, rec)


def test_default_on_noise_free_data_is_algorithm1_and_records_the_decision():
    d = list(simulate_datasets(VESSEL, seed=0).items())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = estimate_mass_cm(d, KNOWN, z_f=ZF, options=MassCMOptions(compute="fast"))
        r0 = estimate_mass_cm(d, KNOWN, z_f=ZF, options=MassCMOptions(compute="fast", refine="none"))
    assert MassCMOptions().refine == "auto"
    rec = r.diagnostics["refine"]
    assert rec["mode"] == "auto" and rec["decision"] == "none" and not rec["applied"]
    assert "no sensor noise" in rec["decision_reason"]
    assert not any("refine" in w.lower() for w in r.diagnostics.get("warnings", []))   # a skip is not a failure
    for k in r.estimates:      # bit-identical (np.array_equal: a std that is nan in both counts as equal)
        assert np.array_equal([r.value(k), r.std(k)], [r0.value(k), r0.std(k)], equal_nan=True), k
    assert r0.diagnostics["refine"]["decision"] == "none"


def test_unknown_refine_mode_is_refused():
    with pytest.raises(ValueError, match="refine must be one of"):
        refine.apply(None, [], KNOWN, ZF, "whatever")


def test_coverage_text_counts_the_refined_runs():
    # sensor noise alone: the default refines none of them (Algorithm 1 is at the bound there)
    res = CliRunner().invoke(cli, ["study", "mass-cm-coverage", "--regime", "sensors", "--runs", "2", "--duration",
                                   "60", "--workers", "1", "--seed", "5152"])
    assert res.exit_code == 0, res.output
    line = next(x for x in res.output.splitlines() if "refine auto:" in x)
    assert "refined in 0 of 2 runs" in line, line


@pytest.mark.slow
def test_default_refines_a_both_regime_run_and_keeps_algorithm1_beside_it():
    """300-s records (the study's length), waves and sensor noise: the default refines; the decision, the tests
    and Algorithm 1's estimate are in the record."""
    o = run_one(0, 5151, regime="both")
    assert o["refine_decision"] == "pem" and o["sensor_level"] > refine.SENSOR_NOISE_MIN
    assert o["pem_ok"], o["pem_reason"]
    assert o["m"] != o["iv_m"] and abs(o["m"] - 0.4) < 3 * o["m_std"]


def test_plausibility_is_judged_again_on_the_refined_estimate():
    from dataclasses import replace

    r = _alg1(_data("both"))
    assert not r.diagnostics["implausible"]
    # Algorithm 1's judgement (here made stale: a nuisance split it did not have) and its line go when the
    # (here: unchanged, physical) estimate is judged again
    stale = plausibility.Judgement([], ["A_x <= 0"])
    r.diagnostics.update(stale.diagnostics())
    r.diagnostics["warnings"] += stale.warnings()
    kept = list(r.diagnostics["warnings"][:-1])
    r.diagnostics["refine"] = {"applied": True}
    refine.rejudge(r, KNOWN, ZF)
    assert r.diagnostics["warnings"] == kept
    assert r.diagnostics["nuisance_outside_physical"] == []
    assert r.diagnostics["refine"]["algorithm1_plausibility"]["nuisance_outside_physical"] == ["A_x <= 0"]
    # a refined m that is not a load (far below zero beyond its std) is flagged, with the entry relabelled
    r.estimates["m"] = replace(r.estimates["m"], value=-1.0, std=0.01)
    refine.rejudge(r, KNOWN, ZF)
    assert r.diagnostics["implausible"] and r.estimates["m"].status == "not determined"
    assert sum(w.startswith("implausible solution: ") for w in r.diagnostics["warnings"]) == 1
    # ... and an estimate that the next judgement finds plausible is an estimate again, with its own note
    good = dict(r.estimates)
    r.estimates["m"] = replace(r.estimates["m"], value=0.4, std=0.02)
    refine.rejudge(r, KNOWN, ZF)
    assert not r.diagnostics["implausible"]
    assert [r.estimates[n].status for n in ("m", "zm_bar", "rho")] == ["estimated", "estimated", "derived"]
    assert not any(r.estimates[n].note.startswith("implausible") for n in ("m", "zm_bar", "rho"))
    assert r.estimates["k"] == good["k"]


def test_auto_engine_is_the_exact_likelihood_on_short_records_and_whittle_on_long_ones():
    short = [("nominal", {"p": np.zeros(refine.EXACT_MAX_SAMPLES)})]
    long_ = [("nominal", {"p": np.zeros(refine.EXACT_MAX_SAMPLES + 1)})]
    assert refine.auto_engine(short) == "pem" and refine.auto_engine(long_) == "whittle"


def test_rule_statistics_do_not_depend_on_the_blas_thread_count():
    """The two tests' statistics (long ``X^T X`` and dot products) are the same bits with one or two BLAS threads
    (on a machine where OpenBLAS splits them, two threads changed the wave statistic by ~1e-12 before they ran
    under one thread)."""
    from threadpoolctl import threadpool_limits

    class _Trial(dict):
        pass

    rng = np.random.default_rng(5)
    data = []
    for cond in ("nominal", "calibration", "loaded"):
        tr = _Trial({k: np.cumsum(rng.standard_normal(30_000)) * 1e-2 + rng.standard_normal(30_000)
                     for k in ("p", "a_s", "r", "delta")})
        tr.t = np.arange(30_000) * 0.02
        data.append((cond, tr))
    recs = []
    for threads in (1, 2):
        with threadpool_limits(threads):
            recs.append(refine.choose(data, None, ZF)[1])
    for test in ("sensor_test", "wave_test"):
        assert recs[0][test]["level"] == recs[1][test]["level"]
