"""Assemble the self-contained HTML report of a :class:`~shipid.result.Result`.

Layout: header (method, vessel, provenance) → verdict in plain words
(:mod:`shipid.report.verdict`) → warnings → data used → estimates (value, SE, 95 % CI,
unit, status — ``not determined`` above 100 % relative SE —, note; the DP bis values also
in SI; correlation heat map) → diagnostics (with units, matrices as tables) →
the method's sections (defaults in :mod:`shipid.report.sections`, then any the
method registered) → entries carrying a ``"paper"`` reference → every other
``series`` entry under the generic convention → residual checks → provenance.
No JavaScript, no external resources: CSS inline, figures as data URIs.
"""

from __future__ import annotations

import datetime as _dt
import math
import re
from pathlib import Path
from typing import Any, Mapping

import numpy as np

import shipid
from shipid.io.trial import CHANNELS
from shipid.errors import OutputExistsError
from shipid.outputs import atomic_write_text
from shipid import registry as method_registry
from shipid.report.formatting import format_estimate, fmt_num
from shipid.report.registry import load_method_sections, sections_for
from shipid.report.render import (RenderContext, esc, kv_table, paper_sort_key, render_entry, render_group,
                                  residual_stats_table)
from shipid.report import figures as F
from shipid.report.page import page
from shipid.report.units import pretty_unit
from shipid.report.values import flatten, si_table, with_units
from shipid.report.verdict import NOT_DETERMINED, verdict_html
from shipid import summary as _summary
from shipid.report.render import plain_text, short_paths

METHOD_TITLES = _summary.METHOD_TITLES

GENERIC_ORDER = ("overlays", "residuals", "histories", "signals", "contours", "matrices", "xy", "tables")
GENERIC_TITLES = {
    "overlays": "Measured and model", "residuals": "Residuals and innovations",
    "histories": "Parameter histories", "signals": "Time histories", "contours": "Maps",
    "matrices": "Matrices", "xy": "Other plots", "tables": "Further tables",
}



def _fmt_duration(s: float) -> str:
    if not np.isfinite(s):
        return "—"
    if s >= 3600:
        return f"{s / 3600:.2f} h ({fmt_num(s)} s)"
    if s >= 120:
        return f"{s / 60:.1f} min ({fmt_num(s)} s)"
    return f"{fmt_num(s)} s"


# -- page sections --------------------------------------------------------------------------------------

def _header(result) -> str:
    title, source = METHOD_TITLES.get(result.method, (f"Identification result: {result.method}", ""))
    model = result.model or {}
    prov = result.provenance or {}
    vessel = model.get("vessel") or prov.get("vessel")
    bits = [f"method <b>{esc(result.method)}</b>"]
    if source:
        bits.append(esc(source))
    if vessel:
        bits.append(f"vessel <b>{esc(str(vessel))}</b>")
    if prov.get("created"):
        bits.append(f"created {esc(str(prov['created']))}")
    if prov.get("shipid_version"):
        bits.append(f"shipid {esc(str(prov['shipid_version']))}")
    return (f'<header class="top"><h1>{esc(title)}</h1><div class="sub">{" · ".join(bits)}</div></header>')


def _badges(result, n_warnings: int) -> str:
    d = result.diagnostics or {}
    v = _summary.verdict(result)
    out = []
    if "converged" in d:
        ok = bool(d["converged"])
        out.append(f'<div class="badge {"ok" if ok else "bad"}">converged<b>{"yes" if ok else "NO"}</b></div>')
    if "iterations" in d:
        it = d["iterations"]
        if isinstance(it, Mapping):
            it = ", ".join(f"{k} {fmt_num(v)}" for k, v in it.items())
        else:
            it = fmt_num(it)
        out.append(f'<div class="badge">iterations<b>{esc(it)}</b></div>')
    out.append(f'<div class="badge">determined<b>{len(v.determined)}</b></div>')
    if v.not_determined:
        out.append(f'<div class="badge bad">not determined<b>{len(v.not_determined)}</b></div>')
    out.append(f'<div class="badge {"bad" if n_warnings else "ok"}">warnings<b>{n_warnings}</b></div>')
    prov0 = result.provenance or {}
    ins = prov0.get("inputs") or prov0.get("training_runs") or prov0.get("trials") or []
    if isinstance(ins, (list, tuple)):
        out.append(f'<div class="badge">input trials<b>{len(ins)}</b></div>')
    return f'<div class="badges">{"".join(out)}</div>'


