"""One verdict per estimate, and the tables a :class:`~shipid.result.Result` shows of itself.

Every place that says how well an estimate is determined (``Result.summary()``, ``repr``,
``to_frame()``, the notebook display, the HTML report's card, tables and warnings, ``shipid
demo``) takes the verdict from :func:`grade` here, so that they cannot disagree.

The grade of an estimate, in this order:

* ``not determined``: its status says so (the method's own test), its standard error is
  infinite, or its relative standard error ``std / |value|`` exceeds
  :data:`REL_SE_UNDETERMINED` (the 95 % interval then spans zero widely: the data do not fix
  even its sign). Its value is kept in the result but never shown as an estimate;
* ``fixed``, ``derived``, ``known`` ...: not estimated from these data (the status itself);
* ``flagged``: estimated, but the method's note calls it weakly determined or biased beyond its
  standard error;
* ``well`` (relative SE ≤ :data:`WELL`), ``loose`` (≤ :data:`LOOSE`), ``poor`` (above), or
  ``no SE`` when no standard error is available.

The 95 % interval is the normal approximation ``value ± z SE`` (``z = 1.96``).
"""

from __future__ import annotations

import html
import math
import re
import textwrap
from dataclasses import dataclass
from statistics import NormalDist
from typing import Any, Mapping

from shipid import registry as method_registry

#: Relative SE above which an "estimated" coefficient is not determined.
REL_SE_UNDETERMINED = 1.0
#: Bands of relative SE for "well" and "loose".
WELL, LOOSE = 0.10, 0.50

NOT_DETERMINED = "not determined"
#: Grades of estimated quantities, best first.
GRADES = ("well", "loose", "poor", "no SE", "flagged", NOT_DETERMINED)
GRADE_TEXT = {
    "well": f"well determined (rel. SE ≤ {100 * WELL:.0f} %)",
    "loose": f"loosely determined (rel. SE {100 * WELL:.0f}–{100 * LOOSE:.0f} %)",
    "poor": f"poorly determined (rel. SE {100 * LOOSE:.0f}–{100 * REL_SE_UNDETERMINED:.0f} %)",
    "no SE": "estimated without a standard error",
    "flagged": "flagged by the method as weakly determined or biased (see its note)",
    NOT_DETERMINED: f"not determined by these data (rel. SE above {100 * REL_SE_UNDETERMINED:.0f} % or "
                    "the method's test): not estimates",
}
_FLAG = re.compile(r"weakly determined|biased|bias beyond", re.I)
_UNDET = ("not determined", "not identifiable", "undetermined", "not-determined")

#: Method titles for headings (a method not listed uses its registry title).
METHOD_TITLES = {
    "mass-cm": ("Mass and centre of mass from IMU and rudder", "after Linder et al. (2015)"),
    "dp": ("DP low-frequency model, parallel EKF", "after Fossen, Sagatun & Sørensen (1996)"),
    "ebm": ("Manoeuvring coefficients by Estimation-Before-Modelling", "after Yoon & Rhee (2003)"),
    "ebm-study": ("Manoeuvring coefficients by EBM: paper reproduction study",
                  "after Yoon & Rhee (2003), Tables 3 and 5"),
    "mmg-ebm": ("MMG manoeuvring model from free-running tests (EBM)",
                "after Yoon & Rhee (2003), adapted to the MMG model"),
    "ebm-design": ("D-optimal PRBS input design for EBM", "after Yoon & Rhee (2003), Figs 7–8"),
}


def method_title(method: str) -> tuple[str, str]:
    """(title, source) of a result's method for headings."""
    if method in METHOD_TITLES:
        return METHOD_TITLES[method]
    info = method_registry.for_result(method)
    if info is None:
        return f"Identification result: {method}", ""
    return info.title, f"after {info.paper}" if info.paper else ""


def rel_se(e) -> float:
    """``std / |value|`` (inf for an infinite SE, NaN when either is missing or the value is 0)."""
    try:
        v, s = float(e.value), float(e.std)
    except (TypeError, ValueError):
        return float("nan")
    if math.isinf(s):
        return math.inf
    if not (math.isfinite(v) and math.isfinite(s)) or v == 0 or s <= 0:
        return float("nan")
    return abs(s / v)


def effective_status(e) -> str:
    """The status shown: the estimate's own, or ``not determined`` (module docstring)."""
    st = str(getattr(e, "status", "") or "estimated")
    if st.lower() in _UNDET:
        return NOT_DETERMINED
    if st == "estimated":
        r = rel_se(e)
        if math.isinf(r) or (math.isfinite(r) and r > REL_SE_UNDETERMINED):
            return NOT_DETERMINED
    return st


