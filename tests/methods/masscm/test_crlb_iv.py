"""The time-domain optimal-IV covariance with the Box-Jenkins noise model (shipid.methods.masscm.crlb_iv)."""

import numpy as np

from shipid.methods.masscm.crlb_iv import crlb_iv
from shipid.models.roll_sim import NoiseSpec


def test_iv_bound_is_finite_shrinks_with_record_length_and_finds_the_wave_structure():
    noise = NoiseSpec(wave_roll_deg=0.5)
    short = crlb_iv(noise=noise, duration=60.0, n_rudder=1, noise_duration=300.0, transient=10.0)
    long = crlb_iv(noise=noise, duration=240.0, n_rudder=1, noise_duration=300.0, transient=10.0)
    for k in ("m", "zm_bar", "rho"):
        assert np.isfinite(short["bounds"][k]["std"]) and short["bounds"][k]["std"] > 0
        assert 1.4 < short["bounds"][k]["std"] / long["bounds"][k]["std"] < 3.0, k    # ~ sqrt(4) (rudders differ)
    assert all(k == 2 for _c, k, _lam in short["noise_models"].values())             # (1 - c q^-2)^2 found
