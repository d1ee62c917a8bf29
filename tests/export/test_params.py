"""Parameter files: a model written as TOML/YAML with units and sources, read back by ``shipid simulate``."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from shipid.cli import main
from shipid.errors import InputError
from shipid.export import load, read_params, simulate_params, write_params
from shipid.io.files import read_trial
from shipid.io.paths import data_root
from shipid.simulate.manoeuvres import run_manoeuvre
from shipid.simulate.registry import get_ship_model


def _same_trajectory(a, b):
    for c in ("x", "y", "psi", "u", "v", "r", "delta"):
        np.testing.assert_array_equal(a[c], b[c])


@pytest.mark.parametrize("vessel, manoeuvre", [("esso-osaka", "zigzag-10"), ("supply", "dp-sway-yaw")])
def test_round_trip_simulates_the_same_trajectory(tmp_path, vessel, manoeuvre):
    """export -> read back -> simulate gives the trajectory of the model object, bit for bit (floats written
    with repr read back to the same doubles)."""
    path = write_params(load(vessel), tmp_path / "p.toml")
    trial, _, _ = simulate_params(path, manoeuvre, duration=300.0, dt=0.5)
    ref = run_manoeuvre(get_ship_model(vessel), manoeuvre, duration=300.0, dt=0.5)
    for c in ("x", "y", "psi"):
        np.testing.assert_array_equal(trial[c], ref[c])
    back = read_params(path)
    assert back.coef == load(vessel).coef


def test_file_has_units_sources_and_status(tmp_path):
    path = write_params(load("esso-osaka"), tmp_path / "e.toml")
    doc = tomllib.loads(path.read_text(encoding="utf-8"))
    assert doc["model"]["family"] == "abkowitz"
    assert doc["particulars"]["L"] == {"value": 325.0, "unit": "m"}
    y = doc["coefficients"]["Y_v"]
    assert y["value"] == -2.83e-2 and y["unit"] == "-" and y["source"] == "yr2003 Table 3"
    assert y["status"] == "published" and np.isnan(y["std"])
    assert "Yoon" in doc["sources"]["yr2003"]
    assert doc["steering"]["rudder_rate_limit"]["unit"] == "rad/s"


def test_yaml_round_trip(tmp_path):
    pytest.importorskip("yaml")
    src = load("supply")
    back = read_params(write_params(src, tmp_path / "s.yaml"))
    assert back.family == "dp" and back.coef == src.coef
    np.testing.assert_array_equal(back.model.M, src.model.M)


def test_cli_export_then_simulate_equals_simulating_the_vessel_model(tmp_path):
    """`shipid export params esso-osaka -o p.toml` then `shipid simulate p.toml zigzag-10` gives the trajectory of
    the packaged vessel's model, bit for bit. (`shipid simulate esso-osaka` itself makes the paper's measured
    trials, with the current and the sensors of the vessel file, so its file is not the reference here.)"""
    p = tmp_path / "p.toml"
    assert main(["export", "params", "esso-osaka", "-o", str(p)]) == 0
    a = tmp_path / "a.csv"
    assert main(["simulate", str(p), "zigzag-10", "--out", str(a), "--duration", "200", "--dt", "0.5"]) == 0
    ref = run_manoeuvre(get_ship_model("esso-osaka"), "zigzag-10", duration=200.0, dt=0.5)
    got = read_trial(a)
    for c in ("x", "y", "psi"):
        np.testing.assert_array_equal(got[c], ref[c])


def test_mmg_round_trip_through_the_cli(tmp_path):
    """The KVLCC2 L7 MMG set (published:kvlcc2_L7) through a parameter file simulates as `shipid simulate
    published:kvlcc2_L7` does."""
    root = data_root()
    if root is None or not (root / "params" / "kvlcc2_L7_mmg_shipmmg.yml").is_file():
        pytest.skip("KVLCC2 parameters not found (set SHIPID_DATA)")
    p = tmp_path / "k.toml"
    assert main(["export", "params", "published:kvlcc2_L7", "-o", str(p)]) == 0
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    opts = ["--duration", "60", "--speed", "1.179", "--rudder-rate", "15.8"]
    assert main(["simulate", str(p), "turning-35", "--out", str(a), *opts]) == 0
    assert main(["simulate", "published:kvlcc2_L7", "turning-35", "--out", str(b), *opts]) == 0
    _same_trajectory(read_trial(a), read_trial(b))


def test_malformed_file_is_one_error(tmp_path, capsys):
    p = tmp_path / "bad.toml"
    p.write_text("[model]\nfamily = 'mmg'\n", encoding="utf-8")
    with pytest.raises(InputError, match="malformed"):
        read_params(p)
    assert main(["simulate", str(p), "zigzag-10", "--out", str(tmp_path / "o.csv")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("shipid: error:") and len(err.strip().splitlines()) == 1 and "bad.toml" in err
