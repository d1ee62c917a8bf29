"""Helpers shared by the methods' ``series.with_series``: report series made on request from a stored result."""

from __future__ import annotations

import copy


def noted(result, text: str):
    """A copy of ``result`` with one warning: the report series were not made, and why."""
    out = copy.deepcopy(result)
    out.diagnostics["warnings"] = [*(out.diagnostics.get("warnings") or []), f"report series not made: {text}"]
    return out


def first_unreproduced(stored, refit) -> str | None:
    """The first estimate of ``stored`` whose value the refit ``refit`` does not reproduce exactly, or None.

    Series made by a refit belong to the stored result only when every estimate is the same double.
    """
    for n, e in stored.estimates.items():
        if n in refit.estimates and refit.value(n) != e.value:
            return n
    return None


__all__ = ["noted", "first_unreproduced"]