def report_warnings(result, extra: list[str]) -> list[str]:
    """The warnings the report shows, once: the method's; a line naming the quantities the method called
    estimated that the report shows as not determined (relative SE above 100 %), so that a count in the
    method's own words is explained; then the report's own problems."""
    out = [plain_text(w) for w in _summary.warnings_of(result)]
    relabelled = [n for n, e in result.estimates.items()
                  if _summary.grade(e) == NOT_DETERMINED and str(e.status) == "estimated"]
    if relabelled:
        out.append(f"report: {len(relabelled)} quantit{'y' if len(relabelled) == 1 else 'ies'} the method reports "
                   f"as estimated {'has' if len(relabelled) == 1 else 'have'} a relative SE above 100 % and "
                   f"{'is' if len(relabelled) == 1 else 'are'} shown as not determined: {', '.join(relabelled)}")
    return out + [f"report: {p}" for p in extra]


def _warnings(warns: list[str]) -> str:
    if not warns:
        return ""
    items = "".join(f"<li>{esc(w)}</li>" for w in warns)
    return f'<section class="warnings" id="warnings"><h2>Warnings ({len(warns)})</h2><ul>{items}</ul></section>'


def _fold(key: str, title: str, body: str, *, open_: bool = False, note: str = "") -> str:
    """A section under a ``<details>`` whose summary is its heading (``id`` = ``key``)."""
    extra = f' <span class="small">{esc(note)}</span>' if note else ""
    return (f'<details class="sec" id="{key}"{" open" if open_ else ""}><summary><h2>{esc(title)}{extra}</h2>'
            f"</summary>{body}</details>")


def _data_section(ctx: RenderContext, result) -> str:
    prov = result.provenance or {}
    ins = prov.get("inputs")
    for alt in ("training_runs", "trials", "files"):  # other names methods use for their inputs
        if ins is None and isinstance(prov.get(alt), (list, tuple)):
            ins = prov[alt]
    if ins is None:  # model["inputs"] often names the model's input signals: only trial records count
        m_in = (result.model or {}).get("inputs")
        if isinstance(m_in, (list, tuple)) and m_in and all(isinstance(x, Mapping) for x in m_in):
            ins = m_in
    if ins is None:
        return '<p class="small">The result does not record its inputs.</p>'
    if isinstance(ins, (str, Mapping)):
        ins = [ins]
    head = ("<tr><th>trial</th><th class='num'>samples</th><th class='num'>duration</th>"
            "<th class='num'>sampling</th><th>channels [unit]</th><th>note</th></tr>")
    rows = []
    for item in ins:
        if not isinstance(item, Mapping):
            rows.append(f"<tr><td><code>{esc(short_paths(str(item)))}</code></td><td></td><td></td><td></td>"
                        "<td></td><td></td></tr>")
            continue
        name = short_paths(str(item.get("name") or item.get("file") or item.get("path") or "—"))
        n = item.get("n_samples")
        dur = item.get("duration_s")
        dt = item.get("dt_s")
        if dt is None and item.get("rate_hz"):
            dt = 1.0 / float(item["rate_hz"])
        samp = "—"
        if dt is not None and np.isfinite(float(dt)) and float(dt) > 0:
            samp = f"{fmt_num(float(dt), 3)} s ({fmt_num(1.0 / float(dt), 3)} Hz)"
        ch = item.get("channels")
        if isinstance(ch, Mapping):
            chs = " ".join(f"<span class='chan'>{esc(str(k))} <span class='unit'>[{esc(pretty_unit(str(u)))}]"
                           "</span></span>" for k, u in ch.items())
        elif isinstance(ch, (list, tuple)):
            chs = " ".join(f"<span class='chan'>{esc(str(c))}</span>" for c in ch)
        else:
            chs = "—" if ch is None else esc(str(ch))
        note_bits = [f"{k}: {item[k]}" for k in ("vessel", "manoeuvre", "seed") if k in item]
        if item.get("note"):
            note_bits.append(short_paths(str(item["note"])))
        rows.append(f"<tr><td><code>{esc(str(name))}</code></td><td class='num'>{fmt_num(n) if n is not None else '—'}"
                    f"</td><td class='num'>{_fmt_duration(float(dur)) if dur is not None else '—'}</td>"
                    f"<td class='num'>{samp}</td><td>{chs}</td><td>{esc('; '.join(note_bits))}</td></tr>")
    return (f'<table class="data">{ctx.table_caption("Trials the estimates come from.")}'
            f"<thead>{head}</thead><tbody>{''.join(rows)}</tbody></table>")


