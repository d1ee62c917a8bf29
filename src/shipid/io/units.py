"""Units at the edges: parse a unit string, convert values to SI and back.

Conversions are done with :mod:`pint` (one lazily created registry), after a small
alias table has put the strings found in ship trial files into a form pint reads
the way a naval architect means them:

* ``-``, ``""``, ``1`` are dimensionless; ``%`` is 0.01.
* ``rps``, ``rev/s``, ``Hz`` are revolutions (cycles) per second and convert to
  ``1/s`` with factor 1; ``rpm``, ``rev/min`` to ``1/s`` with factor 1/60. (pint's own
  ``rpm`` is ``revolution/minute`` = 2π/60 rad/s; propeller revolutions are not stored
  as an angular rate here, so the alias table handles them.)
* ``kn``, ``kt``, ``kts``, ``knots`` are knots (1852/3600 m/s).
* ``Nm``, ``kNm`` are N·m and kN·m (pint alone would read ``Nm`` as something else).
* ``m/s2``, ``deg/s2`` are ``m/s^2``, ``deg/s^2``; ``°`` is ``deg``.

Angles keep ``rad`` in their SI unit (``deg/s`` → ``rad/s``) although pint treats the
radian as dimensionless, because a heading and a pitch ratio must not look alike.

Every SI unit is written in the canonical spelling used by
:data:`shipid.io.trial.CHANNELS`: ``s, m, m/s, m/s^2, rad, rad/s, 1/s, N, N*m, -``,
``kg``, ``kg*m^2`` ...
"""

from __future__ import annotations

import math
import re
from functools import lru_cache

import numpy as np

from shipid.errors import InputError
from shipid.io.trial import CHANNELS

_ALIASES: dict[str, str] = {
    "-": "dimensionless", "": "dimensionless", "1": "dimensionless", "none": "dimensionless",
    "%": "percent",
    "rps": "1/s", "rev/s": "1/s", "r/s": "1/s", "1/s": "1/s", "hz": "1/s",
    "rpm": "1/minute", "rev/min": "1/minute", "r/min": "1/minute", "1/min": "1/minute",
    "kn": "knot", "kt": "knot", "kts": "knot", "knots": "knot", "knot": "knot",
    "nm": "newton*meter", "n.m": "newton*meter", "n m": "newton*meter",
    "knm": "kilonewton*meter", "kn.m": "kilonewton*meter",
    "°": "degree", "deg": "degree", "degs": "degree", "degrees": "degree",
    "°/s": "degree/second", "deg/s": "degree/second",
    "m/s2": "meter/second**2", "deg/s2": "degree/second**2", "rad/s2": "radian/second**2",
}
# strings whose lower-case form is ambiguous and must be matched with their case
_CASE_SENSITIVE: dict[str, str] = {
    "kN": "kilonewton", "kN*m": "kilonewton*meter", "N": "newton", "N*m": "newton*meter",
    "Nm": "newton*meter", "kNm": "kilonewton*meter", "MN": "meganewton",
}
# 'nm' in lower case is read as N*m, not nanometre: torques are written that way in
# trial files and nanometres never occur in them.

_SYMBOL = {"meter": "m", "second": "s", "kilogram": "kg", "radian": "rad", "kelvin": "K",
           "ampere": "A", "mole": "mol", "candela": "cd"}
_NAMED = {  # canonical spellings of derived SI units, keyed by their base-unit exponents
    (("kilogram", 1), ("meter", 1), ("second", -2)): "N",
    (("kilogram", 1), ("meter", 2), ("second", -2)): "N*m",
    (("kilogram", 1), ("meter", 2), ("second", -3)): "W",
    (("kilogram", 1), ("meter", -1), ("second", -2)): "Pa",
}


@lru_cache(maxsize=1)
def registry():
    """The shared :class:`pint.UnitRegistry` (created on first use)."""
    import pint
    return pint.UnitRegistry()


def _pint_expr(unit: str) -> str:
    u = " ".join(str(unit).strip().split())
    if u in _CASE_SENSITIVE:
        return _CASE_SENSITIVE[u]
    low = u.lower()
    if low in _ALIASES:
        return _ALIASES[low]
    return u.replace("^", "**")


def _format_si(units: dict[str, float]) -> str:
    items = tuple(sorted((k, int(round(v))) for k, v in units.items() if round(v) != 0))
    if any(abs(v - round(v)) > 1e-12 for v in units.values()):
        raise ValueError("fractional unit exponent")
    if not items:
        return "-"
    rad = [(k, e) for k, e in items if k == "radian"]
    rest = tuple((k, e) for k, e in items if k != "radian")
    if rest in _NAMED and not rad:
        return _NAMED[rest]
    order = ["radian", "kilogram", "meter", "kelvin", "ampere", "mole", "candela", "second"]
    items = sorted(items, key=lambda ke: order.index(ke[0]) if ke[0] in order else 99)

    def sym(k: str, e: int) -> str:
        s = _SYMBOL.get(k, k)
        return s if e == 1 else f"{s}^{e}"

    num = [sym(k, e) for k, e in items if e > 0]
    den = [sym(k, -e) for k, e in items if e < 0]
    text = "*".join(num) if num else "1"
    if den:
        text += "/" + ("/".join(den) if len(den) == 1 else "/".join(den))
    return text


