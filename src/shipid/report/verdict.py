"""The first screen of a report: what was found, how far to trust it, what to do next.

Everything comes from the result: ``diagnostics["converged"]``, the estimates and their
standard errors, ``diagnostics["warnings"]``, a recorded coverage study
(``diagnostics["coverage"]`` or ``provenance["coverage"]``, else the ``COVERAGE`` table a method
module publishes, :func:`known_coverage`) and held-out validation
(``series["overlays"]`` entries of ``kind = "validation"``, or ``diagnostics["validation"]``).

The verdict on each estimate is :func:`shipid.summary.grade`, computed once
(:func:`shipid.summary.verdict`) and used by the panel, the badges, the estimates table and
``Result.summary()`` alike: an estimate is in exactly one list.
"""

from __future__ import annotations

import html
import math
import re
from typing import Any, Mapping

import numpy as np

from shipid import registry as method_registry
from shipid.report.formatting import fmt_num, format_estimate
from shipid.report.units import pretty_unit
from shipid.summary import (LOOSE, NOT_DETERMINED, REL_SE_UNDETERMINED, WELL, Verdict, effective_status,
                            rel_se, verdict, warnings_of)

esc = html.escape

__all__ = ["verdict_html", "verdict_facts", "known_coverage", "effective_status", "rel_se", "NOT_DETERMINED",
           "REL_SE_UNDETERMINED", "WELL", "LOOSE"]


def _warnings(result) -> list[str]:
    return warnings_of(result)


def _coverage_text(result) -> tuple[str, str]:
    """(css class, sentence) about the coverage study of the stated uncertainty."""
    d, p = result.diagnostics or {}, result.provenance or {}
    cov = d.get("coverage", p.get("coverage"))
    if cov is None:
        cov = known_coverage(result.method)
    if isinstance(cov, Mapping) and cov:
        frac = next((cov[k] for k in ("coverage", "fraction", "coverage_2std", "value") if k in cov), None)
        n = cov.get("n") or cov.get("runs") or cov.get("realisations")
        nominal = cov.get("nominal", 0.954)
        bits = []
        if isinstance(frac, (int, float)):
            bits.append(f"the ±2 SE intervals covered the true value in {100 * float(frac):.0f} % of "
                        + (f"{n} " if n else "") + f"simulated runs (nominal {100 * float(nominal):.0f} %)")
            ok = abs(float(frac) - float(nominal)) <= 0.05
            verdict = "the stated uncertainty is about right" if ok else (
                "the stated uncertainty is too small (optimistic)" if float(frac) < float(nominal) else
                "the stated uncertainty is conservative")
            bits.append(verdict)
        else:
            per = {k: v for k, v in cov.items() if isinstance(v, (int, float)) and not isinstance(v, bool)}
            if per:
                bits.append("coverage of ±2 SE per quantity: "
                            + ", ".join(f"{k} {100 * float(v):.0f} %" for k, v in per.items()))
        if cov.get("note"):
            bits.append(str(cov["note"]))
        if bits:
            return ("ok" if "about right" in " ".join(bits) else "warn"), "Coverage study: " + "; ".join(bits) + "."
    if isinstance(cov, str) and cov.strip():
        return "warn", f"Coverage study: {cov.strip()}"
    opt = any("optimistic" in str(getattr(e, "note", "")).lower() for e in result.estimates.values())
    text = ("No coverage study of the stated standard errors is recorded with this result, so how well they "
            "match the real scatter has not been checked here")
    if opt:
        text += "; the method itself calls its standard errors optimistic (see the notes of the estimates)"
    return "warn", text + "."


def known_coverage(method: str) -> Mapping | None:
    """A coverage study the method publishes as ``COVERAGE`` (through :mod:`shipid.registry`).

    The mapping holds ``coverage`` (fraction of runs whose ±2 SE interval held the true value),
    ``n`` (runs), optionally ``nominal``, ``note`` and ``source`` (the study that produced it).
    """
    info = method_registry.for_result(method)
    cov = None if info is None else info.coverage
    if not cov:
        return None
    out = dict(cov)
    if out.get("source"):
        out["note"] = "; ".join(x for x in (str(out.get("note") or ""), f"source: {out['source']}") if x)
    return out


