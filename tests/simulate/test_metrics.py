"""Turning-circle and zig-zag measures on cases with known answers."""

import numpy as np
import pytest

from shipid.io.trial import Trial
from shipid.errors import InputError
from shipid.simulate.manoeuvres import run_manoeuvre
from shipid.simulate.metrics import heading_overshoots, turning_metrics, zigzag_metrics
from shipid.simulate.nomoto import nomoto_model


@pytest.mark.parametrize("name,side", [("turning-30", 1), ("turning-30-port", -1)])
def test_turning_circle_of_a_nearly_instant_ship_is_a_circle(name, side):
    # T = 0.01 s and an effectively unlimited rudder rate: the path is a circle of radius
    # R = U / (K δ) from the execute point, so advance = transfer = R and tactical = 2R
    # (up to the lag U·T = 0.075 m and the 1-sample rudder step).
    U, K = 7.5, 0.15
    m = nomoto_model(K=K, T=0.01, U=U, rudder_rate_limit=1e3)
    tr = run_manoeuvre(m, name, duration=200.0, dt=0.01)
    R = U / (K * np.deg2rad(30.0))
    tm = turning_metrics(tr)
    assert tm.side == side
    assert tm.advance == pytest.approx(R, abs=0.2)
    assert tm.transfer == pytest.approx(R, abs=0.2)
    assert tm.tactical_diameter == pytest.approx(2 * R, abs=0.2)
    assert tm.steady_diameter == pytest.approx(2 * R, rel=1e-9)
    assert tm.steady_yaw_rate == pytest.approx(side * K * np.deg2rad(30.0), rel=1e-9)


def test_turning_metrics_nomoto_lag_increases_advance():
    tr = run_manoeuvre(nomoto_model(), "turning-35", duration=600.0, dt=0.1)
    tm = turning_metrics(tr)
    R = 7.5 / (0.15 * np.deg2rad(35.0))
    # steady part from t = 305 s: yaw transient e^{-(305 - 10 - 15)/20} ≈ 1e-6 left
    assert tm.steady_diameter == pytest.approx(2 * R, rel=1e-5)
    assert tm.advance > R and tm.tactical_diameter > 0


def test_zigzag_overshoot_of_a_known_heading():
    # ψ = 30° sin(ω (t − 1)) after an execute at t = 1 s (ψ = 0 before); reversals ordered
    # where d·ψ first reaches 20°: overshoot exactly 10°, the peaks (t = 6 + 10 k) lying on samples.
    t = np.arange(0, 60.0, 0.05)
    psi = np.where(t >= 1.0, np.deg2rad(30.0) * np.sin(np.pi / 10 * (t - 1.0)), 0.0)
    cmd = np.zeros_like(t)
    d = 1
    for k in range(t.size):
        if t[k] < 1.0:
            continue
        cmd[k] = d
        if d * psi[k] >= np.deg2rad(20.0):
            d = -d
            cmd[k] = d
    tr = Trial(t, {"psi": psi, "delta_cmd": cmd})
    zm = zigzag_metrics(tr, np.deg2rad(20.0))
    assert len(zm.overshoots) >= 4
    np.testing.assert_allclose(np.rad2deg(zm.overshoots), 10.0, atol=1e-9)
    assert zm.initial_turning_time == pytest.approx(10 / np.pi * np.arcsin(2 / 3), abs=0.05)


def test_heading_overshoots_of_a_known_heading_and_as_the_rudder_rule():
    # the heading of the test above: 10° exactly after each crossing of ±20°; execute at t = 1 s
    t = np.arange(0, 60.0, 0.05)
    psi = np.where(t >= 1.0, np.deg2rad(30.0) * np.sin(np.pi / 10 * (t - 1.0)), 0.0)
    k0 = int(np.flatnonzero(t >= 1.0)[0])
    np.testing.assert_allclose(np.rad2deg(heading_overshoots(t, psi, k0, np.deg2rad(20.0), 1, count=4)),
                               10.0, atol=1e-9)
    # on a simulated zig-zag (reversals on the sample where the heading reaches ±10°) the heading-only
    # rule and the rudder-event rule find the same overshoots
    tr = run_manoeuvre(nomoto_model(), "zigzag-10", duration=400.0, dt=0.1)
    zm = zigzag_metrics(tr, np.deg2rad(10.0))
    ev = np.flatnonzero(np.diff(tr["delta_cmd"]) != 0) + 1
    side = int(np.sign(tr["delta_cmd"][ev[0]]))
    ho = heading_overshoots(tr.t, tr["psi"], int(ev[0]), np.deg2rad(10.0), side, count=len(zm.overshoots))
    np.testing.assert_allclose(ho, zm.overshoots, rtol=1e-12)


def test_zigzag_metrics_on_simulation_and_errors():
    tr = run_manoeuvre(nomoto_model(), "zigzag-10", duration=400.0, dt=0.1)
    zm = zigzag_metrics(tr, np.deg2rad(10.0))
    assert len(zm.overshoots) >= 2 and all(o > 0 for o in zm.overshoots)
    assert zm.initial_turning_time > 0
    with pytest.raises(InputError):
        zigzag_metrics(run_manoeuvre(nomoto_model(), "straight", duration=20.0), 0.1)
    with pytest.raises(InputError):
        turning_metrics(run_manoeuvre(nomoto_model(), "straight", duration=20.0))


def test_metrics_tolerate_wrapped_heading():
    tr = run_manoeuvre(nomoto_model(), "turning-35", duration=300.0, dt=0.1)
    wrapped = tr.with_channels(psi=np.angle(np.exp(1j * tr["psi"])))
    a, b = turning_metrics(tr), turning_metrics(wrapped)
    assert a.tactical_diameter == pytest.approx(b.tactical_diameter, rel=1e-12)
    assert a.advance == pytest.approx(b.advance, rel=1e-12)
