"""The verdict panel at the top of a report: what the result says about itself, in plain words.

Everything comes from the result: ``diagnostics["converged"]``, the estimates and their
standard errors, ``diagnostics["warnings"]``, a recorded coverage study
(``diagnostics["coverage"]`` or ``provenance["coverage"]``, else the ``COVERAGE`` table a method
module publishes, :func:`known_coverage`) and held-out validation
(``series["overlays"]`` entries of ``kind = "validation"``, or ``diagnostics["validation"]``).

A coefficient is *not determined* when its status says so, when its SE is infinite or when
its relative SE exceeds :data:`REL_SE_UNDETERMINED` (the 95 % interval then spans zero by a
wide margin: the data do not fix even its sign).
"""

from __future__ import annotations

import html
import math
import re
from typing import Any, Mapping

import numpy as np

from shipid import registry as method_registry
from shipid.report.formatting import fmt_num

esc = html.escape

#: Relative SE above which an "estimated" coefficient is shown as not determined.
REL_SE_UNDETERMINED = 1.0
#: Bands of relative SE for the plain-words summary.
WELL, LOOSE = 0.10, 0.50

NOT_DETERMINED = "not determined"


def rel_se(e) -> float:
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
    """The status shown: the estimate's own, or ``not determined`` for rel. SE > 100 % / infinite SE."""
    st = str(getattr(e, "status", "") or "estimated")
    if st.lower() in ("not determined", "not identifiable", "undetermined", "not-determined"):
        return NOT_DETERMINED
    if st == "estimated":
        r = rel_se(e)
        if math.isinf(r) or (math.isfinite(r) and r > REL_SE_UNDETERMINED):
            return NOT_DETERMINED
    return st


def _warnings(result) -> list[str]:
    w = (result.diagnostics or {}).get("warnings") or []
    if isinstance(w, str):
        w = [w]
    return [str(x) for x in w] if isinstance(w, (list, tuple)) else [str(w)]


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


def _list(names: list[tuple[str, float]], limit: int = 12) -> str:
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


def verdict_html(result) -> str:
    """The ``<section class="verdict">`` panel (plain words; the sections below carry the numbers)."""
    d = result.diagnostics or {}
    lines: list[tuple[str, str]] = []  # (css class, html)
    conv = d.get("converged")
    if conv is True:
        lines.append(("ok", "<b>Converged.</b> The estimator reports convergence."))
    elif conv is False:
        lines.append(("bad", "<b>Did not converge.</b> The estimates are the last iterate and must not be "
                             "trusted."))
    else:
        lines.append(("warn", "<b>Convergence not recorded</b> by this method."))
    well, loose, poor, undet, fixed = [], [], [], [], []
    for n, e in result.estimates.items():
        st, r = effective_status(e), rel_se(e)
        if st == NOT_DETERMINED:
            undet.append((n, r))
        elif st != "estimated":
            fixed.append((n, r))
        elif not math.isfinite(r):
            loose.append((n, r))
        elif r <= WELL:
            well.append((n, r))
        elif r <= LOOSE:
            loose.append((n, r))
        else:
            poor.append((n, r))
    weak = [(n, rel_se(e)) for n, e in result.estimates.items()
            if effective_status(e) == "estimated" and re.search(r"weakly determined|biased|bias",
                                                                 str(getattr(e, "note", "")), re.I)]
    if well:
        lines.append(("ok", f"<b>Well determined</b> (relative SE ≤ {100 * WELL:.0f} %): {_list(well)}."))
    if loose:
        lines.append(("", f"<b>Loosely determined</b> (relative SE {100 * WELL:.0f}–{100 * LOOSE:.0f} %): "
                          f"{_list(loose)}."))
    if poor:
        lines.append(("warn", f"<b>Poorly determined</b> (relative SE {100 * LOOSE:.0f}–100 %): {_list(poor)}."))
    if weak:
        lines.append(("warn", f"<b>Flagged by the method</b> as weakly determined or biased beyond their SE "
                              f"(see the notes of the estimates): {_list(weak)}."))
    if undet:
        lines.append(("bad", f"<b>Not determined by these data</b> (relative SE above 100 % or flagged by the "
                             f"method; shown as <i>not determined</i> below, not as estimates): {_list(undet)}."))
    if fixed:
        lines.append(("", f"Not estimated (fixed, known or derived): {len(fixed)} "
                          f"quantit{'y' if len(fixed) == 1 else 'ies'}."))
    if not result.estimates:
        lines.append(("warn", "The result carries no estimates."))
    lines.append(_coverage_text(result))
    warns = _warnings(result)
    if warns:
        lines.append(("bad", f"<b>{len(warns)} warning{'s' if len(warns) != 1 else ''}</b> from the method "
                             "(listed below the verdict)."))
    else:
        lines.append(("ok", "No warnings from the method."))
    val = _validation_text(result)
    if val:
        lines.append(("", "<b>Held-out prediction</b> (data not used for estimation): "
                          + "; ".join(esc(v) for v in val) + "."))
    elif _real_data(result):
        lines.append(("warn", "<b>No held-out prediction error</b> is recorded with this result: check the model "
                              "on a run it was not fitted to (<code>shipid validate MODEL.json --trial RUN</code>)."))
    setting = (result.provenance or {}).get("demo_setting")
    if setting:
        lines.append(("", f"<b>Demo setting:</b> {esc(str(setting))}"))
    items = "".join(f'<li class="{c}">{t}</li>' for c, t in lines)
    return f'<section class="verdict" id="verdict"><h2>Verdict</h2><ul>{items}</ul></section>'


def verdict_facts(result) -> dict[str, Any]:
    """The classification behind the panel, for tests: name → effective status."""
    return {n: effective_status(e) for n, e in result.estimates.items()}