def _validation_text(result) -> list[str]:
    """Held-out prediction errors the result carries (RMS of measured − model per validation overlay)."""
    out = []
    ov = (result.series or {}).get("overlays") or {}
    if isinstance(ov, Mapping):
        for name, e in ov.items():
            if not isinstance(e, Mapping) or e.get("kind") != "validation":
                continue
            try:
                err = np.asarray(e["measured"], float) - np.asarray(e["model"], float)
                rms = float(np.sqrt(np.nanmean(err ** 2)))
                span = float(np.nanstd(np.asarray(e["measured"], float)))
            except (KeyError, TypeError, ValueError):
                continue
            unit = e.get("unit") or ""
            if unit in ("rad", "rad/s"):     # angles in deg, as the validation tables
                rms, span, unit = math.degrees(rms), math.degrees(span), unit.replace("rad", "deg")
            text = f"{e.get('label', name)}: RMS error {fmt_num(rms, 3)} {unit}".rstrip()
            if span > 0:
                text += f" ({fmt_num(100 * rms / span, 2)} % of the measured signal's standard deviation)"
            out.append(text)
    v = (result.diagnostics or {}).get("validation")
    if isinstance(v, Mapping) and not out:
        for k, x in v.items():
            if isinstance(x, (int, float)) and not isinstance(x, bool):
                out.append(f"{k}: {fmt_num(x, 3)}")
    return out


def _list(names: list[tuple[str, float]], limit: int = 8) -> str:
    items = [f"{esc(n)} ({fmt_num(100 * r, 2)} %)" if math.isfinite(r) else esc(n) for n, r in names[:limit]]
    more = len(names) - limit
    return ", ".join(items) + (f" and {more} more" if more > 0 else "")


def _real_data(result) -> bool:
    """Measured (not simulated) inputs: the real-data pipeline, or input files that are not simulations."""
    if result.method == "mmg-ebm":
        return True
    p = result.provenance or {}
    ins = p.get("inputs") or p.get("training_runs") or []
    names = [str(x.get("name") or x.get("file") or "") if isinstance(x, Mapping) else str(x) for x in ins]
    files = [n for n in names if re.search(r"\.(csv|dat|parquet|pq|txt|nmea|log)$", n, re.I)]
    return bool(files) and not any("simulat" in n.lower() for n in names)


_LISTS = (
    ("well", "ok", f"<b>Well determined</b> (relative SE ≤ {100 * WELL:.0f} %)"),
    ("loose", "", f"<b>Loosely determined</b> (relative SE {100 * WELL:.0f}–{100 * LOOSE:.0f} %)"),
    ("poor", "warn", f"<b>Poorly determined</b> (relative SE {100 * LOOSE:.0f}–100 %)"),
    ("no SE", "warn", "<b>Without a standard error</b>"),
    ("flagged", "warn", "<b>Flagged by the method</b> as weakly determined or biased beyond their SE (see the notes "
                        "of the estimates)"),
    (NOT_DETERMINED, "bad", "<b>Not determined by these data</b> (relative SE above 100 % or the method's own test; "
                            "shown as <i>not determined</i>, never as estimates)"),
)


def _found_table(result, v: Verdict, limit: int = 14) -> str:
    """The determined estimates and derived quantities, value ± SE, compact (the full table is below)."""
    rows = []
    names = v.tabled
    for n in names[:limit]:
        e = result.estimates[n]
        f = format_estimate(e.value, e.std)
        sd = f" ± {f.std}" if f.std not in ("—", "not identifiable") else ""
        g = v.grades[n]
        rows.append(f"<tr><td><b>{esc(n)}</b></td><td class='num'>{f.value}{sd}{(' ' + f.scale) if f.scale else ''}"
                    f"</td><td>{esc(pretty_unit(e.unit))}</td><td><span class='grade {g.replace(' ', '')}'>"
                    f"{esc(g)}</span></td></tr>")
    more = len(names) - limit
    if more > 0:
        rows.append(f"<tr><td colspan='4' class='small'>… and {more} more in <a href='#estimates'>Estimates</a>"
                    "</td></tr>")
    if not rows:
        rows.append("<tr><td colspan='4'>No quantity is determined by these data.</td></tr>")
    und = v.not_determined
    tail = ""
    if und:
        tail = (f"<p class='small'><b>Not determined ({len(und)})</b>, not estimates: "
                f"{esc(', '.join(und))}.</p>")
    return (f"<table class='found'><thead><tr><th>quantity</th><th class='num'>estimate ± SE</th><th>unit</th>"
            f"<th>verdict</th></tr></thead><tbody>{''.join(rows)}</tbody></table>{tail}")


def _headline(v: Verdict, n_warn: int) -> str:
    n = len(v.grades)
    det, und = len(v.determined), len(v.not_determined)
    est_total = det + und
    bits = [f"{det} of {est_total} estimated quantit{'y' if est_total == 1 else 'ies'} determined by these data"
            if est_total else "no estimated quantities"]
    if und:
        bits.append(f"{und} not determined")
    weak = len(v.names("poor", "flagged", "no SE"))
    if weak:
        bits.append(f"{weak} of them poorly determined or flagged")
    bits.append({True: "the estimator converged", False: "the estimator DID NOT converge",
                 None: "convergence not recorded"}[v.converged])
    bits.append(f"{n_warn} warning{'' if n_warn == 1 else 's'}")
    cls = "bad" if (v.converged is False or (est_total and und * 2 > est_total)) else (
        "warn" if (und or n_warn or weak) else "ok")
    return f'<p class="headline {cls}">{esc("; ".join(bits))}.</p>' if n else \
        '<p class="headline warn">The result carries no estimates.</p>'


