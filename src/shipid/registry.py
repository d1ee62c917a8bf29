"""The method registry: name -> identify, options, title, paper, for the CLI, the API, the report and the demo.

Every identification method lives in its own subpackage ``shipid.methods.<pkg>`` whose ``__init__``
defines ``METHOD``, a :class:`MethodInfo`, and the callables it names. The registry finds them by
walking :mod:`shipid.methods` (a plug-in lookup by name: this shared module imports no method
statically), so a fifth method is one new subpackage and nothing else.

Examples
--------
>>> from shipid import registry
>>> sorted(registry.methods())                                          # doctest: +SKIP
['dp', 'ebm', 'mass-cm', 'mmg', 'monitor']
>>> registry.get("masscm").paper                                        # doctest: +SKIP
'Linder et al. 2015'
"""

from __future__ import annotations

import functools
import importlib
import importlib.util
import pkgutil
from dataclasses import dataclass, field
from types import ModuleType
from typing import Any, Callable, Mapping

from shipid.errors import InputError

_METHODS_PACKAGE = "shipid.methods"


@dataclass(frozen=True)
class MethodInfo:
    """One identification method as the CLI, ``shipid.identify`` and the report know it.

    Attributes
    ----------
    name : str
        CLI name (``shipid identify NAME``), e.g. ``"mass-cm"``.
    title : str
        What it identifies, one line.
    paper : str
        The paper it implements (``"Linder et al. 2015"``).
    trials : str
        The shape of the ``trials`` argument of ``identify``.
    package : str
        The subpackage (``"shipid.methods.masscm"``).
    result_methods : tuple of str
        Values of :attr:`shipid.result.Result.method` this package writes (``("mmg-ebm",)``).
    aliases : tuple of str
        Other spellings accepted by :func:`get`.
    """

    name: str
    title: str
    paper: str
    trials: str
    package: str
    result_methods: tuple[str, ...] = ()
    aliases: tuple[str, ...] = field(default=())

    @property
    def module(self) -> ModuleType:
        """The method's package (imported on first use)."""
        return importlib.import_module(self.package)

    @property
    def identify(self) -> Callable[..., Any]:
        """``identify(trials, *, vessel=None, options=None, **kw) -> Result``, or None (monitor)."""
        return getattr(self.module, "identify", None)

    @property
    def options(self) -> type | None:
        """The method's frozen options class."""
        return getattr(self.module, "Options", None)

    @property
    def coverage(self) -> Mapping | None:
        """The coverage study the method publishes (``COVERAGE``), or None."""
        cov = getattr(self.module, "COVERAGE", None)
        return cov if isinstance(cov, Mapping) and cov else None

    def has_module(self, name: str) -> bool:
        """Whether ``<package>.<name>`` exists (``report``, ``validate``, ...)."""
        return importlib.util.find_spec(f"{self.package}.{name}") is not None

    def submodule(self, name: str) -> ModuleType:
        """Import ``<package>.<name>``."""
        return importlib.import_module(f"{self.package}.{name}")


def _key(name: str) -> str:
    return str(name).strip().lower().replace("_", "-")


@functools.cache
def methods() -> dict[str, MethodInfo]:
    """All registered methods by CLI name, in the order of their package names."""
    pkg = importlib.import_module(_METHODS_PACKAGE)
    out: dict[str, MethodInfo] = {}
    for mod in sorted(pkgutil.iter_modules(pkg.__path__), key=lambda m: m.name):
        if not mod.ispkg:
            continue
        info = getattr(importlib.import_module(f"{_METHODS_PACKAGE}.{mod.name}"), "METHOD", None)
        if isinstance(info, MethodInfo):
            out[info.name] = info
    return out


def _by_package(pkg: str) -> MethodInfo | None:
    """``METHOD`` of the subpackage ``shipid.methods.<pkg>`` if there is one (imports that package only)."""
    if not pkg.isidentifier() or pkg.startswith("_"):
        return None
    name = f"{_METHODS_PACKAGE}.{pkg}"
    try:
        if importlib.util.find_spec(name) is None:
            return None
    except ImportError:
        return None
    info = getattr(importlib.import_module(name), "METHOD", None)
    return info if isinstance(info, MethodInfo) else None


def get(name: str) -> MethodInfo:
    """The method called ``name`` (CLI name, an alias, or a ``Result.method`` value).

    Raises
    ------
    InputError
        One line naming the methods there are.
    """
    key = _key(name)
    info = _by_package(key.replace("-", ""))
    if info is not None and key in (info.name, *info.aliases, *info.result_methods):
        return info                     # the method named after its package: only that one imported
    for info in methods().values():
        if key == info.name or key in info.aliases or key in info.result_methods:
            return info
    raise InputError(f"unknown method {name!r}; choose from {', '.join(methods())}")


def for_result(result_method: str) -> MethodInfo | None:
    """The method that writes results with ``Result.method == result_method``, or None."""
    try:
        return get(result_method)
    except InputError:
        return None


def identifying() -> dict[str, MethodInfo]:
    """The methods that ``shipid.identify`` runs (those with an ``identify`` callable)."""
    return {k: v for k, v in methods().items() if v.identify is not None}


def lazy_attributes(namespace: dict, table: dict[str, tuple[str, str]]):
    """A module ``__getattr__`` (PEP 562) for a method package: ``table[name] = (module, attribute)`` is imported
    on first use and kept in ``namespace`` (the package's ``globals()``), so that importing the package, which
    the registry does to read ``METHOD``, loads none of its numerics."""

    def __getattr__(name: str):
        if name in table:
            mod, attr = table[name]
            value = getattr(importlib.import_module(mod), attr)
            namespace[name] = value
            return value
        raise AttributeError(f"module {namespace.get('__name__')!r} has no attribute {name!r}")

    return __getattr__
