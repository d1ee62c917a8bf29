"""Per-method report sections: ``register_section(method, fn)``.

A section function takes the :class:`~shipid.result.Result` and returns a list of
fragments, each one of

- ``str``: trusted HTML inserted as is (escape your own text with :func:`html.escape`);
- a :class:`matplotlib.figure.Figure`, or a tuple ``(figure, caption)``: drawn as an
  inline PNG with the caption below;
- :class:`Claim` ``(kind, name)``: not drawn; tells the generic part of the report
  that ``result.series[kind][name]`` has already been shown;
- :class:`Entry` ``(kind, name, paper=None, title=None)``: draw that convention entry
  here, in the standard way, with the given paper reference / caption (claims it);
- :class:`Group` ``(kind, names, caption)``: several ``histories`` (small multiples)
  or ``signals`` (stacked, shared time axis) in one figure (claims them);
- a dict following the ``tables`` convention (``columns``, ``rows``, ``units``,
  ``caption``/``title``/``paper``): a numbered table;
- ``"residual-checks"``: the table of residual statistics of the overlays and
  residuals drawn so far in this section.

Sections registered for a method run in registration order; the defaults of
each method's ``report`` module are registered first.
"""

from __future__ import annotations

import importlib
import importlib.util
from dataclasses import dataclass
from typing import Any, Callable

from shipid import registry as method_registry

SectionFn = Callable[[Any], list]

_REGISTRY: dict[str, list[tuple[str, SectionFn, bool]]] = {}
_LOAD_ERRORS: dict[str, str] = {}


@dataclass(frozen=True)
class Claim:
    """Marks ``result.series[kind][name]`` as drawn by a section."""

    kind: str
    name: str


@dataclass(frozen=True)
class Entry:
    """Draw ``result.series[kind][name]`` here, captioned with ``paper`` and ``title``."""

    kind: str
    name: str
    paper: str | None = None
    title: str | None = None


@dataclass(frozen=True)
class Group:
    """Draw several ``histories`` or ``signals`` entries in one figure."""

    kind: str
    names: tuple
    caption: str = ""


def register_section(method: str, fn: SectionFn, *, title: str | None = None,
                     default: bool = False) -> SectionFn:
    """Add ``fn`` to the report of every result whose ``method`` is ``method``.

    Parameters
    ----------
    method : str
        ``"mass-cm"``, ``"dp"``, ``"ebm"`` ...; ``"*"`` applies to every method.
    fn : callable
        ``fn(result) -> list`` of fragments (see module docstring).
    title : str, optional
        Heading of the section (default: ``fn.__doc__``'s first line or the function name).
    default : bool
        Used by :mod:`shipid.report.sections` only: default sections come first.

    Returns
    -------
    fn, so that it can be used as a decorator helper.
    """
    if not callable(fn):
        raise TypeError("register_section: fn must be callable")
    if title is None:
        doc = (fn.__doc__ or "").strip().splitlines()
        title = doc[0].rstrip(".") if doc else fn.__name__.replace("_", " ")
    entries = _REGISTRY.setdefault(method, [])
    if all(f is not fn for _, f, _d in entries):  # idempotent on re-import
        entries.append((title, fn, default))
    return fn


def _method_modules(method: str) -> list[str]:
    info = method_registry.for_result(method)
    return [] if info is None else [info.package, f"{info.package}.report"]


def load_method_sections(method: str) -> list[str]:
    """Import the method's own modules so that their ``register_section`` calls run.

    Imports the package that :mod:`shipid.registry` names for ``method`` (a
    ``Result.method`` value) and its ``report`` module. Returns messages for modules that exist but failed to import (shown in the report).
    """
    problems = []
    for mod in _method_modules(method):
        try:
            if importlib.util.find_spec(mod) is None:
                continue
            importlib.import_module(mod)
        except ModuleNotFoundError as err:
            if err.name and (mod == err.name or mod.startswith(err.name + ".")):
                continue  # the module simply does not exist
            problems.append(f"{mod}: {type(err).__name__}: {err}")
        except Exception as err:  # a broken method module must not break every report
            problems.append(f"{mod}: {type(err).__name__}: {err}")
    return problems


def sections_for(method: str) -> list[tuple[str, SectionFn]]:
    """The ``(title, fn)`` pairs for ``method``: defaults, then the method's own, then ``"*"``."""
    load_method_sections(method)
    own = _REGISTRY.get(method, [])
    ordered = [e for e in own if e[2]] + [e for e in own if not e[2]] + list(_REGISTRY.get("*", []))
    return [(title, fn) for title, fn, _d in ordered]
