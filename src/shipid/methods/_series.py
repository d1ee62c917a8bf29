"""Helpers shared by the methods' ``series.with_series``: report series made on request from a stored result."""

from __future__ import annotations

import copy
from typing import Mapping


def noted(result, text: str):
    """A copy of ``result`` with one warning: the report series were not made, and why."""
    out = copy.deepcopy(result)
    out.diagnostics["warnings"] = [*(out.diagnostics.get("warnings") or []), f"report series not made: {text}"]
    return out


def recorded_call(result, method: str, call_key: str, made_key: str) -> Mapping | None:
    """The call recorded in ``result.provenance[call_key]`` when the series are still to be made, else None.

    None when ``result`` is not a ``method`` result, already holds ``series[made_key]``, or records no call.
    """
    series = result.series if isinstance(result.series, Mapping) else {}
    prov = result.provenance if isinstance(result.provenance, Mapping) else {}
    call = prov.get(call_key)
    if result.method != method or series.get(made_key) or not isinstance(call, Mapping):
        return None
    return call


def first_unreproduced(stored, refit) -> str | None:
    """The first estimate of ``stored`` whose value the refit ``refit`` does not reproduce exactly, or None.

    Series made by a refit belong to the stored result only when every estimate is the same double.
    """
    for n, e in stored.estimates.items():
        if n in refit.estimates and refit.value(n) != e.value:
            return n
    return None


__all__ = ["noted", "recorded_call", "first_unreproduced"]