TR_NOTDET = '<tr class="notdet">'


def _estimates_section(ctx: RenderContext, result) -> str:
    head = ("<tr><th>parameter</th><th class='num'>estimate</th><th class='num'>standard error</th>"
            "<th class='num'>95 % confidence interval</th><th class='num'>rel. SE</th><th>unit</th>"
            "<th>verdict</th><th>note</th></tr>")
    rows = []
    # a note repeated on many rows is shown once under the table, with a marker in the rows
    counts: dict[str, int] = {}
    for e in result.estimates.values():
        if e.note:
            counts[e.note] = counts.get(e.note, 0) + 1
    common = [n for n, c in counts.items() if c >= 3]
    marks = {n: "abcdefghijklmnopqrstuvwxyz"[i % 26] for i, n in enumerate(common)}
    grades = _summary.verdict(result).grades
    for name, e in result.estimates.items():
        f = format_estimate(e.value, e.std)
        g = grades[name]
        und = g == NOT_DETERMINED
        ci = "—" if f.ci_low == "—" else f"[{f.ci_low}, {f.ci_high}]"
        scale = f' <span class="unit">{f.scale}</span>' if f.scale else ""
        if und:   # never shown as an estimate: the stored value is in the JSON and to_frame()
            cells = ("<td class='num'>—</td>" * 4)
        else:
            cells = (f"<td class='num'>{f.value}{scale}</td>"
                     f"<td class='num'>{f.std}{scale if f.std not in ('—', 'not identifiable') else ''}</td>"
                     f"<td class='num'>{ci}{scale if ci != '—' else ''}</td><td class='num'>{f.rel}</td>")
        st_cls = "notdet" if und else g.replace(" ", "")
        rows.append(
            f"{TR_NOTDET if und else '<tr>'}<td><b>{esc(name)}</b></td>{cells}"
            f"<td>{esc(pretty_unit(e.unit))}</td><td><span class='grade {esc(st_cls)}'>{esc(g)}</span></td>"
            + (f"<td><sup>({marks[e.note]})</sup></td></tr>" if e.note in marks
               else f"<td>{esc(plain_text(e.note))}</td></tr>"))
    if not rows:
        body = '<p class="small">No estimates.</p>'
    else:
        cap = ctx.table_caption("Estimates with standard errors; 95 % intervals are value ± 1.96 SE (normal "
                                "approximation). Digits follow the SE.")
        foot = "".join(f'<p class="small"><sup>({m})</sup> {esc(plain_text(n))}</p>' for n, m in marks.items())
        used = list(dict.fromkeys(grades.values()))
        foot += ('<p class="small">Verdict: ' + "; ".join(
            f"<span class='grade {esc(g.replace(' ', ''))}'>{esc(g)}</span> {esc(_summary.GRADE_TEXT[g])}"
            for g in used if g in _summary.GRADE_TEXT) + ".</p>")
        foot += si_table(ctx, result)
        body = (f'<div class="scroll"><table class="est">{cap}'
                f"<thead>{head}</thead><tbody>{''.join(rows)}</tbody></table></div>{foot}")
    cov_html = ""
    if result.covariance is not None and len(result.covariance_names) >= 2:
        try:
            entry = F.correlation_from_covariance(result.covariance, result.covariance_names)
            r = np.asarray(entry["values"])
            off = np.abs(r - np.diag(np.diag(r)))
            high = [(result.covariance_names[i], result.covariance_names[j], r[i, j])
                    for i in range(r.shape[0]) for j in range(i + 1, r.shape[1]) if off[i, j] > 0.95]
            cov_html = ctx.figure(F.matrix_figure(entry), "Correlation of the estimates (from the covariance), "
                                                          "labelled by estimate.")
            if high:
                pairs = ", ".join(f"{a}–{b} ({v:+.3f})" for a, b, v in high)
                cov_html += (f'<div class="note bad">Strongly correlated estimates (|ρ| &gt; 0.95): {esc(pairs)}. '
                             "They are hard to separate with these data.</div>")
        except Exception as err:  # noqa: BLE001
            cov_html = ctx.problem("the correlation matrix", err)
    if cov_html:
        cov_html = f"<details><summary>Correlation of the estimates</summary>{cov_html}</details>"
    return f"{body}{cov_html}"


