"""Values of the key–value tables of a report (diagnostics, model, provenance) and the SI table.

:func:`flatten` turns nested diagnostics into rows: numpy arrays and numpy's own text of an
array become :class:`MatrixValue` / :class:`VectorValue` (drawn as small tables), lists of flat
dicts :class:`RecordsValue`; :func:`with_units` adds each row's unit
(:func:`shipid.report.units.unit_of`); :func:`si_table` shows the DP bis parameters in SI.
No Python or numpy ``repr`` reaches the page.
"""

from __future__ import annotations

import re
from typing import Any, Mapping

import numpy as np

from shipid.report.formatting import fmt_num, format_estimate
from shipid.report.render import RenderContext, esc, sci_text, short_paths
from shipid.report.units import bis_to_si, dp_si_matrices, unit_of


def _is_scalar(v: Any) -> bool:
    return v is None or isinstance(v, (str, int, float, bool, np.integer, np.floating))


class MatrixValue(list):
    """A small 2-D numeric list shown as a matrix in key-value tables."""


class RecordsValue(list):
    """A short list of flat dicts shown as a nested table in key-value tables."""


class VectorValue(list):
    """A short numeric vector shown as a one-row table in key-value tables."""


class NamedVector(list):
    """A numeric vector with one value per estimate: a two-row table (estimate names, values)."""

    names: list = []


def _records(v) -> bool:
    if not isinstance(v, (list, tuple)) or not v or len(v) > 30:
        return False
    if not all(isinstance(r, Mapping) for r in v):
        return False
    return all(_is_scalar(x) or (isinstance(x, (list, tuple)) and len(x) <= 6 and all(_is_scalar(y) for y in x))
               for r in v for x in r.values())


def _records_map(v) -> bool:
    """A dict of flat dicts ({mode: {kappa, R2, ...}}): shown as one table, a row per key."""
    if not isinstance(v, Mapping) or not v or len(v) > 30:
        return False
    return _records(list(v.values())) and len({k for r in v.values() for k in r}) > 1


def _small_matrix(v) -> bool:
    if not isinstance(v, (list, tuple)) or not v or not all(isinstance(r, (list, tuple)) for r in v):
        return False
    if len(v) > 10 or any(len(r) != len(v[0]) or len(r) > 10 for r in v):
        return False
    return all(isinstance(x, (int, float)) and not isinstance(x, bool) for r in v for x in r)


def _plain(v: Any) -> Any:
    """numpy arrays/scalars as lists/floats; numpy's own text of an array (``"[[1. 2.]\\n [3. 4.]]"``,
    left by an older JSON writer) parsed back into lists."""
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, str) and v.lstrip().startswith("[") and v.rstrip().endswith("]") and \
            not any(c.isalpha() and c not in "eE" for c in v):
        try:
            vals = [[float(x) for x in g.split()] for g in re.findall(r"\[([^\[\]]*)\]", v)]
            vals = [r for r in vals if r]
            if len(vals) == 1 and v.count("[") == 1:
                return vals[0]
            if vals and all(len(r) == len(vals[0]) for r in vals):
                return vals
        except ValueError:
            return v
    return v


def _squeeze(x):
    x = _plain(x)
    return x[0] if isinstance(x, (list, tuple)) and len(x) == 1 else x


def _named_numbers(v, names) -> bool:
    """A mapping of 3 to 40 of ``names`` (the result's estimates) to numbers (or one-element lists)."""
    if not names or not isinstance(v, Mapping) or not 3 <= len(v) <= 40 or not set(map(str, v)) <= names:
        return False
    vals = [_squeeze(x) for x in v.values()]
    return all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in vals)


def flatten(d: Mapping, prefix: str = "", depth: int = 2, names=None) -> list[tuple[str, Any]]:
    """``(key, value)`` rows of a nested mapping for a key-value table; ``names`` (the result's estimate
    names): a mapping of one number per estimate becomes one row (a two-row table)."""
    names = set(names) if names else None
    rows = []
    for k, v in d.items():
        key = f"{prefix}{short_paths(str(k))}"
        v = _plain(v)
        if isinstance(v, (list, tuple)):
            v = [_plain(x) for x in v]
            if len(v) == 1 and _is_scalar(v[0]):
                v = v[0]
        if _is_scalar(v):
            rows.append((key, v))
        elif _records_map(v):
            rows.append((key, RecordsValue([{"": str(n), **r} for n, r in v.items()])))
        elif _named_numbers(v, names):           # one number per coefficient: one row, a two-row table
            nv = NamedVector([_squeeze(x) for x in v.values()])
            nv.names = [str(n) for n in v]
            rows.append((key, nv))
        elif isinstance(v, Mapping) and depth > 0:
            rows.extend(flatten(v, key + ".", depth - 1, names))
        elif isinstance(v, (list, tuple)) and not v:
            rows.append((key, "none"))
        elif _small_matrix(v):
            rows.append((key, MatrixValue(v)))
        elif _records(v):
            rows.append((key, RecordsValue(v)))
        elif isinstance(v, (list, tuple)) and 0 < len(v) <= 10 and all(isinstance(x, Mapping) for x in v):
            for i, item in enumerate(v):  # one block of rows per item: trials[1].manoeuvre ...
                rows.extend(flatten(item, f"{key}[{i + 1}].", max(depth - 1, 0)))
        elif isinstance(v, (list, tuple)) and len(v) <= 12 and all(_is_scalar(x) for x in v):
            rows.append((key, VectorValue(v) if all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                     for x in v) else "; ".join(str(x) for x in v)))
        elif isinstance(v, (list, tuple)):
            try:
                a = np.asarray(v, dtype=float).ravel()
                rows.append((key, f"{a.size} values, from {fmt_num(np.nanmin(a))} to {fmt_num(np.nanmax(a))}"
                             if a.size else "empty"))
            except (TypeError, ValueError):
                rows.append((key, f"{len(v)} items"))
        else:
            rows.append((key, _inline(v)[:400]))
    return rows


