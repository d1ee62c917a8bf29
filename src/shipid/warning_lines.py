"""The warning lines of a result, collected by the library so that every face reports the same ones.

A :class:`~shipid.result.Result` carries in ``diagnostics["warnings"]`` one line per thing a user must not
miss: non-convergence, an undetermined or implausible estimate, a repair the reader made to the data, a
Python warning raised inside the method. :func:`collect` assembles that list (the methods' own lines
first); ``shipid.identify`` calls it, and the command line prints the same list, one
``shipid: warning:`` line each.
"""

from __future__ import annotations

import math
import warnings
from contextlib import contextmanager
from typing import Any, Iterable, Iterator

#: Estimate statuses that are not an estimate a user may quote.
UNDETERMINED = ("not determined", "not identifiable", "implausible", "flagged")
#: Warning categories meant for developers, not for users (not recorded, as Python's defaults).
QUIET = (DeprecationWarning, PendingDeprecationWarning, ImportWarning, ResourceWarning)


def one_line(text: Any) -> str:
    """``text`` on one line (runs of whitespace, newlines included, become one space)."""
    return " ".join(str(text).split())


def implied_warnings(res) -> list[str]:
    """What a :class:`~shipid.result.Result` says a user must know, beyond its own warning list.

    Non-convergence (``diagnostics["converged"]`` False, or a stage / mode of it), and
    every estimate whose status is one of :data:`UNDETERMINED` or whose standard error
    is infinite (the data do not determine it).
    """
    d = res.diagnostics or {}
    own = " ".join(str(w) for w in d.get("warnings", []) or []).lower()
    out = []
    if d.get("converged") is False and not ("converge" in own or "settled" in own):
        parts = []
        for key, label in (("stages", "stage"), ("ridge", "mode"), ("modes", "mode")):
            sub = d.get(key)
            if isinstance(sub, dict):
                parts += [f"{label} {k}" for k, v in sub.items() if isinstance(v, dict) and v.get("converged") is False]
        where = f" ({', '.join(parts)} not converged)" if parts else ""
        out.append(f"{res.method}: the estimator did not converge{where}; do not trust these estimates")
    for name, e in (res.estimates or {}).items():
        status = str(getattr(e, "status", "")).lower()
        std = getattr(e, "std", float("nan"))
        if status in UNDETERMINED or (isinstance(std, float) and math.isinf(std)):
            label = status if status in UNDETERMINED else "not determined by the data"
            note = f" ({one_line(e.note)})" if getattr(e, "note", "") else ""
            out.append(f"{name}: {label}{note}")
    return out


def unconverged_model_line(document: dict | None, label: str) -> list[str]:
    """The line ``validate`` prints for a model whose identification did not converge (``diagnostics.converged``
    false in its result ``document``), naming the model by ``label``; empty otherwise."""
    if document is None or (document.get("diagnostics") or {}).get("converged") is not False:
        return []
    return [f"model {label} did not converge when it was identified (diagnostics.converged false): "
            "its predictions must not be trusted"]


def repair_warnings(trials: Iterable) -> list[str]:
    """One line per data repair recorded by the reader (``trial.meta["repairs"]``), naming the file."""
    out = []
    for tr in trials:
        meta = getattr(tr, "meta", {}) or {}
        src = meta.get("source", "")
        for r in meta.get("repairs", []) or []:
            text = r.get("text", r) if isinstance(r, dict) else r
            out.append(f"data repaired in {src}: {one_line(text)}" if src else f"data repaired: {one_line(text)}")
    return out


def python_warnings(records: Iterable) -> list[str]:
    """Recorded Python warnings as distinct one-line texts (counts appended), developer categories left out."""
    counts: dict[str, int] = {}
    for w in records:
        if issubclass(w.category, QUIET):
            continue
        t = one_line(w.message)
        counts[t] = counts.get(t, 0) + 1
    return [t if n == 1 else f"{t} ({n} times)" for t, n in counts.items()]


def collect(res, *, trials: Iterable = (), extra: Iterable[str] = (), python: Iterable[str] = ()) -> list[str]:
    """Set ``res.diagnostics["warnings"]`` to its own lines, then ``python``, the repairs of ``trials``,
    ``extra`` and :func:`implied_warnings`, each once; returns the list."""
    d = res.diagnostics
    lst = [one_line(w) for w in (d.get("warnings") or [])]
    for w in [*python, *repair_warnings(trials), *extra, *implied_warnings(res)]:
        w = one_line(w)
        if w not in lst:
            lst.append(w)
    d["warnings"] = lst
    return lst


@contextmanager
def recorded(into: list) -> Iterator[None]:
    """Record the Python warnings raised inside into ``into`` (as one-line texts) instead of showing them."""
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        for cat in QUIET:
            warnings.simplefilter("ignore", cat)
        try:
            yield
        finally:
            into.extend(python_warnings(rec))


__all__ = ["UNDETERMINED", "QUIET", "one_line", "implied_warnings", "unconverged_model_line", "repair_warnings",
           "python_warnings", "collect", "recorded"]
