"""Manoeuvres on a first-order Nomoto ship (T ṙ + r = K δ) and a toy DP vessel.

The Nomoto ship has known steady answers: in a turning circle r → K δ and the steady
diameter is 2U / |r| (kinematics ẋ = U cos ψ, ẏ = U sin ψ).
"""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from shipid.errors import ShipidError
from shipid.simulate.actuators import RateLimitedActuator
from shipid.simulate.manoeuvres import (PITCH_RATE, T_EXECUTE, mls_bits, parse_manoeuvre,
                                        prbs_signal, rudder_turn_sign, run_manoeuvre)
from shipid.models.ship_model import ShipModel
from shipid.simulate.nomoto import nomoto_model


def ship(K_sign=1.0, rate_deg=2.33):
    # L = 100 m, U = 7.5 m/s: K = 0.15 1/s, T = 20 s
    return nomoto_model(K=K_sign * 0.15, T=20.0, U=7.5, rudder_rate_limit=np.deg2rad(rate_deg))


def toy_dp_model():
    """Linear DP toy: surge/sway/yaw damping, thrust linear in pitch deviation from p_i0 = 0.1."""
    names = ("p1", "p2", "p3", "p4", "p5", "p6", "alpha6")

    def f(t, x, u, th):
        X, Y, psi, uu, vv, r = x
        p = u[:6] - 0.1
        a = u[6]
        tau = np.array([p[0] + p[1] + p[5] * np.cos(a), p[2] + p[3] + p[4] + p[5] * np.sin(a),
                        0.05 * (p[0] - p[1]) - 0.4 * (p[2] + p[3]) + 0.45 * p[4] + 0.34 * p[5] * np.sin(a)])
        c, s = np.cos(psi), np.sin(psi)
        return np.r_[c * uu - s * vv, s * uu + c * vv, r, tau - 0.1 * np.array([uu, vv, r])]

    return ShipModel(name="toy-dp", f=f, theta=None, state_names=("x", "y", "psi", "u", "v", "r"),
                     input_names=names, x0=lambda s: np.r_[0, 0, 0, s, 0, 0.0],
                     outputs=lambda t, X, U: {n: X[:, i] for i, n in enumerate(("x", "y", "psi", "u", "v", "r"))},
                     service_speed=0.0, heading_index=2,
                     u0=lambda s: np.array([0.1] * 6 + [np.pi / 2]))


def expected_switches(psi, k_exec, psi_sw, d0):
    """Replay the zig-zag rule on the recorded heading: indices where the rudder must reverse."""
    d, out = d0, []
    psi0 = psi[k_exec]
    for k in range(k_exec + 1, psi.size):
        if d * (psi[k] - psi0) >= psi_sw:
            d = -d
            out.append(k)
    return out


@pytest.mark.parametrize("K_sign", [1.0, -1.0])
@pytest.mark.parametrize("name,dpsi,side", [("zigzag-20", 20, 1), ("zigzag-10", 10, 1),
                                            ("zigzag-10-5-port", 5, -1)])
def test_zigzag_switches_exactly_at_first_crossing(K_sign, name, dpsi, side):
    dt = 0.2
    tr = run_manoeuvre(ship(K_sign), name, duration=400.0, dt=dt)
    psi, cmd = tr["psi"], tr["delta_cmd"]
    k_exec = int(round(T_EXECUTE / dt))
    want = expected_switches(psi, k_exec, np.deg2rad(dpsi), side)
    got = [k for k in range(k_exec + 1, cmd.size) if cmd[k] != cmd[k - 1]]
    assert len(want) >= 3
    assert got == want
    # heading first moves to the ordered side (starboard = increasing ψ), whatever the sign of K
    assert side * (psi[k_exec + 100] - psi[k_exec]) > 0
    # before execution the rudder is amidships
    assert np.all(cmd[:k_exec] == 0.0) and cmd[k_exec] != 0.0


@pytest.mark.parametrize("K_sign", [1.0, -1.0])
@pytest.mark.parametrize("name,side", [("turning-35", 1), ("turning-35-port", -1)])
def test_turning_circle_reaches_steady_turning(K_sign, name, side):
    m = ship(K_sign)
    tr = run_manoeuvre(m, name, duration=600.0, dt=0.1)
    last = tr.t > 400.0
    r = tr["r"][last]
    assert np.sign(r.mean()) == side
    # steady: r constant; its value K·35° (Nomoto steady state, transient e^{-t/T}, T = 20 s)
    r_ss = 0.15 * np.deg2rad(35.0)
    np.testing.assert_allclose(np.abs(r), r_ss, rtol=1e-6)
    # steady diameter from a least-squares circle fit of the track = 2U / r_ss
    x, y = tr["x"][last], tr["y"][last]
    M = np.column_stack([x, y, np.ones_like(x)])
    a, b, c = np.linalg.lstsq(M, x ** 2 + y ** 2, rcond=None)[0]
    D = 2 * np.sqrt(c + a ** 2 / 4 + b ** 2 / 4)
    np.testing.assert_allclose(D, 2 * 7.5 / r_ss, rtol=1e-5)


