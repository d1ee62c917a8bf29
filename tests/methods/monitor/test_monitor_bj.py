"""The monitor's Box-Jenkins prefilter (shipid.methods.monitor.bj_prefilter): blockwise 1/C equals the whole-record
filter, the transient length, and a seeded wave-roll stream without sensor noise through the BJ mode."""

from dataclasses import replace

import numpy as np
import pytest
from known.linder2015 import true_value
from scipy.signal import lfilter

from shipid.methods.masscm.noise_bj import ma_poly
from shipid.methods.masscm.options import MassCMOptions
from shipid.methods.monitor.bj_prefilter import inverse_c, structure_of, transient_samples
from shipid.methods.monitor.estimator import MonitorOptions, run_monitor
from shipid.models.roll_reduced import KnownParams
from shipid.models.roll_sim import NoiseSpec
from shipid.simulate.masscm_stream import StreamSpec, simulate_stream, truth_at

KN = KnownParams.from_vessel()
Z_F = true_value("z_f")


class _S:
    zc = None
    ghist = None


def test_inverse_c_blockwise_equals_whole_record():
    rng = np.random.default_rng(11)
    x = rng.standard_normal((3, 1000))
    C = ma_poly(0.97, 2)
    whole = lfilter([1.0], C, x, axis=1)
    sm, hist, out = _S(), 8, []
    prev = np.zeros((3, hist))
    for a in range(0, 1000, 250):
        S = np.hstack([prev, x[:, a:a + 250]])
        G = inverse_c(S, sm, C, hist)
        assert G.shape == S.shape
        out.append(G[:, hist:])
        prev = x[:, a + 250 - hist:a + 250]
    np.testing.assert_allclose(np.hstack(out), whole, rtol=1e-12, atol=1e-12)
    assert structure_of(C) == pytest.approx((0.97, 2))


def test_transient_samples():
    o = MassCMOptions()
    C = ma_poly(0.99, 2)
    m = int(np.ceil(np.log(o.transient_tol) / np.log(np.sqrt(0.99))))
    assert transient_samples(C, o, 10**6) == 2 * m
    assert transient_samples(C, o, 1000) == int(o.transient_max * 1000)
    assert transient_samples(np.ones(1), o, 1000) == 0


@pytest.mark.slow
def test_bj_mode_waves_without_sensor_noise():
    """Seed 4243, a 600-s stream with the change at 300 s, 0.5 deg wave roll and noise-free sensors: the start-up
    run gives a usable model (with the AR(40) prefilter it failed in 11 of 20 such streams) and the change is
    detected within 120 s."""
    sim = simulate_stream(StreamSpec(duration=600.0, change_at=300.0, noise=NoiseSpec(wave_roll_deg=0.5)), seed=4243)
    opts = MonitorOptions(masscm=replace(MonitorOptions().masscm, noise_model="auto"))
    ups = run_monitor(sim["nominal"], sim["calibration"], sim["stream"], KN, Z_F, opts)
    alarms = [u for u in ups if u.alarm]
    assert len(alarms) >= 1 and 300.0 < alarms[0].t <= 420.0
    # before the change (window of 180-300 s, no reset yet) the intervals cover the truth; after the reset the
    # short-window search can drift away on such streams (README "Known limitations", monitor bullet)
    pre = [u for u in ups if u.m is not None and 270.0 <= u.t <= 295.0]   # full 300-s windows, all before
    mt, zt = truth_at(sim["truth"], [u.t for u in pre])
    assert pre and all(abs(u.m - a) <= 2 * u.m_std and abs(u.zm_bar - z) <= 2 * u.zm_bar_std
                       for u, a, z in zip(pre, mt, zt))
    assert all(u.m_std < 0.15 and u.zm_bar_std < 0.05 for u in pre)