#: Units already in the canonical SI spelling of :data:`shipid.io.trial.CHANNELS` (what ``shipid`` itself
#: writes): SI unit = the unit, factor 1, no offset, without building the pint registry (about half a second of
#: start-up). ``tests/io/test_units_si_spellings.py`` checks every entry against pint.
SI_SPELLINGS = ("s", "m", "m/s", "m/s^2", "rad", "rad/s", "rad/s^2", "1/s", "kg", "kg*m^2", "N", "N*m", "-")


_DEG = math.pi / 180.0
#: Units of trial files other than the SI spellings, read without the pint registry: unit as written -> (SI unit,
#: factor to SI). Each factor is the double pint gives (``tests/io/test_units_si_spellings.py`` checks every entry
#: against the registry); any other unit goes through pint.
COMMON_UNITS: dict[str, tuple[str, float]] = {
    **dict.fromkeys(("deg", "degs", "degree", "degrees", "°"), ("rad", _DEG)),
    **dict.fromkeys(("deg/s", "°/s"), ("rad/s", _DEG)),
    **dict.fromkeys(("deg/s^2", "deg/s2"), ("rad/s^2", _DEG)),
    "rad/s2": ("rad/s^2", 1.0), "m/s2": ("m/s^2", 1.0),
    **dict.fromkeys(("rps", "rev/s", "r/s", "Hz", "hz"), ("1/s", 1.0)),
    **dict.fromkeys(("rpm", "rev/min", "r/min", "1/min"), ("1/s", 1.0 / 60.0)),
    **dict.fromkeys(("kn", "kt", "kts", "knot", "knots"), ("m/s", 1852.0 / 3600.0)),
    "km/h": ("m/s", 1000.0 / 3600.0),
    "%": ("-", 0.01),
    "ms": ("s", 0.001), "min": ("s", 60.0), "h": ("s", 3600.0),
    "mm": ("m", 0.001), "cm": ("m", 0.01), "km": ("m", 1000.0),
    "t": ("kg", 1000.0),
    **dict.fromkeys(("Nm", "N m"), ("N*m", 1.0)),
    "kN": ("N", 1000.0), **dict.fromkeys(("kN*m", "kNm"), ("N*m", 1000.0)),
}


@lru_cache(maxsize=512)
def _parse(unit: str) -> tuple[str, str, float, bool]:
    """(pint expression, SI unit string, factor to SI, has offset) or raise ValueError."""
    expr = _pint_expr(unit)
    if unit in SI_SPELLINGS:
        return expr, unit, 1.0, False
    if unit in COMMON_UNITS:
        si, factor = COMMON_UNITS[unit]
        return expr, si, factor, False
    return _parse_pint(unit, expr)


def _parse_pint(unit: str, expr: str) -> tuple[str, str, float, bool]:
    """:func:`_parse` through the pint registry."""
    ureg = registry()
    try:
        q = ureg.Quantity(1.0, expr)
        base = q.to_base_units()
    except Exception as err:  # pint raises several types for unknown or malformed units
        raise ValueError(str(err)) from None
    si = _format_si(dict(base._units))
    offset = not ureg.Quantity(0.0, expr).to_base_units().magnitude == 0.0
    return expr, si, float(base.magnitude), offset


def parse_unit(unit: str, *, file: str | None = None, channel: str | None = None) -> str:
    """Check a unit string and return its SI unit (``"deg/s"`` → ``"rad/s"``).

    Raises
    ------
    InputError
        The unit is unknown, naming the file and channel where it was found.
    """
    try:
        return _parse(str(unit))[1]
    except ValueError:
        raise InputError(f"unknown unit '{unit}'", file=file, channel=channel) from None


def si_unit(unit: str) -> str:
    """The SI unit a value in ``unit`` is stored in (``"knot"`` → ``"m/s"``)."""
    return parse_unit(unit)


def same_dimension(unit_a: str, unit_b: str) -> bool:
    """True when values in the two units can be converted into each other."""
    return parse_unit(unit_a) == parse_unit(unit_b)


