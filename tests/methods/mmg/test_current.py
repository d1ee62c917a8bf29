"""The wind-driven current of :mod:`shipid.methods.mmg.current`: its low-pass and the water-frame transform."""

import numpy as np
import pytest

from shipid.io.trial import Trial
from shipid.methods.mmg.current import DriftCurrent, drift_velocity, to_water_frame
from shipid.models.mmg_forces import apparent_wind


def test_drift_is_the_factor_times_the_downwind_air_velocity_low_passed_causally():
    t = np.arange(0.0, 600.0, 0.1)
    U = np.where(t < 100.0, 2.0, 4.0)                       # a step in wind speed at 100 s
    g = np.full_like(t, np.deg2rad(30.0))                    # blowing from 30 deg (clockwise from x0)
    cx, cy = drift_velocity(t, U, g, DriftCurrent(0.02, tau=60.0))
    down = -np.array([np.cos(g[0]), np.sin(g[0])])           # the air moves away from where it blows from
    np.testing.assert_allclose(cx[:900] / 0.02, 2.0 * down[0], rtol=1e-12)   # started at the first sample
    np.testing.assert_allclose(cy[:900] / 0.02, 2.0 * down[1], rtol=1e-12)
    # one time constant after the step: 1 - 1/e of the way to the new value, and nothing before it
    k = int(round(160.0 / 0.1))
    frac = (np.hypot(cx[k], cy[k]) / 0.02 - 2.0) / 2.0
    assert frac == pytest.approx(1.0 - np.exp(-1.0), abs=2e-3)
    assert np.hypot(cx[999], cy[999]) == pytest.approx(0.04, rel=1e-12)        # causal: the step at 100 s is
    # not seen before it; a gap in the time base (99.9 s -> 160 s) decays the filter by the gap's length
    t2 = np.concatenate([t[:1000], t[1000:] + 60.0])
    c2 = drift_velocity(t2, U, g, DriftCurrent(0.02, tau=60.0))[0]
    assert (c2[1000] / 0.02 - 2.0 * down[0]) / (2.0 * down[0]) == pytest.approx(1.0 - np.exp(-60.1 / 60.0), rel=1e-9)


def _run_in_current(c):
    """A water-frame manoeuvre (turning at 0.3 m/s) and the same seen over ground in a steady current ``c``."""
    t = np.arange(0.0, 200.0, 0.1)
    r = np.full_like(t, np.deg2rad(1.5))
    psi = r * t
    u, v = np.full_like(t, 0.3), np.full_like(t, -0.02)
    xw = np.concatenate([[0.0], np.cumsum((u * np.cos(psi) - v * np.sin(psi))[:-1] * 0.1)])
    yw = np.concatenate([[0.0], np.cumsum((u * np.sin(psi) + v * np.cos(psi))[:-1] * 0.1)])
    ws, wd = np.full_like(t, 2.0), np.full_like(t, np.deg2rad(200.0))
    cx, cy = c * -2.0 * np.cos(wd[0]), c * -2.0 * np.sin(wd[0])
    ground = Trial(t, {"x": xw + cx * t, "y": yw + cy * t, "psi": psi, "u": u + np.cos(psi) * cx + np.sin(psi) * cy,
                       "v": v - np.sin(psi) * cx + np.cos(psi) * cy, "r": r, "delta": 0 * t, "n": 0 * t + 10.0,
                       "wind_speed": ws, "wind_dir": wd})
    return ground, (xw, yw, u, v)


def test_water_frame_of_a_steady_current_gives_back_the_water_track_and_keeps_the_apparent_wind():
    ground, (xw, yw, u, v) = _run_in_current(0.02)
    w = to_water_frame(ground, DriftCurrent(0.02, tau=60.0))
    for name, ref in (("x", xw), ("y", yw), ("u", u), ("v", v)):
        np.testing.assert_allclose(w[name], ref, atol=1e-12, err_msg=name)
    np.testing.assert_array_equal(w["psi"], ground["psi"])
    # the air relative to the ship does not depend on the frame the water is seen in
    a0 = apparent_wind(ground["wind_speed"], ground["wind_dir"], ground["psi"], ground["u"], ground["v"])
    a1 = apparent_wind(w["wind_speed"], w["wind_dir"], w["psi"], w["u"], w["v"])
    np.testing.assert_allclose(a1[0], a0[0], rtol=1e-12)
    np.testing.assert_allclose(np.angle(np.exp(1j * (a1[1] - a0[1]))), 0.0, atol=1e-12)
    assert w.meta["repairs"][-1]["kind"] == "water-frame" and w.meta["current"] == {"factor": 0.02, "tau": 60.0}
    assert to_water_frame(ground, DriftCurrent(0.0)) is ground