def _inline(v: Any) -> str:
    """Plain one-line text of a nested value: ``relative: n 17, min_rank 17; absolute: ...`` (no repr)."""
    v = _plain(v)
    if isinstance(v, Mapping):
        return "; ".join(f"{k}: {_inline(x)}" if isinstance(x, Mapping) else f"{k} {_inline(x)}"
                         for k, x in v.items())
    if isinstance(v, (list, tuple)):
        return ", ".join(_inline(x) for x in v)
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, (int, float)):
        return fmt_num(v)
    if v is None:
        return "—"
    return sci_text(short_paths(" ".join(str(v).split())))



def _vessel(result) -> str | None:
    v = (result.model or {}).get("vessel") or (result.provenance or {}).get("vessel")
    return str(v) if v else None


def with_units(result, rows: list[tuple[str, Any]]) -> list[tuple[str, Any, str]]:
    """(key, value, unit) rows; the unit from the vessel file or :data:`~shipid.report.units.KNOWN_UNITS`."""
    vessel = _vessel(result)
    bis = "bis" in str((result.model or {}).get("units", ""))
    out = []
    names = list(result.estimates)
    for k, v in rows:
        u = unit_of(k, v, vessel=vessel)
        if isinstance(v, VectorValue) and len(v) == len(names) > 1:
            nv = NamedVector(v)
            nv.names = names
            v = nv
        if bis and k.split(".")[-1] in ("A_h", "A", "B", "M", "D", "K", "T", "theta", "theta_std"):
            u = "bis (L, m, √(L/g))"
        elif bis and k.split(".")[-1] in ("theta_true", "error", "error_sigma", "relative_error"):
            u = {"error_sigma": "SE", "relative_error": "-"}.get(k.split(".")[-1], "bis")
        out.append((k, v, u))
    return out


def si_table(ctx: RenderContext, result) -> str:
    """DP θ1…θ9 (bis) in SI: A_h entries as rates with time constants, K as forces (eqs. 26–29)."""
    model = result.model or {}
    try:
        L, m, g = float(model["L"]), float(model["m"]), float(model.get("g", 9.81))
    except (KeyError, TypeError, ValueError):
        return ""
    rows = []
    for name, e in result.estimates.items():
        if "bis" not in str(e.unit):
            continue
        conv = bis_to_si(name, float(e.value), float(e.std), L, m, g)
        if conv is None:
            continue
        v, s, unit, note = conv
        f = format_estimate(v, s)
        sc = f' <span class="unit">{f.scale}</span>' if f.scale else ""
        rows.append(f"<tr><td><b>{esc(name)}</b></td><td class='num'>{f.value}{sc}</td>"
                    f"<td class='num'>{f.std}{sc if f.std != '—' else ''}</td><td>{esc(unit)}</td>"
                    f"<td>{esc(note)}</td></tr>")
    if not rows:
        return ""
    head = ("<tr><th>parameter</th><th class='num'>value (SI)</th><th class='num'>standard error</th>"
            "<th>unit</th><th>meaning</th></tr>")
    cap = ctx.table_caption(f"The bis-system parameters in SI units (L = {fmt_num(L)} m, m = {fmt_num(m)} kg, "
                            f"g = {fmt_num(g)} m/s², time unit √(L/g) = {fmt_num((L / g) ** 0.5)} s).")
    mats = ""
    for title, mat, units in dp_si_matrices(model):
        big = max(abs(x) for r in mat for x in r) or 1.0
        body = "".join("<tr><th scope='row'>" + ("X", "Y", "N")[i] + "</th>" + "".join(
            f"<td class='num'>{'0' if abs(x) < 1e-12 * big else fmt_num(x)} <span class='unit'>{esc(u)}</span></td>"
            for x, u in zip(r, units[i])) + "</tr>" for i, r in enumerate(mat))
        cap_m = ctx.table_caption(f"{title} in SI units (from the bis values, eqs. 27–28).")
        mats += (f'<table class="data si">{cap_m}'
                 "<thead><tr><th></th><th class='num'>u</th><th class='num'>v</th><th class='num'>r</th></tr></thead>"
                 f"<tbody>{body}</tbody></table>")
    return f'<table class="est">{cap}<thead>{head}</thead><tbody>{"".join(rows)}</tbody></table>{mats}'