def _zero(v) -> bool:
    try:
        return float(v) == 0.0
    except (TypeError, ValueError):
        return False


def _shown(rows: list[tuple]) -> list[tuple]:
    """Rows worth a reader's time: no ``options.*`` dump, no all-zero ``simex.*`` rows, no correlation or
    covariance matrix without row and column names (the estimates' correlation is drawn labelled; the
    rest stay in the result JSON)."""
    out = []
    for row in rows:
        k, v = str(row[0]), row[1]
        if k.startswith("options.") or (k.startswith("simex") and (_zero(v) or v in ("none", "", None))):
            continue
        if type(v).__name__ == "MatrixValue" and re.search(r"corr|cov", k, re.I):
            continue
        out.append(row)
    return out


def _diagnostics_section(ctx: RenderContext, result) -> str:
    d = {k: v for k, v in (result.diagnostics or {}).items() if k != "warnings"}
    if not d:
        return ""
    sx = d.get("simex")
    if isinstance(sx, Mapping) and not sx.get("applied", True):   # a correction not made: one line, no zeros
        move = sx.get("pilot_largest_move_in_se")
        d["simex"] = "not applied" + (f" (the pilot run moved no estimate by more than {fmt_num(move, 2)} SE)"
                                      if isinstance(move, (int, float)) else "")
    return kv_table(ctx, _shown(with_units(result, flatten(d, names=result.estimates))), "Estimator diagnostics.")


def _provenance_section(ctx: RenderContext, result) -> str:
    prov = {k: v for k, v in (result.provenance or {}).items() if k != "inputs"}
    model = result.model or {}
    prov = {k: v for k, v in prov.items() if k != "options"}   # the options are in the result JSON
    out = ""
    if model:
        out += kv_table(ctx, _shown(with_units(result, flatten(model))), "Model structure and vessel particulars.")
    if prov:
        out += kv_table(ctx, _shown(with_units(result, flatten(prov))), "Provenance.")
    return out


def _method_sections(ctx: RenderContext, result, load_problems: list[str]) -> str:
    out = []
    for title, fn in sections_for(result.method):
        try:
            frags = fn(result)
        except Exception as err:  # noqa: BLE001 - a broken section must not lose the report
            out.append(f"<h3>{esc(title)}</h3>" + ctx.problem(f"section '{title}'", err))
            continue
        body = ctx.fragments(frags, f"section '{title}'")
        if body.strip():
            out.append(f"<h3>{esc(title)}</h3>{body}")
    # entries that name their place in the paper
    papers = []
    for kind in GENERIC_ORDER:
        for name, entry in ctx.series(kind).items():
            if isinstance(entry, Mapping) and entry.get("paper") and not ctx.is_claimed(kind, name):
                papers.append((paper_sort_key(str(entry["paper"])), kind, name, entry))
    papers.sort(key=lambda p: p[0])
    for _, kind, name, entry in papers:
        out.append(render_entry(ctx, kind, name, entry))
    if not out:
        return ""
    return f'{"".join(out)}{residual_stats_table(ctx)}'


