"""The registry gives a ShipModel for every packaged vessel, and each runs its trials."""

import numpy as np
import pytest

from shipid.errors import ShipidError
from shipid.simulate import registry
from shipid.simulate.manoeuvres import run_manoeuvre
from shipid.models.ship_model import ShipModel
from shipid.vessels import vessel_names


def test_every_packaged_vessel_has_a_model():
    names = {e.name for e in registry.list_vessels()}
    assert {"esso-osaka", "supply", "fishing-vessel", "nomoto"} <= names
    for stem in vessel_names():
        m = registry.get_ship_model(stem)
        assert isinstance(m, ShipModel)
        x0 = m.x0(m.service_speed)
        dx = m.f(0.0, x0, m.nominal_input(m.service_speed), m.theta)
        assert dx.shape == x0.shape and np.all(np.isfinite(dx))


def test_aliases_resolve():
    assert registry.get_ship_model("fss1996").name == "supply"


def test_unknown_vessel_and_missing_family(monkeypatch):
    with pytest.raises(ShipidError, match="unknown vessel 'titanic'.*nomoto"):
        registry.get_ship_model("titanic")
    monkeypatch.setitem(registry.FAMILIES, "supply", "shipid.models.not_written_yet")
    with pytest.raises(ShipidError, match="not available"):
        registry.get_ship_model("supply")


def test_esso_osaka_zigzag_20_switches_at_20_degrees():
    m = registry.get_ship_model("esso-osaka")
    tr = run_manoeuvre(m, "zigzag-20", duration=600.0, dt=0.5)
    cmd = tr["delta_cmd"]
    k = np.flatnonzero(np.diff(cmd)) + 1
    assert len(k) >= 3                                       # execute + at least two reversals
    psi0 = tr["psi"][k[0]]
    dpsi = np.rad2deg(tr["psi"][k[1:]] - psi0)
    before = np.rad2deg(tr["psi"][k[1:] - 1] - psi0)
    # reversal at the first sample beyond ±20° (alternating), not one sample earlier
    assert np.all(np.abs(dpsi) >= 20.0) and np.all(np.abs(before) < 20.0)
    assert np.all(np.sign(dpsi[:-1]) == -np.sign(dpsi[1:]))
    assert dpsi[0] > 0                                       # first to starboard
    assert np.abs(tr["delta"]).max() == pytest.approx(np.deg2rad(20.0))
    assert np.abs(np.diff(tr["delta"])).max() <= m.rudder_rate_limit * 0.5 * (1 + 1e-12)


@pytest.mark.parametrize("man", ["dp-surge", "dp-sway-yaw", "dp-azimuth"])
def test_supply_vessel_dp_trials(man):
    m = registry.get_ship_model("supply")
    tr = run_manoeuvre(m, man, duration=300.0, dt=0.5)
    moved = np.hypot(tr["x"], tr["y"]).max()
    assert np.all(np.isfinite(tr.stack(["x", "y", "psi"]))) and moved > 1.0
    if man == "dp-surge":       # l1 = l2: equal main propellers give no yaw (eq. 7)
        assert np.abs(tr["psi"]).max() < 1e-9 and tr["x"].max() > 10 * np.abs(tr["y"]).max()


def test_fishing_vessel_zigzag():
    m = registry.get_ship_model("fishing-vessel")
    tr = run_manoeuvre(m, "zigzag-10", duration=60.0, dt=0.05)
    k = np.flatnonzero(np.diff(tr["delta_cmd"])) + 1
    assert len(k) >= 4 and "phi" in tr


def test_unknown_vessel_lists_names_as_shipid_vessels_shows_them():
    names = sorted(e.name for e in registry.list_vessels())
    with pytest.raises(ShipidError) as err:
        registry.get_ship_model("titanic")
    for n in names:
        assert n in str(err.value)
    assert "esso_osaka" not in str(err.value) and "esso-osaka" in str(err.value)