def grade(e) -> str:
    """The one verdict on an estimate (module docstring): a name of :data:`GRADES` or its status."""
    st = effective_status(e)
    if st != "estimated":
        return st
    if _FLAG.search(str(getattr(e, "note", "") or "")):
        return "flagged"
    r = rel_se(e)
    if not math.isfinite(r):
        return "no SE"
    return "well" if r <= WELL else ("loose" if r <= LOOSE else "poor")


def is_estimate(g: str) -> bool:
    """Whether a grade is shown as an estimate (estimated from these data and determined)."""
    return g in GRADES and g != NOT_DETERMINED


def warnings_of(result) -> list[str]:
    """``diagnostics["warnings"]`` as a list of str."""
    w = (result.diagnostics or {}).get("warnings") or []
    if isinstance(w, str):
        w = [w]
    return [str(x) for x in w] if isinstance(w, (list, tuple)) else [str(w)]


@dataclass(frozen=True)
class Verdict:
    """What a result says of itself, computed once.

    Attributes
    ----------
    grades : dict
        Estimate name → grade (:func:`grade`), in the result's order.
    warnings : tuple of str
        The method's warnings.
    converged : bool or None
    """

    grades: dict
    warnings: tuple
    converged: bool | None

    def names(self, *grades: str) -> list[str]:
        """Estimates with any of ``grades``."""
        return [n for n, g in self.grades.items() if g in grades]

    @property
    def determined(self) -> list[str]:
        return [n for n, g in self.grades.items() if is_estimate(g)]

    @property
    def not_determined(self) -> list[str]:
        return self.names(NOT_DETERMINED)

    @property
    def not_estimated(self) -> list[str]:
        """Fixed, known or derived quantities (not estimated from these data)."""
        return [n for n, g in self.grades.items() if g not in GRADES]

    @property
    def tabled(self) -> list[str]:
        """What the summary table shows with a value: determined estimates and derived quantities."""
        return [n for n, g in self.grades.items() if is_estimate(g) or g == "derived"]

    @property
    def fixed(self) -> list[str]:
        """Quantities given to the method (fixed, known), not results."""
        return [n for n, g in self.grades.items() if g not in GRADES and g != "derived"]

    def counts_line(self) -> str:
        """``26 quantities: 12 estimated, 14 not determined, 2 fixed · converged · 3 warnings``."""
        n = len(self.grades)
        bits = [f"{len(self.determined)} estimated"]
        if self.not_determined:
            bits.append(f"{len(self.not_determined)} not determined")
        if self.not_estimated:
            bits.append(f"{len(self.not_estimated)} fixed/derived")
        conv = {True: "converged", False: "DID NOT CONVERGE", None: "convergence not recorded"}[self.converged]
        w = len(self.warnings)
        return (f"{n} quantit{'y' if n == 1 else 'ies'}: " + ", ".join(bits)
                + f" · {conv} · {w} warning{'' if w == 1 else 's'}")


def verdict(result) -> Verdict:
    """The :class:`Verdict` of ``result``."""
    conv = (result.diagnostics or {}).get("converged")
    return Verdict({n: grade(e) for n, e in result.estimates.items()}, tuple(warnings_of(result)),
                   conv if isinstance(conv, bool) else None)


# -- numbers as text ------------------------------------------------------------------------------------

def num(x: float, sig: int = 4) -> str:
    """``x`` in at most 10 characters, ``sig`` significant digits."""
    try:
        v = float(x)
    except (TypeError, ValueError):
        return str(x)[:10]
    if math.isnan(v):
        return "-"
    if math.isinf(v):
        return "inf" if v > 0 else "-inf"
    if v == 0:
        return "0"
    e = math.floor(math.log10(abs(v)))
    if -3 <= e < 5:
        s = f"{v:.{max(sig - 1 - e, 0)}f}"
        return s.rstrip("0").rstrip(".") if "." in s else s
    return f"{v:.{sig - 1}e}".replace("e+0", "e").replace("e-0", "e-").replace("e+", "e")


def _cut(s: str, n: int) -> str:
    s = " ".join(str(s).split())
    return s if len(s) <= n else s[:n - 1] + "…"