def to_si(values, unit: str, *, file: str | None = None,
          channel: str | None = None) -> tuple[np.ndarray, str]:
    """Convert ``values`` given in ``unit`` to SI.

    Parameters
    ----------
    values : array_like
        Numbers in ``unit``.
    unit : str
        Unit string as written in a file header (``"deg"``, ``"knot"``, ``"rpm"`` ...).
    file, channel : str, optional
        Where the unit came from, for the error message.

    Returns
    -------
    values_si : ndarray of float64
    si : str
        The canonical SI unit (``"rad"``, ``"m/s"``, ``"1/s"`` ...).
    """
    try:
        expr, si, factor, offset = _parse(str(unit))
    except ValueError:
        raise InputError(f"unknown unit '{unit}'", file=file, channel=channel) from None
    x = np.asarray(values, dtype=np.float64)
    if offset:  # e.g. degC: affine, let pint do it
        ureg = registry()
        return np.asarray(ureg.Quantity(x, expr).to_base_units().magnitude, dtype=np.float64), si
    return x * factor if factor != 1.0 else x.copy(), si


def to_si_view(values, unit: str) -> np.ndarray:
    """:func:`to_si` without a copy where none is needed: contiguous float64 ``values`` in an SI unit come back
    themselves (a reader's fresh column, not copied again); any conversion gives a new array."""
    expr, si, factor, offset = _parse(str(unit))
    if offset:
        return to_si(values, unit)[0]
    x = np.ascontiguousarray(values, dtype=np.float64)
    return x * factor if factor != 1.0 else x


def from_si(values, unit: str, *, file: str | None = None,
            channel: str | None = None, si: str | None = None) -> np.ndarray:
    """Convert SI ``values`` into ``unit`` (the inverse of :func:`to_si`).

    Parameters
    ----------
    si : str, optional
        The SI unit the values are in; when given it must match ``unit``'s dimension
        (``from_si(psi, "m/s", si="rad")`` is an error, not a silent scaling).
    """
    try:
        expr, target_si, factor, offset = _parse(str(unit))
    except ValueError:
        raise InputError(f"unknown unit '{unit}'", file=file, channel=channel) from None
    if si is not None and parse_unit(si, file=file, channel=channel) != target_si:
        raise InputError(f"cannot express a value in {si} as {unit}", file=file, channel=channel)
    x = np.asarray(values, dtype=np.float64)
    if offset:
        ureg = registry()
        base = ureg.Quantity(1.0, expr).to_base_units().units
        return np.asarray(ureg.Quantity(x, base).to(expr).magnitude, dtype=np.float64)
    return x / factor if factor != 1.0 else x.copy()


_HEADER = re.compile(r"^\s*(?P<name>[^\[\]]*?)\s*\[(?P<unit>[^\[\]]*)\]\s*$")
_PAREN = re.compile(r"^\s*(?P<name>[^\[\]()]*?)\s*\((?P<unit>[^\[\]()]*)\)\s*$")
#: Unit spellings read from a ``name_unit`` header cell (``time_s``, ``heading_deg``, ``speed_kn``): only
#: these, so that names such as ``x_position_mid`` or ``psi_hat`` stay whole.
UNDERSCORE_UNITS = ("s", "ms", "min", "h", "m", "km", "mm", "deg", "rad", "degs", "kn", "kt", "kts", "knots",
                    "rpm", "rps", "hz", "Hz", "N", "kN", "Nm", "kNm", "degps", "mps", "m/s", "deg/s", "rad/s",
                    "m/s2", "m/s^2", "pct")
_UNDERSCORE_SPELLING = {"degps": "deg/s", "mps": "m/s", "pct": "%"}


def split_header(cell: str) -> tuple[str, str | None]:
    """Split a header cell into ``(name, unit)``; unit is None when the cell names none.

    Read, in this order: ``name [unit]`` (the convention shipid writes), ``name (unit)``
    (``Time (ms)``, ``Heading (deg)``) and ``name_unit`` where the part after the last
    underscore is one of :data:`UNDERSCORE_UNITS` (``speed_kn``, ``time_s``) and the cell is
    not a standard channel name itself (``a_s``, ``x_dot`` stay whole). Anything else is a
    name without a unit.

    Raises ValueError for a cell with unbalanced or repeated brackets.
    """
    m = _HEADER.match(cell)
    if m:
        return m.group("name"), m.group("unit").strip()
    if "[" in cell or "]" in cell:
        raise ValueError(f"malformed header cell '{cell.strip()}' (expected 'name [unit]')")
    m = _PAREN.match(cell)
    if m and m.group("name") and m.group("unit").strip():
        return m.group("name"), m.group("unit").strip()
    name = cell.strip()
    head, sep, tail = name.rpartition("_")
    if sep and head.strip() and tail in UNDERSCORE_UNITS:
        if name not in CHANNELS:
            return head.strip(), _UNDERSCORE_SPELLING.get(tail, tail)
    return name, None
