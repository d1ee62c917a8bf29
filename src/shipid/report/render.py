"""Turning convention entries and section fragments into HTML.

:class:`RenderContext` numbers figures and tables, records which series entries
have been drawn (:class:`~shipid.report.registry.Claim`) and collects problems
(a figure that could not be drawn is replaced by a visible note, never a crash).
"""

from __future__ import annotations

import html
import math
import re
from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping

import numpy as np
from matplotlib.figure import Figure

from shipid.outputs import short_path
from shipid.report import figures as F
from shipid.report.formatting import fmt_num
from shipid.report.registry import Claim, Entry, Group
from shipid.report.stats import residual_stats

esc = html.escape

#: Authors and year of the paper each method follows (captions cite them, never "seed 00x").
PAPERS = {"mass-cm": "Linder et al. 2015", "dp": "Fossen, Sagatun & Sørensen 1996",
          "ebm": "Yoon & Rhee 2003", "ebm-study": "Yoon & Rhee 2003", "mmg-ebm": "Yoon & Rhee 2003",
          "ebm-design": "Yoon & Rhee 2003"}

_ABS_PATH = re.compile(r"(?<![\w.])(/[\w.\-+@]+)+/?")


_SEED_REF = re.compile(r"\s*\(seed 00\d\)|,?\s*\bseed 00\d\b", re.I)


_SCI = re.compile(r"(?<![\w.])(\d+(?:\.\d+)?)e([-+]?)0*(\d+)\b")
_SUPS = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def sci_text(text: str) -> str:
    """``5.3e-05`` in a method's message shown as ``5.3×10⁻⁵`` (no Python float text in the report)."""
    return _SCI.sub(lambda m: f"{m.group(1)}×10{(('-' if m.group(2) == '-' else '') + m.group(3)).translate(_SUPS)}",
                    text)


def plain_text(text: str) -> str:
    """Text of a method shown in the report: machine paths shortened, the project's internal paper
    numbers (the word "seed" and three digits) dropped (papers are named by authors and year), Python's 1.5e+08 as 1.5×10⁸."""
    return sci_text(_SEED_REF.sub("", short_paths(text)))


def short_paths(text: str) -> str:
    """Every absolute path in ``text`` shortened by :func:`short_path` (reports never show the machine's
    directory layout)."""
    if "/" not in text:
        return text
    return _ABS_PATH.sub(lambda m: short_path(m.group(0)) if m.group(0).count("/") >= 2 else m.group(0), text)


def paper_ref(method: str | None, ref: str | None) -> str:
    """``"Yoon & Rhee 2003, Table 4"`` for ``ref = "Table 4"`` (the paper figure a caption reproduces)."""
    if not ref:
        return ""
    who = PAPERS.get(method or "", "")
    return f"{who}, {ref}" if who and not re.search(r"\d{4}", str(ref)) else str(ref)


