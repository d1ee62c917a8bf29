"""The units that :mod:`shipid.io.units` reads without pint (canonical SI spellings, common trial-file units)
give what pint gives."""

import numpy as np
import pytest

from shipid.io.trial import CHANNELS
from shipid.io.units import COMMON_UNITS, SI_SPELLINGS, _parse, _parse_pint, _pint_expr, parse_unit, registry, to_si

#: each canonical spelling written so that only pint can read it
LONG = {"s": "second", "m": "meter", "m/s": "meter/second", "m/s^2": "meter/second**2", "rad": "radian",
        "rad/s": "radian/second", "rad/s^2": "radian/second**2", "1/s": "1/second", "kg": "kilogram",
        "kg*m^2": "kilogram*meter**2", "N": "newton", "N*m": "newton*meter", "-": "dimensionless"}


@pytest.mark.parametrize("unit", SI_SPELLINGS)
def test_si_spelling_is_what_pint_says(unit):
    x = np.array([1.5, -2.25e-3])
    v_pint, si_pint = to_si(x, LONG[unit])           # through the pint registry
    v, si = to_si(x, unit)                           # the table
    assert si == si_pint == unit == parse_unit(unit)
    assert np.array_equal(v, v_pint) and np.array_equal(v, x)


def test_every_channel_unit_is_read_without_pint():
    assert set(CHANNELS.values()) <= set(SI_SPELLINGS)


@pytest.mark.parametrize("unit", sorted(COMMON_UNITS))
def test_common_unit_is_what_pint_says(unit):
    expr = _pint_expr(unit)
    assert _parse(unit) == _parse_pint(unit, expr)            # the same SI unit and the same double as pint
    x = np.array([1.5, -2.25e-3, 1e300])
    v, si = to_si(x, unit)
    ureg = registry()
    want = np.asarray(ureg.Quantity(x, expr).to_base_units().magnitude, dtype=np.float64)
    assert si == parse_unit(unit) and np.array_equal(v, want)
