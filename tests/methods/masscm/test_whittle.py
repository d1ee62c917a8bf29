"""Tests of the frequency-domain (Whittle) refinement of the mass / CM estimate (shipid.methods.masscm.whittle)."""

import numpy as np
import pytest

from shipid.methods.masscm import pem, whittle
from shipid.methods.masscm.coverage import REGIMES
from shipid.methods.masscm.crlb_kf import DatasetModel, true_free_theta
from shipid.methods.masscm.estimator import MassCMOptions, estimate_mass_cm
from shipid.models.roll_reduced import KnownParams
from shipid.models.roll_sim import simulate_datasets
from shipid.vessels import load_vessel

VESSEL = "fishing-vessel"


def _case(regime="both", duration=120.0, seed=(4252, 0)):
    known = KnownParams.from_vessel(VESSEL)
    z_f = float(load_vessel(VESSEL).value("general", "z_f"))
    noise = REGIMES[regime]
    d = simulate_datasets(VESSEL, seed=np.random.SeedSequence(list(seed)), duration=duration, noise=noise)
    sets, locs, models = [], [], []
    for c, t in d.items():        # the data-generating local parameters (for the likelihood checks only)
        s = whittle._FSet(c, t, known, z_f)
        s.transform()
        dm = DatasetModel(VESSEL, c, known, z_f, noise, s.T)
        sets.append(s)
        models.append(dm)
        with np.errstate(divide="ignore"):      # log 0 of a zero sensor variance (waves regime)
            lg = np.log(dm.p0[20:26])
        locs.append(np.r_[dm.p0[8:20], lg, [noise.gyro_bias, noise.acc_bias, noise.gyro_bias]])
    return known, z_f, d, sets, locs, models


def test_rudder_path_dft_is_exact_and_one_band_per_bin_is_unbinned_whittle():
    """At one bin per band the banded likelihood is the plain Whittle sum over bins, with the rudder response's
    DFT from the time-domain simulation from rest (DatasetModel.mean_response), not from the transfer function."""
    known, z_f, d, sets, locs, models = _case(regime="sensors", duration=60.0)
    th = true_free_theta(VESSEL)
    for s, l, dm in zip(sets, locs, models):
        s.design_bands(th, l, False, whittle.WhittleOptions(exact=True))
        assert s.nb.size == s.w.size and np.all(s.nb == 1)
        A, S = s.matrices(th, l, False, z=s.zb)        # at given z: without the profiled initial-state term
        mu = dm.mean_response(dm.p0, s.delta)
        K = s.w.size
        y = np.column_stack([d[s.cond][c] for c in ("p", "a_s", "r")])
        E = (np.fft.rfft(y - mu, axis=0)[1:K + 1]) / np.sqrt(s.n)      # DC (biases) left out
        R = np.diag(np.exp(l[15:18]))
        direct = K * np.log(np.linalg.det(R)) + float(np.real(np.sum(np.conj(E) * (E @ np.linalg.inv(R)))))
        assert s.nll(A, S) == pytest.approx(direct, rel=1e-10)
        assert s.nll(*s.matrices(th, l, False)) <= s.nll(A, S)     # the profiled transient can only fit better


def test_banded_data_part_is_the_quadratic_form_of_the_bins():
    """With A linear in frequency and S_b held over a band, the banded sum equals the sum over its bins of
    E_j^H S_b^-1 E_j, E_j = (A_b + (w_j - w_b) A'_b) Z_j."""
    known, z_f, d, sets, locs, models = _case(duration=60.0)
    th = true_free_theta(VESSEL)
    s, l = sets[0], locs[0]
    s.design_bands(th, l, True, whittle.WhittleOptions())
    assert 20 < s.nb.size < s.w.size / 3           # bands of several bins
    A, S = s.matrices(th, l, True)
    b = np.repeat(np.arange(s.nb.size), s.nb.astype(int))
    Aj = A[b][:, :, :5] + (s.w - s.wb[b])[:, None, None] * A[b][:, :, 5:]
    E = np.einsum("kij,kj->ki", Aj, s.Z)
    W = np.linalg.inv(S)[b]
    direct = float(np.sum(s.nb * np.log(np.real(np.linalg.det(S))))
                   + np.real(np.einsum("ki,kij,kj->", np.conj(E), W, E)))
    assert s.nll(A, S) == pytest.approx(direct, rel=1e-10)


def test_frequency_slope_columns_are_the_derivative_of_the_model_columns():
    known, z_f, d, sets, locs, models = _case(regime="sensors", duration=60.0)
    th, s, l = true_free_theta(VESSEL), sets[0], locs[0]
    w = np.array([0.01, 0.05, 0.3])
    h = 1e-6
    A0 = s.matrices(th, l, False, z=np.exp(1j * w))[0]
    A1 = s.matrices(th, l, False, z=np.exp(1j * (w + h)))[0]
    A2 = s.matrices(th, l, False, z=np.exp(1j * (w - h)))[0]
    fd = (A1[:, :, :5] - A2[:, :, :5]) / (2 * h)
    np.testing.assert_allclose(A0[:, :, 5:], fd, rtol=1e-5, atol=1e-7 * np.abs(A0[:, :, :5]).max())


def test_band_count_grows_only_logarithmically_with_record_length():
    """The bands are set by the model's curves, not the bin spacing: measured 365 / 394 / 416 bands at 300 / 1200 /
    3600 s (7499 / 29999 / 89999 bins), 234 at 60 s where the bins are too coarse for the curves."""
    th = true_free_theta(VESSEL)
    counts = []
    for dur in (300.0, 1200.0):
        known, z_f, d, sets, locs, models = _case(regime="both", duration=dur, seed=(4253, 1))
        s = sets[0]
        s.design_bands(th, locs[0], True, whittle.WhittleOptions())
        counts.append(s.nb.size)
    assert counts[1] < 1.2 * counts[0]              # four times the bins, not four times the bands