@dataclass
class RenderContext:
    """State shared while one report is built."""

    result: Any
    n_fig: int = 0
    n_tab: int = 0
    claimed: set = field(default_factory=set)
    authors: str = ""
    problems: list = field(default_factory=list)
    residual_rows: list = field(default_factory=list)

    # -- claims ------------------------------------------------------------------------------------
    def claim(self, kind: str, name: str) -> None:
        self.claimed.add((kind, name))

    def is_claimed(self, kind: str, name: str) -> bool:
        return (kind, name) in self.claimed

    def series(self, kind: str) -> dict:
        s = (self.result.series or {}).get(kind) or {}
        return s if isinstance(s, Mapping) else {}

    # -- primitives --------------------------------------------------------------------------------
    def figure(self, fig: Figure, caption: str = "", *, alt: str | None = None) -> str:
        """An inline PNG ``<figure>`` with a numbered caption (plain-text caption, escaped)."""
        self.n_fig += 1
        uri = F.to_data_uri(fig)
        fig.clear()
        caption = plain_text(caption) if caption else caption
        cap = f"<b>Figure {self.n_fig}.</b> {esc(caption)}" if caption else f"<b>Figure {self.n_fig}.</b>"
        return (f'<figure><img src="{uri}" alt="{esc(alt or caption or f"figure {self.n_fig}")}">'
                f"<figcaption>{cap}</figcaption></figure>")

    def table_caption(self, caption: str) -> str:
        self.n_tab += 1
        return f"<caption><b>Table {self.n_tab}.</b> {esc(plain_text(caption))}</caption>" if caption else \
            f"<caption><b>Table {self.n_tab}.</b></caption>"

    def problem(self, what: str, err: BaseException | str) -> str:
        msg = f"{what}: {type(err).__name__}: {err}" if isinstance(err, BaseException) else f"{what}: {err}"
        msg = " ".join(msg.split())
        self.problems.append(msg)
        return f'<div class="note bad">Could not draw {esc(what)} — {esc(msg)}</div>'

    def fragments(self, frags: Iterable, where: str) -> str:
        """HTML of a section function's fragment list (see :mod:`shipid.report.registry`)."""
        out = []
        for fr in frags or []:
            try:
                if isinstance(fr, Claim):
                    self.claim(fr.kind, fr.name)
                elif isinstance(fr, Entry):
                    entry = self.series(fr.kind).get(fr.name)
                    if entry is None:
                        out.append(self.problem(where, f"no series['{fr.kind}']['{fr.name}']"))
                    else:
                        out.append(render_entry(self, fr.kind, fr.name, entry, paper=fr.paper,
                                                default_title=fr.title))
                elif isinstance(fr, Group):
                    s = self.series(fr.kind)
                    items = [(n, s[n]) for n in fr.names if isinstance(s.get(n), Mapping)]
                    if items:
                        out.append(render_group(self, fr.kind, items, fr.caption))
                elif isinstance(fr, Mapping) and "columns" in fr and "rows" in fr:
                    out.append(data_table(self, fr, caption_of("", fr, fr.get("caption") or "",
                                                               method=self.result.method)))
                elif fr == "residual-checks":
                    out.append(residual_stats_table(self))
                elif isinstance(fr, str):
                    out.append(fr)
                elif isinstance(fr, Figure):
                    out.append(self.figure(fr))
                elif isinstance(fr, tuple) and len(fr) == 2 and isinstance(fr[0], Figure):
                    out.append(self.figure(fr[0], str(fr[1])))
                else:
                    out.append(self.problem(where, f"unknown fragment type {type(fr).__name__}"))
            except Exception as err:  # noqa: BLE001 - one bad figure must not lose the report
                out.append(self.problem(where, err))
        return "\n".join(out)


# -- captions ----------------------------------------------------------------------------------------

def caption_of(name: str, entry: Mapping, default: str, paper: str | None = None,
               method: str | None = None) -> str:
    """Caption text: the title, then the paper figure or table it reproduces in parentheses.

    The report's own number (``Figure 3.``, ``Table 2.``) is the only number in front; the paper's
    reference follows as ``(Yoon & Rhee 2003, Table 4)``.
    """
    paper = entry.get("paper") or paper  # the method's own reference wins over a default
    title = str(entry.get("title") or default).strip()
    if not paper:
        return title
    ref = paper_ref(method, str(paper))
    return f"{title} ({ref})" if not title.endswith(".") else f"{title[:-1]} ({ref})."


_PAPER_RE = re.compile(r"(fig|table)[a-z.]*\s*(\d+)", re.I)


def paper_sort_key(ref: str) -> tuple:
    """Sort "Fig. 4" < "Fig. 10" < "Table 1" (figures first, then tables, numerically)."""
    m = _PAPER_RE.search(ref or "")
    if not m:
        return (2, math.inf, ref)
    return (0 if m.group(1).lower().startswith("fig") else 1, int(m.group(2)), ref)


# -- tables ------------------------------------------------------------------------------------------

