"""Units at the edges: parsing, conversion to SI and back (pint underneath)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shipid.io import read_trial
from shipid.io.units import from_si, parse_unit, split_header, to_si
from shipid.errors import InputError

# SI unit of every unit the issue asks for, plus the tolerated spellings
SI_OF = {
    "s": "s", "m": "m", "m/s": "m/s", "knot": "m/s", "kn": "m/s", "rad": "rad", "deg": "rad",
    "rad/s": "rad/s", "deg/s": "rad/s", "rps": "1/s", "rpm": "1/s", "Hz": "1/s", "1/s": "1/s",
    "m/s^2": "m/s^2", "m/s2": "m/s^2", "N": "N", "kN": "N", "N*m": "N*m", "Nm": "N*m", "kN*m": "N*m",
    "-": "-", "%": "-", "min": "s",
}


@pytest.mark.parametrize("unit,si", sorted(SI_OF.items()))
def test_si_unit_of_each_required_unit(unit, si):
    assert parse_unit(unit) == si


@pytest.mark.parametrize("unit,value,expected", [
    ("deg", 180.0, math.pi),                 # definition of the degree
    ("knot", 1.0, 1852.0 / 3600.0),          # 1 international knot = 1852 m/h
    ("rpm", 60.0, 1.0),                      # revolutions per minute -> per second, no 2*pi
    ("rps", 10.23, 10.23),
    ("Hz", 2.0, 2.0),
    ("deg/s", 1.0, math.pi / 180.0),
    ("kN", 1.5, 1500.0),
    ("kN*m", 2.0, 2000.0),
    ("Nm", 3.0, 3.0),
    ("%", 50.0, 0.5),
    ("min", 2.0, 120.0),
    ("m/s^2", 9.81, 9.81),
])
def test_to_si_known_values(unit, value, expected):
    got, _ = to_si([value], unit)
    assert got[0] == pytest.approx(expected, rel=1e-15)


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(-1e6, 1e6, allow_nan=False), min_size=1, max_size=20),
       st.sampled_from(["deg", "knot", "rpm", "deg/s", "kN*m", "%", "rps"]))
def test_round_trip(values, unit):
    x = np.array(values)
    si, si_unit = to_si(x, unit)
    back = from_si(si, unit, si=si_unit)
    np.testing.assert_allclose(back, x, rtol=1e-14, atol=1e-9)


def test_pairs_round_trip_explicitly():
    # deg <-> rad, knot <-> m/s, rpm <-> rps
    assert from_si(to_si([90.0], "deg")[0], "rad")[0] == pytest.approx(math.pi / 2)
    assert from_si(to_si([math.pi], "rad")[0], "deg")[0] == pytest.approx(180.0)
    assert from_si(to_si([10.0], "knot")[0], "m/s")[0] == pytest.approx(5.144444444444445)
    assert from_si(to_si([5.144444444444445], "m/s")[0], "knot")[0] == pytest.approx(10.0)
    assert from_si(to_si([600.0], "rpm")[0], "rps")[0] == pytest.approx(10.0)
    assert from_si(to_si([10.0], "rps")[0], "rpm")[0] == pytest.approx(600.0)


def test_unknown_unit_is_input_error_naming_channel():
    with pytest.raises(InputError, match=r"f\.csv, channel 'u': unknown unit 'blorps'"):
        to_si([1.0], "blorps", file="f.csv", channel="u")


def test_from_si_refuses_wrong_dimension():
    with pytest.raises(InputError, match="cannot express"):
        from_si([1.0], "m/s", si="rad", channel="psi")


def test_header_with_unknown_unit_is_a_clear_error(tmp_path):
    p = tmp_path / "u.csv"
    p.write_text("t [s],u [furlongz]\n0,1\n0.1,1\n")
    with pytest.raises(InputError) as err:
        read_trial(p)
    assert str(err.value) == f"{p}, channel 'u': unknown unit 'furlongz'"


@pytest.mark.parametrize("cell,expected", [
    ("t [s]", ("t", "s")), ("psi_hat [rad]", ("psi_hat", "rad")), ("  u  [ m/s ] ", ("u", "m/s")),
    ("p1 [-]", ("p1", "-")), ("x", ("x", None)), ("n []", ("n", "")),
])
def test_split_header(cell, expected):
    assert split_header(cell) == expected


def test_split_header_rejects_broken_brackets():
    with pytest.raises(ValueError):
        split_header("x [m]]")
