"""Vessel name → simulatable :class:`~shipid.models.ship_model.ShipModel`.

The packaged vessels (``shipid.vessels``) are simulated by the model family of
their paper; each family module exposes ``ship_model(vessel) -> ShipModel``
taking the loaded :class:`~shipid.vessels.Vessel`. Families are imported lazily,
so a missing or broken family only affects its own vessels, with a one-line
:class:`~shipid.errors.ShipidError`.

Besides the packaged vessels there are generic models that need no data file
(:data:`GENERIC`): ``nomoto``, a first-order Nomoto steering model.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Callable

from shipid.errors import ShipidError
from shipid.models.ship_model import ShipModel
from shipid.vessels import load_vessel, vessel_names

#: Model family module of each packaged vessel (canonical name as in its TOML file).
FAMILIES: dict[str, str] = {
    "esso-osaka": "shipid.models.abkowitz",    # Yoon & Rhee 2003
    "supply": "shipid.models.dp",              # Fossen, Sagatun & Sørensen 1996
    "fishing-vessel": "shipid.models.roll",    # Linder et al. 2015
}

#: Generic models without a data file: name → (title, factory).
GENERIC: dict[str, tuple[str, str]] = {
    "nomoto": ("Generic first-order Nomoto steering model (L = 100 m, U = 7.5 m/s)",
               "shipid.simulate.nomoto"),
}


@dataclass(frozen=True)
class VesselEntry:
    """One line of ``shipid vessels``."""

    name: str
    title: str
    family: str
    sources: tuple[str, ...]
    aliases: tuple[str, ...] = ()


def _family_of(vessel) -> str:
    for key in (vessel.name, *vessel.aliases):
        if key in FAMILIES:
            return FAMILIES[key]
    raise ShipidError(f"vessel {vessel.name!r} has no simulation model registered "
                      f"(shipid.simulate.registry.FAMILIES)")


def _import_family(module: str, vessel_name: str) -> Callable:
    try:
        mod = importlib.import_module(module)
    except ModuleNotFoundError as err:
        if err.name and (err.name == module or module.startswith(err.name + ".")):
            raise ShipidError(f"vessel {vessel_name!r}: its model family {module} is not "
                              "available in this version of shipid") from None
        raise
    fn = getattr(mod, "ship_model", None)
    if fn is None:
        raise ShipidError(f"vessel {vessel_name!r}: {module} has no ship_model(vessel) yet")
    return fn


def get_ship_model(name: str) -> ShipModel:
    """The :class:`ShipModel` of a packaged vessel (name or alias) or of a generic model.

    Raises
    ------
    ShipidError
        Unknown vessel, or its model family not available.
    """
    if name in GENERIC:
        mod = importlib.import_module(GENERIC[name][1])
        return mod.ship_model(None)
    try:
        vessel = load_vessel(name)
    except ShipidError:
        known = sorted({e.name for e in list_vessels()} | set(GENERIC))   # as `shipid vessels` shows them
        raise ShipidError(f"unknown vessel {name!r} (known: {', '.join(known)})") from None
    module = _family_of(vessel)
    model = _import_family(module, vessel.name)(vessel)
    if not isinstance(model, ShipModel):
        raise ShipidError(f"{module}.ship_model returned {type(model).__name__}, not a ShipModel")
    return model


def list_vessels() -> list[VesselEntry]:
    """Packaged vessels (with their sources) followed by the generic models."""
    out = []
    for stem in vessel_names():
        v = load_vessel(stem)
        fam = next((FAMILIES[k] for k in (v.name, *v.aliases) if k in FAMILIES), "-")
        out.append(VesselEntry(v.name, v.title, fam.rsplit(".", 1)[-1],
                               tuple(f"{k}: {s}" for k, s in v.sources.items()), v.aliases))
    for name, (title, module) in GENERIC.items():
        out.append(VesselEntry(name, title, module.rsplit(".", 1)[-1], ("generic (no paper)",)))
    return out