def _cell(v: Any) -> tuple[str, str]:
    """(html, css class) of one table cell."""
    if type(v).__name__ == "RecordsValue":  # shipid.report.html.RecordsValue: list of flat dicts
        keys = list(dict.fromkeys(k for r in v for k in r))
        head = "".join(f"<th>{esc(str(k))}</th>" for k in keys)
        body = "".join("<tr>" + "".join(f"<td class='{_cell(r.get(k))[1]}'>{_cell(r.get(k))[0]}</td>"
                                        for k in keys) + "</tr>" for r in v)
        return (f'<div class="scroll"><table class="rec"><thead><tr>{head}</tr></thead><tbody>{body}</tbody>'
                f'</table></div>'), ""
    if type(v).__name__ == "NamedVector":  # shipid.report.values.NamedVector: one value per estimate
        head = "".join(f"<th>{esc(str(n))}</th>" for n in v.names)
        body = "".join(f"<td>{fmt_num(x)}</td>" for x in v)
        return (f'<div class="scroll"><table class="rec nv"><thead><tr>{head}</tr></thead><tbody><tr>{body}</tr>'
                f'</tbody></table></div>'), ""
    if type(v).__name__ == "VectorValue":  # shipid.report.html.VectorValue: a short numeric vector
        body = "".join(f'<span class="vi">{fmt_num(x)}</span>' for x in v)
        return f'<div class="vec">{body}</div>', ""
    if type(v).__name__ == "MatrixValue":  # shipid.report.html.MatrixValue: a small matrix
        big = max((abs(float(x)) for row in v for x in row), default=0.0) or 1.0
        body = "".join("<tr>" + "".join(f"<td>{'0' if abs(float(x)) < 1e-12 * big else fmt_num(x)}</td>"
                                        for x in row) + "</tr>" for row in v)  # rounding residue shown as 0
        return f'<table class="mat"><tbody>{body}</tbody></table>', ""
    if isinstance(v, bool):
        return ("yes" if v else "no"), ""
    if isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool):
        return fmt_num(v), "num"
    if v is None:
        return "—", ""
    if isinstance(v, (list, tuple)):
        return esc(", ".join(plain_text(str(x)) for x in v)), ""
    return esc(plain_text(str(v))), ""


def data_table(ctx: RenderContext, entry: Mapping, caption: str) -> str:
    cols = [str(c) for c in entry.get("columns", [])]
    units = list(entry.get("units") or [])
    head = []
    for j, c in enumerate(cols):
        u = units[j] if j < len(units) else ""
        head.append(f"<th>{esc(c)}" + (f' <span class="unit">[{esc(u)}]</span>' if u and u != "" else "")
                    + "</th>")
    body = []
    for row in entry.get("rows", []):
        tds = []
        for v in row:
            h, cls = _cell(v)
            tds.append(f'<td class="{cls}">{h}</td>' if cls else f"<td>{h}</td>")
        body.append("<tr>" + "".join(tds) + "</tr>")
    note = f'<p class="small">{esc(entry["caption"])}</p>' if entry.get("caption") and \
        entry.get("caption") != caption else ""
    return (f'<table class="data">{ctx.table_caption(caption)}<thead><tr>{"".join(head)}</tr></thead>'
            f'<tbody>{"".join(body)}</tbody></table>{note}')


def kv_table(ctx: RenderContext | None, rows: Iterable[tuple], caption: str = "",
             cls: str = "kv") -> str:
    """Key–value table; rows are ``(key, value)`` or ``(key, value, unit)`` (unit shown after the value)."""
    body = []
    for row in rows:
        k, v = row[0], row[1]
        u = row[2] if len(row) > 2 else ""
        h, c = _cell(v)
        unit = f' <span class="unit">{esc(u)}</span>' if u and u != "-" and not h.startswith("<") else \
            (f'<div class="unit">[{esc(u)}]</div>' if u and u != "-" else "")
        body.append(f'<tr><th scope="row">{esc(str(k))}</th><td class="{c}">{h}{unit}</td></tr>')
    cap = ctx.table_caption(caption) if (ctx is not None and caption) else ""
    return f'<table class="{cls}">{cap}<tbody>{"".join(body)}</tbody></table>'


