"""Known limitations of Algorithm 1 (Linder et al. 2015) beyond the paper's noise-free §5 study.

See the "Known limitations" section of :mod:`shipid.methods.masscm.estimator`. One is a property (finite-sample bias of
the weakly determined K_vdot that shrinks with the record length: asserted), one a defect of the plain AR(40)
noise model (wrong m under narrow-band wave roll with noise-free sensors), which the default "auto" noise model
fixes (asserted both ways).
"""

import warnings

import numpy as np
import pytest
from known.linder2015 import true_value

from shipid.methods.masscm.estimator import MassCMOptions, estimate_mass_cm
from shipid.models.roll_reduced import KnownParams
from shipid.models.roll_sim import NoiseSpec, simulate_datasets

ZF = true_value("z_f")             # known to the estimator
M_TRUE, KVDOT_TRUE = true_value("m"), true_value("K_vdot")


def _estimate(seed: int, duration: float, noise: NoiseSpec, noise_check: bool = False,
              options: MassCMOptions = MassCMOptions()):
    known = KnownParams.from_vessel("fishing-vessel")
    d = simulate_datasets("fishing-vessel", seed=np.random.SeedSequence([7, seed]), duration=duration, noise=noise)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return estimate_mass_cm(list(d.items()), known, z_f=ZF, noise_check=noise_check, options=options)


def test_kvdot_bias_under_sensor_noise_shrinks_with_record_length():
    noise = NoiseSpec(acc_std=0.02)
    bias = {T: np.mean([_estimate(i, T, noise).value("K_vdot") for i in range(2)]) - KVDOT_TRUE for T in (75.0, 1200.0)}
    # measured +0.52 (75 s) and +0.09 (1200 s); a consistent estimator's bias falls with N
    assert 0 < bias[1200.0] < 0.4 * bias[75.0], bias
    r = _estimate(0, 300.0, noise)
    assert abs(r.value("m") - M_TRUE) < 3 * r.std("m")          # m is not affected
    assert "finite-sample bias" in r.estimates["K_vdot"].note


def test_wave_roll_without_sensor_noise_gives_m_within_its_standard_error():
    """The default noise model ("auto": the MA factor 1 - c q^-2 chosen by the data) handles the narrow-band
    wave roll with noise-free sensors, where plain AR(40) converged to a wrong m (1.29 ± 0.20 for seed 0)."""
    for i in range(3):
        r = _estimate(i, 300.0, NoiseSpec(wave_roll_deg=0.5))
        assert not r.diagnostics["implausible"]
        assert abs(r.value("m") - M_TRUE) < 3 * r.std("m"), (i, r.value("m"), r.std("m"))
        assert min(r.diagnostics["noise_model_selected"]["c"]) >= 0.9      # the unit-circle MA factor was found


def test_plain_ar_noise_model_fails_on_wave_roll_without_sensor_noise():
    """The defect the default fixes, kept visible: AR(40) cannot whiten the wave-roll equation error."""
    r = _estimate(0, 300.0, NoiseSpec(wave_roll_deg=0.5), options=MassCMOptions(noise_model="ar"))
    assert abs(r.value("m") - M_TRUE) > 3 * r.std("m") or r.diagnostics["implausible"]


def test_structured_ar_noise_model_handles_the_wave_roll_case():
    """``noise_model="ar-structured"`` divides the unit-circle zeros out before the AR fit; on the same three
    realisations m comes out within 3 standard errors, none flagged (measured 0.401, 0.361, 0.460)."""
    for i in range(3):
        r = _estimate(i, 300.0, NoiseSpec(wave_roll_deg=0.5), options=MassCMOptions(noise_model="ar-structured"))
        assert not r.diagnostics["implausible"] and r.diagnostics["converged"]
        assert abs(r.value("m") - M_TRUE) < 3 * r.std("m"), (i, r.value("m"), r.std("m"))


def _noise_warning(r) -> bool:
    return any("depends on the noise model" in w for w in r.diagnostics["warnings"])


def test_noise_model_check_warns_on_the_wave_failure_and_not_on_sensor_noise():
    """The AR(40) failure of the wave-only case is no longer silent: m 1.29 ± 0.20 (seed 0) is 4 combined std
    from the structured AR's 0.40 ± 0.03, and the result says so; the combined noise (waves plus sensor noise)
    gives no such warning (fresh seeds 100-119: 0 of 20 warned, and all 9 wave-only estimates beyond 3 std
    were warned or flagged)."""
    # the check belongs to the plain AR(40) model of Algorithm 1 (not refined: combined noise would be by default)
    ar = MassCMOptions(noise_model="ar", refine="none")
    wave = _estimate(0, 300.0, NoiseSpec(wave_roll_deg=0.5), noise_check=True, options=ar)
    chk = wave.diagnostics["noise_model_check"]
    assert chk["z"] > 1.5 and _noise_warning(wave)
    assert abs(chk["m"] - M_TRUE) < 3 * chk["m_std"]
    ok = _estimate(0, 300.0, NoiseSpec.combined(), noise_check=True, options=ar)
    assert ok.diagnostics["noise_model_check"]["z"] < 1.5 and not _noise_warning(ok)