def _generic_sections(ctx: RenderContext, result) -> str:
    out = []
    known = set(GENERIC_ORDER)
    for kind in GENERIC_ORDER:
        items = [(n, e) for n, e in ctx.series(kind).items() if not ctx.is_claimed(kind, n)]
        if not items:
            continue
        parts = []
        if kind in ("histories", "signals") and all(isinstance(e, Mapping) for _, e in items) and len(items) > 1:
            chunk = 12 if kind == "histories" else 6
            for i in range(0, len(items), chunk):
                part = items[i:i + chunk]
                parts.append(render_group(ctx, kind, part, f"{GENERIC_TITLES[kind]}: "
                                          f"{', '.join(e.get('label', n) for n, e in part)}"
                                          + (" (±σ bands)." if kind == "histories" else ".")))
        else:
            # fit overlays first, validation after
            if kind == "overlays":
                items.sort(key=lambda ne: isinstance(ne[1], Mapping) and ne[1].get("kind") == "validation")
            parts = [render_entry(ctx, kind, n, e) for n, e in items]
        out.append(f"<h3>{GENERIC_TITLES[kind]}</h3>{''.join(parts)}")
        if kind in ("overlays", "residuals"):
            out.append(residual_stats_table(ctx))
    unknown = [k for k in (result.series or {}) if k not in known]
    loose_html, drawn = _loose_series(ctx, result, unknown)
    if loose_html:
        out.append(f"<h3>Other stored series</h3>{loose_html}")
    unknown = [k for k in unknown if k not in drawn]
    if unknown:
        out.append(f'<p class="small">Series not drawn (not part of the report convention): '
                   f'{esc(", ".join(sorted(map(str, unknown))))}.</p>')
    if not out:
        return ""
    return "".join(out)


def _guess_unit(name: str) -> str | None:
    """SI unit of a standard channel name (``r``, ``u_r`` -> ``u``), else None."""
    for cand in (name, name.split("_")[0]):
        if cand in CHANNELS and cand != "t":
            return CHANNELS[cand]
    return None


def _loose_unit(result, name: str) -> str:
    """Unit of a loose series: that of the estimate of the same name, else of the standard channel, else "-"."""
    e = result.estimates.get(name)
    if e is not None and getattr(e, "unit", None):
        return pretty_unit(str(e.unit))
    return _guess_unit(name) or "-"


LOOSE_X = ("t", "time", "t_s", "iteration", "iterations", "k")


def _loose_series(ctx: RenderContext, result, keys: list[str]) -> tuple[str, set]:
    """Fallback for series stored outside the convention as flat lists beside an x vector.

    When ``series`` has a top-level ``t`` (or ``time``, ``iteration`` ...) list, every other
    top-level numeric list of the same length is drawn against it in stacked panels (no
    units are known, so none are shown). Returns the HTML and the keys drawn.
    """
    series = result.series or {}
    xkey = next((k for k in LOOSE_X if k in series and k in keys), None)
    if xkey is None:
        return "", set()
    try:
        x = np.asarray(series[xkey], dtype=float).ravel()
    except (TypeError, ValueError):
        return "", set()
    cols = []
    for k in keys:
        if k == xkey:
            continue
        try:
            v = np.asarray(series[k], dtype=float)
        except (TypeError, ValueError):
            continue
        if v.ndim == 1 and v.size == x.size and x.size > 1:
            cols.append((k, v))
    if not cols:
        return "", set()
    xlabel = "t [s]" if xkey in ("t", "time", "t_s") else f"{xkey} [-]"
    html_parts = []
    for i in range(0, len(cols), 6):
        part = cols[i:i + 6]
        items = [(k, {"t": x, "lines": {k: v}, "label": k, "unit": _loose_unit(result, k)}) for k, v in part]
        try:
            fig = F.signals_figure(items)
            fig.axes[-1].set_xlabel(xlabel)
            moved = _final_differs(result, part, fig)
            note = ""
            if moved:
                note = (" The dashed line is the final estimate of the estimates table, which differs from the "
                        "last iterate (a later stage, such as a refinement, moved it): "
                        + "; ".join(f"{k} {fmt_num(a, 3)} → {fmt_num(b, 3)}" for k, a, b in moved) + ".")
            html_parts.append(ctx.figure(fig, f"{', '.join(k for k, _ in part)} versus {xkey} "
                                              "(stored outside the report convention; units from the "
                                              "estimate with that name or the standard channel names)." + note))
        except Exception as err:  # noqa: BLE001
            html_parts.append(ctx.problem(f"series {', '.join(k for k, _ in part)}", err))
    return "".join(html_parts), {xkey, *(k for k, _ in cols)}