# -- residual statistics ------------------------------------------------------------------------------

def _residual_row(ctx: RenderContext, name: str, unit: str, st, innovation: bool = True) -> None:
    """Record one row of the residual-checks table; ``innovation=False`` for a simulation error
    (measured − simulated), whose autocorrelation is expected and therefore not flagged."""
    ctx.residual_rows.append((name, unit, st, innovation))


def _pvalue(p: float) -> str:
    """A p-value with 2 significant digits; below 10⁻¹⁰ shown as a bound (the χ² tail underflows)."""
    if not np.isfinite(p):
        return "—"
    return "&lt; 10⁻¹⁰" if p < 1e-10 else fmt_num(p, 2)


def residual_stats_table(ctx: RenderContext) -> str:
    """Whiteness / consistency of every residual drawn (Box–Jenkins ACF bounds, Ljung–Box)."""
    if not ctx.residual_rows:
        return ""
    head = ("<tr><th>residual</th><th>N</th><th>mean</th><th>RMS</th><th>unit</th>"
            "<th>lags outside ±1.96/√N</th><th>Ljung–Box p</th><th>inside ±2σ</th></tr>")
    body = []
    sim_rows = False
    for row in ctx.residual_rows:
        name, unit, st = row[:3]
        innovation = row[3] if len(row) > 3 else True
        frac = st.frac_outside
        white_bad = innovation and np.isfinite(frac) and frac > 0.10
        lb_bad = innovation and np.isfinite(st.ljung_box_p) and st.ljung_box_p < 0.01
        if not innovation:
            sim_rows = True
            name = f"{name} †"
        in2 = st.frac_in_2sigma
        in2_bad = np.isfinite(in2) and in2 < 0.90
        body.append(
            f"<tr><td>{esc(name)}</td><td class='num'>{st.n}</td><td class='num'>{fmt_num(st.mean, 3)}</td>"
            f"<td class='num'>{fmt_num(st.rms, 3)}</td><td>{esc(unit or '-')}</td>"
            f"<td class='num{' flag' if white_bad else ''}'>"
            f"{'—' if not np.isfinite(frac) else f'{100 * frac:.0f} % of {st.max_lag}'}</td>"
            f"<td class='num{' flag' if lb_bad else ''}'>{_pvalue(st.ljung_box_p)}</td>"
            f"<td class='num{' flag' if in2_bad else ''}'>{'—' if not np.isfinite(in2) else f'{100 * in2:.1f} %'}"
            "</td></tr>")
    ctx.residual_rows = []
    foot = ('<p class="small">† simulation error (measured − simulated by the identified model): it holds what the '
            "model leaves out (disturbances, noise filtered by the dynamics), so it is autocorrelated even for a "
            "correct model and is not flagged; whiteness is tested on innovations and equation errors.</p>"
            if sim_rows else "")
    return (f'<table class="data">{ctx.table_caption("Residual checks. White residuals have about 5 % of lags outside the ±1.96/√N bounds and a Ljung–Box p above 0.01; innovations should lie inside their predicted ±2σ about 95 % of the time. Flagged cells in red.")}'
            f"<thead>{head}</thead><tbody>{''.join(body)}</tbody></table>{foot}")


# -- one convention entry -----------------------------------------------------------------------------