def _next_steps(result, v: Verdict, n_warn: int) -> list[tuple[str, str]]:
    out = []
    if v.converged is False:
        out.append(("bad", "Do not use these estimates: the estimator did not converge. Check the data named in the "
                           "warnings and run again."))
    und = v.not_determined
    if und:
        what = (f"{esc(und[0])} is not determined and is not an estimate: fix it" if len(und) == 1 else
                f"The {len(und)} not-determined quantities are not estimates: fix them")
        out.append(("bad", f"{what} from a prior or a published set, or add trials that excite "
                           f"{'it' if len(und) == 1 else 'them'} (other rudder angles, speed changes, longer runs) "
                           "and identify again."))
    weak = v.names("poor", "flagged", "no SE")
    if weak:
        out.append(("warn", f"Use {', '.join(esc(x) for x in weak[:6])}{' …' if len(weak) > 6 else ''} with care: "
                            "read their notes in the estimates table."))
    if n_warn:
        out.append(("warn", f"Read the {n_warn} warning{'s' if n_warn != 1 else ''} below: each names what it "
                            "affects."))
    if not _validation_text(result):
        out.append(("", "Check the model on a run it was not fitted to: "
                        "<code>shipid validate MODEL.json --trial RUN</code>."))
    if not out:
        out.append(("ok", "Nothing here stops you using the model."))
    return out


def verdict_html(result, warnings: list[str] | None = None) -> str:
    """The ``<section class="verdict">`` first screen.

    ``warnings`` is the list the report's warnings box shows (the method's warnings and any
    report problem); its length is the count quoted here, so the two cannot disagree.
    """
    v = verdict(result)
    warns = list(v.warnings) if warnings is None else list(warnings)
    lines: list[tuple[str, str]] = []  # (css class, html)
    if v.converged is True:
        lines.append(("ok", "<b>Converged.</b> The estimator reports convergence."))
    elif v.converged is False:
        lines.append(("bad", "<b>Did not converge.</b> The estimates are the last iterate and must not be "
                             "trusted."))
    else:
        lines.append(("warn", "<b>Convergence not recorded</b> by this method."))
    for g, cls, label in _LISTS:
        names = v.names(g)
        if names:
            pct = g != NOT_DETERMINED   # the method's test, not the relative SE, may have decided these
            lines.append((cls, f"{label}: "
                               f"{_list([(n, rel_se(result.estimates[n]) if pct else math.nan) for n in names])}."))
    fixed = v.not_estimated
    if fixed:
        lines.append(("", f"Not estimated (fixed, known or derived): {len(fixed)} "
                          f"quantit{'y' if len(fixed) == 1 else 'ies'}."))
    lines.append(_coverage_text(result))
    if warns:
        lines.append(("bad", f"<b>{len(warns)} warning{'s' if len(warns) != 1 else ''}</b> "
                             "(listed below the verdict)."))
    else:
        lines.append(("ok", "No warnings."))
    val = _validation_text(result)
    if val:
        lines.append(("", "<b>Held-out prediction</b> (data not used for estimation): "
                          + "; ".join(esc(x) for x in val) + "."))
    elif _real_data(result):
        lines.append(("warn", "<b>No held-out prediction error</b> is recorded with this result."))
    setting = (result.provenance or {}).get("demo_setting")
    if setting:
        lines.append(("", f"<b>Demo setting:</b> {esc(str(setting))}"))
    trust = "".join(f'<li class="{c}">{t}</li>' for c, t in lines)
    nxt = "".join(f'<li class="{c}">{t}</li>' for c, t in _next_steps(result, v, len(warns)))
    return (f'<section class="verdict" id="verdict"><h2>Verdict</h2>{_headline(v, len(warns))}'
            f'<div class="vcols"><div class="vfound"><h3>What was found</h3>{_found_table(result, v)}</div>'
            f'<div class="vtrust"><h3>How far to trust it</h3><ul>{trust}</ul>'
            f'<h3>What to do next</h3><ul>{nxt}</ul></div></div></section>')


def verdict_facts(result) -> dict[str, Any]:
    """The classification behind the panel, for tests: name → effective status."""
    return {n: effective_status(e) for n, e in result.estimates.items()}