def test_score_matches_finite_differences():
    known, z_f, d, sets, locs, models = _case(duration=60.0)
    th = true_free_theta(VESSEL) * 1.02
    for s, l in zip(sets, locs):
        s.design_bands(th, l, True, whittle.WhittleOptions())
    fl = [1, 9, 13, 14, 16]
    g, info = whittle.score_information(sets, th, locs, True, list(range(whittle.N_TH)), fl)
    assert np.all(np.linalg.eigvalsh(info) > 0)
    for a in list(range(whittle.N_TH)) + list(range(whittle.N_TH, whittle.N_TH + len(fl))):
        t1, t2 = th.copy(), th.copy()
        l1, l2 = [x.copy() for x in locs], [x.copy() for x in locs]
        if a < whittle.N_TH:
            h = 1e-5 * max(abs(th[a]), 0.1)
            t1[a] += h
            t2[a] -= h
        else:
            i = fl[a - whittle.N_TH]
            h = 1e-5 * max(abs(locs[0][i]), 0.1)
            l1[0][i] += h
            l2[0][i] -= h
        fd = -(whittle._objective(sets, t1, l1, True) - whittle._objective(sets, t2, l2, True)) / (2 * h)
        assert g[a] == pytest.approx(fd, rel=2e-3, abs=1e-3 * np.sqrt(info[a, a]))


@pytest.mark.slow
def test_whittle_agrees_with_pem_within_a_fraction_of_a_standard_error():
    known, z_f, d, sets, locs, models = _case(duration=150.0, seed=(4243, 1))
    r = estimate_mass_cm(list(d.items()), known, z_f=z_f, noise_check=False, options=MassCMOptions(compute="fast", refine="none"))
    start = np.array([r.value(n) for n in pem.FREE])
    fp = pem.refine(list(d.items()), known, z_f, start)
    fw = whittle.refine(list(d.items()), known, z_f, start)
    assert fp.ok and fw.ok, (fp.reason, fw.reason)
    assert fw.waves and fp.waves
    sp, sw = np.sqrt(np.diag(fp.cov)), np.sqrt(np.diag(fw.cov))
    for i in (whittle.I_M, whittle.I_ZM):
        assert abs(fw.theta[i] - fp.theta[i]) < 0.3 * sp[i]
        assert 0.85 < sw[i] / sp[i] < 1.15          # the Whittle information is asymptotically the exact one
    assert abs(fw.rho - fp.rho) < 0.3 * fp.rho_std


def test_refine_reports_failure_instead_of_estimate():
    known, z_f, d, sets, locs, models = _case(regime="sensors", duration=30.0, seed=(4245, 3))
    bad = true_free_theta(VESSEL)
    bad[pem.FREE.index("d")] = -5.0               # an unstable roll mode: no admissible likelihood at the start
    f = whittle.refine(list(d.items()), known, z_f, bad)
    assert not f.ok and f.reason


def test_option_refine_whittle_without_known_zf_warns_and_keeps_algorithm1():
    known, z_f, d, sets, locs, models = _case(regime="sensors", duration=30.0, seed=(4247, 5))
    r = estimate_mass_cm(list(d.items()), known, z_f_prior=(z_f, 0.1), noise_check=False,
                         options=MassCMOptions(compute="fast", refine="whittle"))
    rec = r.diagnostics["refine"]
    assert rec["method"] == "whittle" and not rec["applied"]
    assert any("Algorithm 1's estimate is kept" in w for w in r.diagnostics["warnings"])


def test_whiteness_check_rejects_no_wave_model_in_waves_and_accepts_it_with_sensor_noise():
    th = true_free_theta(VESSEL)
    _, _, _, sets, locs, _ = _case(regime="waves", duration=30.0, seed=(4248, 6))
    for l in locs:
        l[15:18] = np.log(1e-6)
    assert "not white" in whittle.whiteness_reason(sets, th, locs)
    _, _, _, sets, locs, _ = _case(regime="sensors", duration=60.0, seed=(4248, 7))
    assert whittle.whiteness_reason(sets, th, locs) == ""


@pytest.mark.slow
def test_coverage_study_refine_whittle_flag(capsys):
    """`study mass-cm-coverage --refine whittle` runs the refinement per run and counts the runs where it failed."""
    import json

    from shipid.cli import main
    rc = main(["study", "mass-cm-coverage", "--regime", "both", "--runs", "2", "--duration", "120",
               "--workers", "1", "--seed", "5", "--refine", "whittle", "--json"])
    assert rc in (0, None)
    s = json.loads(capsys.readouterr().out)
    assert s["refine"] == "whittle" and 0 <= s["refine_failed"] <= 2
    assert all(np.isfinite(s["quantities"][k]["spread"]) for k in ("m", "zm_bar", "rho"))


def test_option_refine_whittle_replaces_estimates_and_keeps_algorithm1():
    known, z_f, d, sets, locs, models = _case(duration=120.0, seed=(4254, 2))
    kw = dict(z_f=z_f, noise_check=False)
    r0 = estimate_mass_cm(list(d.items()), known, options=MassCMOptions(compute="fast", refine="none"), **kw)
    r1 = estimate_mass_cm(list(d.items()), known, options=MassCMOptions(compute="fast", refine="whittle"), **kw)
    rec = r1.diagnostics["refine"]
    assert rec["method"] == "whittle" and rec["applied"], rec["reason"]
    assert rec["algorithm1"]["m"] == [r0.value("m"), r0.std("m")]
    assert r1.value("m") != r0.value("m") and np.isfinite(r1.std("m")) and r1.std("m") > 0
    assert r1.covariance_names == list(pem.FREE)