def render_entry(ctx: RenderContext, kind: str, name: str, entry: Mapping, *, paper: str | None = None,
                 default_title: str | None = None) -> str:
    """HTML for ``result.series[kind][name]`` (marks it claimed). Errors become a visible note."""
    ctx.claim(kind, name)
    try:
        if not isinstance(entry, Mapping):
            raise TypeError(f"series['{kind}']['{name}'] is a {type(entry).__name__}, expected a dict")
        label = entry.get("label", name)
        if kind in ("overlays", "residuals", "signals"):
            entry = F.in_degrees(entry)       # angles in deg, as every table shows them
        if kind == "overlays":
            t = np.asarray(entry["t"], float)
            meas, mod = np.asarray(entry["measured"], float), np.asarray(entry["model"], float)
            res_entry = ctx.series("residuals").get(name)
            if isinstance(res_entry, Mapping):
                res_entry = F.in_degrees(res_entry)
            if isinstance(res_entry, Mapping) and len(res_entry.get("values", [])) == t.size:
                resid = np.asarray(res_entry["values"], float)
                std = res_entry.get("std")
                ctx.claim("residuals", name)
            else:
                resid, std = meas - mod, None
            st, r = residual_stats(resid, std)
            _residual_row(ctx, label, entry.get("unit", ""), st, innovation=isinstance(res_entry, Mapping)
                          and len(res_entry.get("values", [])) == t.size)
            what = "validation data, not used for estimation" if entry.get("kind") == "validation" else \
                "data used for estimation"
            zoom = F.zoom_window(t, meas)
            span = (f" The top panel shows t = {t[zoom[0]]:.0f}–{t[zoom[1] - 1]:.0f} s of the "
                    f"{t[-1] - t[0]:.0f}-s record (the whole record is too dense to read); the residual "
                    "panel and the statistics use every sample." if zoom else "")
            cap = caption_of(name, entry, (f"{default_title} " if default_title else "") +
                             f"{label}: measured and model ({what}); residual and its "
                             f"autocorrelation with 95 % white-noise bounds.{span}", paper, ctx.result.method)
            return ctx.figure(F.overlay_figure(name, entry, resid, r, st.acf_bound), cap)
        if kind == "residuals":
            st, r = residual_stats(entry["values"], entry.get("std"))
            _residual_row(ctx, label, entry.get("unit", ""), st)
            cap = caption_of(name, entry, (f"{default_title} " if default_title else "") +
                             f"{label}: residual" + (" with predicted ±2σ" if entry.get("std") else "")
                             + " and its autocorrelation.", paper, ctx.result.method)
            return ctx.figure(F.residual_figure(name, entry, r, st.acf_bound), cap)
        if kind == "histories":
            cap = caption_of(name, entry, default_title or f"{label} versus time with ±σ band.", paper,
                             ctx.result.method)
            return ctx.figure(F.histories_figure([(name, entry)], ncols=1), cap)
        if kind == "signals":
            cap = caption_of(name, entry, default_title or f"{label} versus time.", paper, ctx.result.method)
            return ctx.figure(F.signals_figure([(name, entry)]), cap)
        if kind == "matrices":
            cap = caption_of(name, entry, default_title or f"{label}.", paper, ctx.result.method)
            return ctx.figure(F.matrix_figure(entry), cap)
        if kind == "tables":
            return data_table(ctx, entry, caption_of(name, entry, default_title or entry.get("caption") or
                                                     name.replace("_", " "), paper, ctx.result.method))
        if kind == "contours":
            cap = caption_of(name, entry, default_title or
                             f"{entry.get('z_label', name)} over ({entry.get('x_label', 'x')}, "
                             f"{entry.get('y_label', 'y')}).", paper, ctx.result.method)
            return ctx.figure(F.contour_figure(entry), cap)
        if kind == "xy":
            cap = caption_of(name, entry, default_title or f"{label}.", paper, ctx.result.method)
            return ctx.figure(F.xy_figure(entry), cap)
        raise ValueError(f"unknown series kind {kind!r}")
    except Exception as err:  # noqa: BLE001
        return ctx.problem(f"series['{kind}']['{name}']", err)


def render_group(ctx: RenderContext, kind: str, items: list[tuple[str, Mapping]], caption: str) -> str:
    """Several ``histories`` or ``signals`` entries in one figure (small multiples / stacked)."""
    for name, _ in items:
        ctx.claim(kind, name)
    try:
        fig = F.histories_figure(items) if kind == "histories" else \
            F.signals_figure([(n, F.in_degrees(e)) for n, e in items])
        return ctx.figure(fig, caption)
    except Exception as err:  # noqa: BLE001
        return ctx.problem(f"{kind} ({', '.join(n for n, _ in items)})", err)