def _fold(label: str, names: list[str], width: int, max_lines: int) -> list[str]:
    """``label names, …`` wrapped to ``width``, at most ``max_lines`` lines, the rest as a count."""
    shown = list(names)
    while True:
        more = len(names) - len(shown)
        text = label + ", ".join(shown) + (f" … and {more} more" if more else "")
        lines = textwrap.wrap(text, width, subsequent_indent="  ", break_on_hyphens=False)
        if len(lines) <= max_lines or not shown:
            return lines[:max_lines]
        shown = shown[:-1]


Z95 = NormalDist().inv_cdf(0.975)
WIDTH, HEIGHT = 100, 40
_COLS = ("name", "estimate", "std", "[0.025", "0.975]", "unit", "verdict")
_W = (14, 11, 10, 11, 11, 11, 24)


def _row(cells) -> str:
    out = []
    for i, (c, w) in enumerate(zip(cells, _W)):
        c = _cut(c, w)
        out.append(c.ljust(w) if i in (0, 5, 6) else c.rjust(w))
    return " ".join(out).rstrip()


def _grade_cell(g: str, e) -> str:
    r = rel_se(e)
    if g != NOT_DETERMINED and math.isfinite(r):
        return f"{g} ({100 * r:.2g} %)" if r < 0.1 else f"{g} ({100 * r:.0f} %)"
    return g


class Text(str):
    """A text table that shows as itself at the prompt and in a notebook (not as a quoted string)."""

    def __repr__(self) -> str:
        return str(self)

    def _repr_html_(self) -> str:
        return f"<pre>{html.escape(str(self))}</pre>"


def summary_text(result, *, width: int = WIDTH, height: int = HEIGHT) -> str:
    """The statsmodels-style summary (module docstring): at most ``width`` × ``height`` characters.

    Every determined estimate with its unit, SE, 95 % interval and grade; the not-determined ones
    named (never with a value); the verdict line; the warnings, one line each. Lists too long for
    the page are folded with a count of what is left out (``to_frame()`` has every row).
    """
    v = verdict(result)
    title, source = method_title(result.method)
    vessel = (result.model or {}).get("vessel") or (result.provenance or {}).get("vessel")
    rule = "=" * min(width, sum(_W) + len(_W) - 1)
    head = [_cut(f"shipid {result.method}: {title}" + (f" — {vessel}" if vessel else ""), width),
            _cut(v.counts_line(), width), rule, _row(_COLS), "-" * len(rule)]
    tail: list[str] = []
    undet = v.not_determined
    if undet:
        tail += _fold(f"Not determined ({len(undet)}; values are not estimates): ", undet, width, 3)
    fixed = v.fixed
    if fixed:
        tail += _fold(f"Given, not estimated ({len(fixed)}): ", fixed, width, 2)
    warns = list(v.warnings)
    wl = []
    if warns:
        wl.append(f"Warnings ({len(warns)}):")
        wl += ["  " + _cut(f"{i + 1}. {w}", width - 2) for i, w in enumerate(warns)]
    else:
        wl.append("No warnings.")
    tail.append("-" * len(rule))
    budget = height - len(head) - len(tail) - 1
    det = v.tabled
    # rows get what is left after at least 4 warning lines; warnings get the rest
    n_rows = min(len(det), max(budget - min(len(wl), 5), 1))
    rows = [_row(_est_cells(n, result.estimates[n], v.grades[n])) for n in det[:n_rows]]
    if len(det) > n_rows:
        rows[-1:] = [f"… and {len(det) - n_rows + 1} more estimates (res.to_frame() lists all)"]
    if not det:
        rows = ["(no quantity is determined by these data)"]
    room = height - len(head) - len(rows) - len(tail)
    if len(wl) > room:
        wl = wl[:max(room - 1, 1)] + [f"  … and {len(warns) - max(room - 2, 0)} more (res.warnings)"]
    return Text("\n".join(head + rows + tail + wl))


def _est_cells(name: str, e, g: str) -> list[str]:
    s = float(e.std) if e.std is not None else float("nan")
    lo, hi = ("-", "-") if not math.isfinite(s) else (num(e.value - Z95 * s), num(e.value + Z95 * s))
    return [name, num(e.value), num(s, 2), lo, hi, str(e.unit or "-"), _grade_cell(g, e)]