@pytest.mark.parametrize("name", ["turning-35", "zigzag-20", "prbs-20-15"])
def test_rudder_angle_and_rate_limits_respected(name):
    rate = np.deg2rad(3.0)
    m = nomoto_model(K=0.15, T=20.0, rudder_rate_limit=rate, rudder_limit=np.deg2rad(30.0))
    dt = 0.1
    tr = run_manoeuvre(m, name, duration=300.0, dt=dt, seed=3)
    d = tr["delta"]
    steps = np.abs(np.diff(d))
    assert steps.max() <= rate * dt * (1 + 1e-12)
    assert steps.max() == pytest.approx(rate * dt, rel=1e-9)     # the limit binds
    assert np.abs(d).max() <= np.deg2rad(30.0) + 1e-15
    if name == "turning-35":                                      # 35° ordered, clipped at 30°
        assert d[-1] == pytest.approx(np.deg2rad(30.0), abs=1e-15)
        # from 0 to 30° at 3°/s takes 10 s
        k = np.argmax(np.abs(d) >= np.deg2rad(30.0) - 1e-12)
        assert tr.t[k] - T_EXECUTE == pytest.approx(10.0 - dt, abs=1.01 * dt)


def test_actuator_unit():
    a = RateLimitedActuator(dt=0.5, rate_limit=2.0, lo=-3.0, hi=3.0)
    assert [a.step(10.0) for _ in range(4)] == [1.0, 2.0, 3.0, 3.0]
    assert a.step(-10.0) == 2.0
    assert a.step(2.4) == 2.4


def test_prbs_min_period_and_seed():
    t = np.arange(0, 1000.0, 0.1)
    s1 = prbs_signal(t, 1.0, 12.0, np.random.default_rng(5))
    s2 = prbs_signal(t, 1.0, 12.0, np.random.default_rng(5))
    s3 = prbs_signal(t, 1.0, 12.0, np.random.default_rng(6))
    np.testing.assert_array_equal(s1, s2)
    assert not np.array_equal(s1, s3)
    assert set(np.unique(s1)) == {-1.0, 1.0}
    edges = np.flatnonzero(np.diff(s1)) + 1
    runs = np.diff(np.r_[0, edges])                 # all complete runs (the last is open)
    assert runs.min() * 0.1 >= 12.0 - 1e-9
    assert len(edges) > 20


def test_prbs_manoeuvre_seeded():
    a = run_manoeuvre(ship(), "prbs-10-20", duration=400, dt=0.5, seed=11)
    b = run_manoeuvre(ship(), "prbs-10-20", duration=400, dt=0.5, seed=11)
    c = run_manoeuvre(ship(), "prbs-10-20", duration=400, dt=0.5, seed=12)
    np.testing.assert_array_equal(a["delta"], b["delta"])
    assert not np.array_equal(a["delta_cmd"], c["delta_cmd"])
    cmd = a["delta_cmd"][a.t >= T_EXECUTE]
    assert set(np.round(np.rad2deg(np.unique(cmd)), 12)) == {-10.0, 10.0}
    runs = np.diff(np.flatnonzero(np.diff(cmd)))
    assert runs.min() * 0.5 >= 20.0
    assert a.meta["seed"] == 11 and a.meta["manoeuvre"] == "prbs-10-20"


@pytest.mark.parametrize("m", [5, 6, 7, 8, 9, 10])
def test_shift_register_is_maximum_length(m):
    n = 2 ** m - 1
    bits = mls_bits(3 * n, np.random.default_rng(m), order=m)
    # period exactly 2^m - 1, and 2^(m-1) ones per period (m-sequence property)
    np.testing.assert_array_equal(bits[:n], bits[n:2 * n])
    assert all(not np.array_equal(bits[:n], np.roll(bits[:n], k)) for k in range(1, n) if n % k == 0)
    assert bits[:n].sum() == 2 ** (m - 1)


