"""``known.toml``: the known mass, geometry and speed of Linder et al. (2015), Table 1, for Algorithm 1.

``known.toml`` holds ``U, M, zg_bar, m_c, zc_bar, zs_bar, g`` (bare numbers in SI, or tables
``{ value = ..., unit = "..." }`` converted with pint) and optionally ``z_f`` (known centre of
rotation) or ``z_f_prior = [mean, std]``, and ``theta0`` (9 initial values in the order of
:data:`shipid.models.roll_reduced.THETA_NAMES`). Read by ``shipid.identify("mass-cm", known=PATH)``
and the ``identify mass-cm`` / ``monitor mass-cm`` commands.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

from shipid.errors import InputError
from shipid.io.units import parse_unit, to_si
from shipid.models.roll_reduced import THETA_NAMES, KnownParams

KNOWN_KEYS = ("U", "M", "zg_bar", "m_c", "zc_bar", "zs_bar", "g")
_UNITS = {"U": "m/s", "M": "kg", "zg_bar": "m", "m_c": "kg", "zc_bar": "m", "zs_bar": "m", "g": "m/s^2",
          "z_f": "m"}


def _si(name: str, entry, path: str) -> float:
    """A known value: a bare number (SI) or ``{value, unit}`` converted with pint."""
    if isinstance(entry, (int, float)) and not isinstance(entry, bool):
        return float(entry)
    if isinstance(entry, dict) and "value" in entry:
        unit = entry.get("unit", _UNITS.get(name, ""))
        try:
            value, si = to_si(float(entry["value"]), unit)
            if si != parse_unit(_UNITS[name]):
                raise ValueError(f"{unit} is {si}, not {parse_unit(_UNITS[name])}")
        except (ValueError, TypeError, InputError) as err:  # one line for any unit problem
            raise InputError(f"{name}: cannot convert {entry['value']} {unit} to {_UNITS[name]} ({err})",
                             file=path) from None
        return float(value)
    raise InputError(f"{name} must be a number or {{ value = ..., unit = \"...\" }}", file=path)


def read_known(path: str) -> dict:
    """Parse ``known.toml`` into KnownParams plus the optional z_f / prior / theta0."""
    try:
        raw = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as err:
        raise InputError(f"not valid TOML ({err})", file=path) from None
    raw = raw.get("known", raw)
    missing = [k for k in KNOWN_KEYS if k not in raw]
    if missing:
        raise InputError(f"missing known parameter(s): {', '.join(missing)} (need {', '.join(KNOWN_KEYS)})",
                         file=path)
    vals = {k: _si(k, raw[k], path) for k in KNOWN_KEYS}
    bad = [k for k in ("U", "M", "m_c", "g") if not vals[k] > 0]
    if bad:
        why = {"U": "U is the ship's speed through the water, which scales the rudder force", "g": "g the gravity",
               "M": "M the nominal mass", "m_c": "m_c the calibration load"}
        raise InputError(f"{', '.join(f'{k} = {vals[k]:g}' for k in bad)}: must be positive "
                         f"({'; '.join(why[k] for k in bad)})", file=path)
    out = {"known": KnownParams(**vals), "z_f": None, "z_f_prior": None, "theta0": None}
    if "z_f" in raw:
        out["z_f"] = _si("z_f", raw["z_f"], path)
    if "z_f_prior" in raw:
        pr = raw["z_f_prior"]
        if not (isinstance(pr, list) and len(pr) == 2 and float(pr[1]) > 0):
            raise InputError("z_f_prior must be [mean, std] in m with std > 0", file=path)
        out["z_f_prior"] = (float(pr[0]), float(pr[1]))
    if "theta0" in raw:
        th = raw["theta0"]
        if not (isinstance(th, list) and len(th) == len(THETA_NAMES)):
            raise InputError(f"theta0 must list {len(THETA_NAMES)} values ({', '.join(THETA_NAMES)})", file=path)
        out["theta0"] = [float(x) for x in th]
    return out