def short_repr(result, *, limit: int = 8) -> str:
    """A few lines: method, vessel, the verdict line, the first estimates, how to see the rest."""
    v = verdict(result)
    vessel = (result.model or {}).get("vessel")
    lines = [f"<shipid Result {result.method}" + (f", vessel {vessel}" if vessel else "") + ">",
             "  " + v.counts_line()]
    det = v.tabled
    for n in det[:limit]:
        e = result.estimates[n]
        s = float(e.std) if e.std is not None else float("nan")
        lines.append(f"  {_cut(n, 16):<16} {num(e.value):>10} ± {num(s, 2):<9} {_cut(str(e.unit or '-'), 12)}")
    if len(det) > limit:
        lines.append(f"  … and {len(det) - limit} more estimates")
    if v.not_determined:
        lines += ["  " + x for x in _fold("not determined: ", v.not_determined, 96, 2)]
    for w in v.warnings[:3]:
        lines.append("  warning: " + _cut(w, 88))
    if len(v.warnings) > 3:
        lines.append(f"  … and {len(v.warnings) - 3} more warnings (res.warnings)")
    lines.append("  res.summary() for the table, res.to_frame() for pandas")
    return "\n".join(lines)


def html_repr(result) -> str:
    """A compact HTML table of the summary for notebooks (``_repr_html_``)."""
    v = verdict(result)
    esc = html.escape
    title, _ = method_title(result.method)
    rows = []
    for n, e in result.estimates.items():
        g = v.grades[n]
        if is_estimate(g):
            cells = _est_cells(n, e, g)
            style = ""
        else:
            cells = [n, "", "", "", "", str(e.unit or "-"), g]
            style = ' style="color:#8a5a00"' if g == NOT_DETERMINED else ' style="color:#666"'
        rows.append(f"<tr{style}>" + "".join(
            f'<td style="text-align:{"left" if i in (0, 5, 6) else "right"}">{esc(str(c))}</td>'
            for i, c in enumerate(cells)) + "</tr>")
    head = "".join(f"<th>{esc(c)}</th>" for c in _COLS)
    warns = "".join(f"<li>{esc(w)}</li>" for w in v.warnings)
    return (f"<div><b>shipid {esc(result.method)}</b>: {esc(title)}<br><small>{esc(v.counts_line())}</small>"
            f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(rows)}</tbody></table>"
            + (f"<details><summary>{len(v.warnings)} warnings</summary><ul>{warns}</ul></details>" if warns else "")
            + "</div>")


FRAME_COLUMNS = ("value", "std", "unit", "status", "note", "estimate", "lower", "upper", "rel_se", "verdict")


def frame_rows(result, alpha: float = 0.05) -> list[dict[str, Any]]:
    """One dict per estimate (:data:`FRAME_COLUMNS`): the stored ``value``, ``std``, ``unit``,
    ``status``, ``note`` (enough to rebuild the estimate), and ``estimate``/``lower``/``upper``
    (NaN unless determined), ``rel_se`` and the ``verdict``."""
    z = NormalDist().inv_cdf(1 - alpha / 2)
    out = []
    for n, e in result.estimates.items():
        g = grade(e)
        s = float(e.std) if e.std is not None else float("nan")
        shown = is_estimate(g) or g not in GRADES
        est = float(e.value) if shown else float("nan")
        lo = est - z * s if shown and math.isfinite(s) else float("nan")
        hi = est + z * s if shown and math.isfinite(s) else float("nan")
        out.append({"name": n, "value": float(e.value), "std": s, "unit": e.unit, "status": e.status,
                    "note": e.note, "estimate": est, "lower": lo, "upper": hi, "rel_se": rel_se(e),
                    "verdict": g})
    return out


def frame(result, alpha: float = 0.05):
    """:func:`frame_rows` as a pandas DataFrame indexed by name."""
    import pandas as pd

    rows = frame_rows(result, alpha)
    df = pd.DataFrame(rows, columns=("name",) + FRAME_COLUMNS)
    return df.set_index("name")


def estimates_from_frame(df) -> dict[str, Mapping]:
    """The ``Estimate`` fields of each row of a :func:`frame` (name → dict of value, std, unit, status, note)."""
    out = {}
    for name, row in df.iterrows():
        out[str(name)] = {"value": float(row["value"]), "std": float(row["std"]), "unit": str(row["unit"]),
                          "status": str(row["status"]), "note": "" if row["note"] is None else str(row["note"])}
    return out


__all__ = ["Text", "grade", "effective_status", "rel_se", "verdict", "Verdict", "summary_text", "short_repr",
           "html_repr", "frame", "frame_rows", "estimates_from_frame", "warnings_of", "method_title",
           "NOT_DETERMINED", "GRADES", "GRADE_TEXT", "REL_SE_UNDETERMINED", "WELL", "LOOSE"]