def test_dp_sequences_rate_limited_and_nominal():
    m = toy_dp_model()
    dt = 0.5
    for name, driven in [("dp-surge", ["p1", "p2"]), ("dp-sway-yaw", ["p3", "p4", "p5"]),
                         ("dp-azimuth", ["p6", "alpha6"])]:
        tr = run_manoeuvre(m, name, duration=600, dt=dt)
        for p in driven:
            assert f"{p}_cmd" in tr
            steps = np.abs(np.diff(tr[p]))
            lim = np.deg2rad(10.0) if p == "alpha6" else PITCH_RATE
            assert steps.max() <= lim * dt * (1 + 1e-12)
            assert steps.max() == pytest.approx(lim * dt)
        for p in set(m.input_names) - set(driven):        # others held at the nominal inputs
            assert np.all(tr[p] == (np.pi / 2 if p == "alpha6" else 0.1))
        if name == "dp-surge":           # main propellers only: no sway, no yaw in this toy model
            assert np.abs(tr["y"]).max() < 1e-12 and np.abs(tr["psi"]).max() < 1e-12
            assert tr["p1"].max() == pytest.approx(0.6)   # nominal 0.1 + step 0.5
    tr = run_manoeuvre(m, "dp-azimuth-0.3", duration=600, dt=dt)
    assert set(np.round(np.rad2deg(np.unique(tr["alpha6_cmd"])), 9)) == {45.0, 90.0, 135.0}
    assert tr["p6"].max() == pytest.approx(0.4)


def test_rudder_manoeuvre_on_dp_vessel_is_clear_error():
    with pytest.raises(ShipidError, match="drives delta"):
        run_manoeuvre(toy_dp_model(), "zigzag-20", duration=100)
    with pytest.raises(ShipidError, match="drives p1"):
        run_manoeuvre(ship(), "dp-surge", duration=100)


def test_rudder_turn_sign_follows_model():
    assert rudder_turn_sign(ship(1.0), 7.5) == 1.0
    assert rudder_turn_sign(ship(-1.0), 7.5) == -1.0


@pytest.mark.parametrize("text,kind", [("straight", "straight"), ("turning-35", "turning"),
                                       ("Zigzag-20", "zigzag"), ("zig-zag-10-5", "zigzag"),
                                       ("prbs-10", "prbs"), ("dp-sway-yaw", "dp"), ("dp-surge-0.3", "dp")])
def test_parse_names(text, kind):
    assert parse_manoeuvre(text).kind == kind


def test_parse_values():
    s = parse_manoeuvre("zigzag-10-5-port")
    assert s.params["delta"] == pytest.approx(np.deg2rad(10)) and s.params["psi"] == pytest.approx(np.deg2rad(5))
    assert s.params["side"] == -1
    assert parse_manoeuvre("zigzag-20").params["psi"] == pytest.approx(np.deg2rad(20))
    assert parse_manoeuvre("prbs-10").params["min_period"] == 30.0


@pytest.mark.parametrize("bad", ["", "zigzag", "zigzag-0", "zigzag-200", "turning-35-up", "prbs-10-0",
                                 "dp-heave", "dp-surge-2", "circle"])
def test_parse_rejects(bad):
    with pytest.raises(ShipidError):
        parse_manoeuvre(bad)


def test_trial_contents_and_straight():
    tr = run_manoeuvre(ship(), "straight", duration=60, dt=0.5)
    assert tr.t[-1] == 60.0 and len(tr) == 121
    assert np.all(tr["delta"] == 0) and np.allclose(tr["x"], 7.5 * tr.t)
    assert tr.units["psi"] == "rad" and tr.units["delta"] == "rad"
    assert tr.meta["vessel"] == "nomoto" and tr.meta["manoeuvre"] == "straight"
    with pytest.raises(ShipidError):
        run_manoeuvre(ship(), "straight", duration=0.05, dt=0.1)


@settings(max_examples=60, deadline=None)
@given(cmds=st.lists(st.floats(-100, 100), min_size=1, max_size=60),
       rate=st.floats(0.01, 50), lim=st.floats(0.1, 60), dt=st.floats(0.001, 2))
def test_actuator_never_exceeds_limits(cmds, rate, lim, dt):
    a = RateLimitedActuator(dt=dt, rate_limit=rate, lo=-lim, hi=lim)
    prev = 0.0
    for c in cmds:
        v = a.step(c)
        assert abs(v - prev) <= rate * dt * (1 + 1e-12) + 1e-12
        assert -lim <= v <= lim
        # moves toward the (clipped) command and never past it
        target = min(max(c, -lim), lim)
        assert min(prev, target) - 1e-12 <= v <= max(prev, target) + 1e-12
        prev = v