def _final_differs(result, part, fig) -> list[tuple[str, float, float]]:
    """For iterate histories drawn in ``fig`` (one axes per entry of ``part``): the entries whose last
    iterate differs from the estimate of the same name by more than 1 % of it or of its SE; the
    estimate is drawn there as a dashed line. Returns ``(name, last iterate, estimate)``."""
    out = []
    axes = [ax for ax in fig.axes if ax.has_data()]
    for ax, (k, v) in zip(axes, part):
        e = result.estimates.get(k)
        if e is None or _summary.grade(e) == NOT_DETERMINED or not v.size or not np.isfinite(v[-1]):
            continue
        tol = 0.01 * max(abs(float(e.value)), float(e.std) if np.isfinite(e.std) else 0.0)
        if abs(float(v[-1]) - float(e.value)) > tol:
            ax.axhline(float(e.value), color="#b3261e", ls="--", lw=1.0)
            out.append((k, float(v[-1]), float(e.value)))
    return out


def _enriched(result):
    """``result`` completed by its method's ``report.enrich`` hook when it has one.

    A method's report module may define ``enrich(result) -> Result`` to add what the report needs
    and the result file does not carry (the MMG method re-reads its training runs for the data
    summary and the fit overlays).
    """
    info = method_registry.for_result(result.method)
    if info is None or not info.has_module("report"):
        return result
    hook = getattr(info.submodule("report"), "enrich", None)
    return hook(result) if callable(hook) else result


def build_report(result) -> str:
    """The complete HTML document for ``result`` (a :class:`~shipid.result.Result`).

    Never raises for odd ``series`` content: a figure that cannot be drawn is
    replaced by a visible note and listed among the warnings.
    """
    result = _enriched(result)
    ctx = RenderContext(result)
    load_problems = load_method_sections(result.method)
    ctx.problems.extend(load_problems)
    parts = {
        "data": _data_section(ctx, result),
        "estimates": _estimates_section(ctx, result),
        "diagnostics": _diagnostics_section(ctx, result),
        "method": _method_sections(ctx, result, load_problems),
        "series": _generic_sections(ctx, result),
        "provenance": _provenance_section(ctx, result),
    }
    titles = {"data": "Data used", "estimates": "Estimates", "diagnostics": "Diagnostics",
              "method": "Figures and tables of the method", "series": "Time histories and checks",
              "provenance": "Model and provenance"}
    toc_names = {"verdict": "Verdict", "warnings": "Warnings", "data": "Data", "estimates": "Estimates",
                 "diagnostics": "Diagnostics",
                 "method": "Method figures", "series": "Time histories", "provenance": "Provenance"}
    warns = report_warnings(result, ctx.problems)
    warnings = _warnings(warns)
    present = ["verdict"] + (["warnings"] if warnings else []) + [k for k, v in parts.items() if v]
    toc = "".join(f'<a href="#{k}">{toc_names[k]}</a>' for k in present)
    n_fig = {k: v.count("<img") for k, v in parts.items()}
    folded = "\n".join(
        _fold(k, titles[k], v, open_=k in ("estimates",),
              note=f"({n_fig[k]} figure{'s' if n_fig[k] != 1 else ''})" if n_fig[k] else "")
        for k, v in parts.items() if v)
    now = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
    title = METHOD_TITLES.get(result.method, (result.method, ""))[0]
    vessel = (result.model or {}).get("vessel")
    doc_title = f"shipid report — {result.method}" + (f" — {vessel}" if vessel else "")
    return page(doc_title, (
        f"{_header(result)}<nav class=\"toc\">{toc}</nav>{_badges(result, len(warns))}"
        f"{verdict_html(result, warns)}{warnings}\n"
        '<p class="small">The sections below are folded: click a heading to open it.</p>\n'
        + folded
        + f"\n<footer>Report written by shipid {esc(shipid.__version__)} at {esc(now)} · {esc(title)} · "
          "self-contained: no network needed to view.</footer>"))


def write_report(result, path, *, force: bool = False) -> Path:
    """Build the report and write it atomically to ``path`` (never clobbers without ``force``)."""
    dest = Path(path)
    if dest.exists() and not force:  # fail before the (slow) figure drawing
        raise OutputExistsError(str(path))
    return atomic_write_text(dest, build_report(result), force=force)
