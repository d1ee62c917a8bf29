"""Vessel parameter sets: packaged TOML files, every value with its unit and source.

File format (``src/shipid/vessels/data/<name>.toml``)::

    [vessel]
    name = "supply"                      # the id used on the command line
    title = "Supply vessel (Fossen, Sagatun & Sørensen 1996)"
    aliases = ["supply-vessel"]
    sources = { fss1996 = "Fossen, T.I., Sagatun, S.I., Sørensen, A.J. (1996) ..." }

    [particulars]                        # any number of sections
    L = { value = 76.2, unit = "m", source = "fss1996 §4" }
    M = { value = [[1.1274, 0, 0], [0, 1.8902, -0.0744], [0, -0.0744, 0.1278]],
          unit = "-", source = "fss1996 eq. 30" }

Every entry must carry ``value``, ``unit`` and ``source``; ``note`` is optional
(say there what was chosen and why, where the literature is silent). Sources name
a key of ``[vessel].sources`` followed by the table or equation.

:func:`load_vessel` returns a frozen :class:`Vessel`; models turn it into their own
frozen parameter dataclasses (DESIGN.md practice 1: parameters apart from models).
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from importlib import resources
from types import MappingProxyType
from typing import Any, Mapping

import numpy as np

from shipid.errors import ShipidError


@dataclass(frozen=True)
class Param:
    """A published value with its unit and source."""

    value: Any
    unit: str
    source: str
    note: str = ""

    @property
    def array(self) -> np.ndarray:
        return np.asarray(self.value, dtype=float)


@dataclass(frozen=True)
class Vessel:
    """A packaged vessel: named sections of :class:`Param`."""

    name: str
    title: str
    sources: Mapping[str, str]
    sections: Mapping[str, Mapping[str, Param]]
    aliases: tuple[str, ...] = field(default=())

    def section(self, name: str) -> Mapping[str, Param]:
        try:
            return self.sections[name]
        except KeyError:
            raise KeyError(f"vessel {self.name!r} has no section {name!r} "
                           f"(has: {', '.join(self.sections)})") from None

    def value(self, section: str, key: str) -> Any:
        """The bare value of ``[section].key`` (a float, or an ndarray for lists)."""
        v = self.section(section)[key].value
        return np.asarray(v, dtype=float) if isinstance(v, list) else v

    def values(self, section: str) -> dict[str, Any]:
        """All bare values of a section."""
        return {k: self.value(section, k) for k in self.section(section)}


def _data_dir():
    return resources.files("shipid.vessels") / "data"


def vessel_names() -> list[str]:
    """Names of the packaged vessels."""
    return sorted(p.name[:-5] for p in _data_dir().iterdir() if p.name.endswith(".toml"))


def _parse(name: str, text: str) -> Vessel:
    raw = tomllib.loads(text)
    head = raw.pop("vessel", {})
    sections: dict[str, Mapping[str, Param]] = {}
    for sec, entries in raw.items():
        params = {}
        for key, e in entries.items():
            if not isinstance(e, dict) or not {"value", "unit", "source"} <= set(e):
                raise ShipidError(f"vessel file {name}.toml: [{sec}].{key} needs value, unit and source")
            params[key] = Param(e["value"], e["unit"], e["source"], e.get("note", ""))
        sections[sec] = MappingProxyType(params)
    return Vessel(name=head.get("name", name), title=head.get("title", name),
                  sources=MappingProxyType(dict(head.get("sources", {}))),
                  sections=MappingProxyType(sections), aliases=tuple(head.get("aliases", ())))


def load_vessel(name: str) -> Vessel:
    """Load a packaged vessel by name or alias (``"esso-osaka"``, ``"supply"`` ...)."""
    shown = []
    for stem in vessel_names():
        v = _parse(stem, (_data_dir() / f"{stem}.toml").read_text(encoding="utf-8"))
        if name == stem or name == v.name or name in v.aliases:
            return v
        shown.append(v.name)
    # named as `shipid vessels` shows them (nomoto is a model family, offered by the simulator itself)
    raise ShipidError(f"unknown vessel {name!r} (known: {', '.join(sorted(shown))})")


__all__ = ["Param", "Vessel", "load_vessel", "vessel_names"]
