"""The last ``shipid demo`` step: an HTML report for every result the demo produced.

Results are collected from the demo context, in this order:

1. ``ctx.results`` (a dict name -> :class:`~shipid.result.Result`) when a step set it;
2. every ``*.json`` file in ``ctx.files`` that reads as a shipid result (method steps
   write their result JSON into ``ctx.out_dir`` and append the path to ``ctx.files``);
3. for a method of the three papers that produced no result in this run, a small
   built-in run on simulated data through the method's Python API (seeded with
   ``ctx.seed``); if that API is missing or fails, the method is listed as skipped with
   the reason, never silently;
4. when the shared real data are present (``$SHIPID_DATA`` or ``../shared/data``) and no
   ``mmg-ebm`` result was produced, the real-data EBM pipeline on KVLCC2 zig-zags with a
   held-out validation run.

Each report is written as ``report-<name>.html`` next to the other demo files.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Callable

from shipid import registry
from shipid.demo import DemoContext, demo_step, result_findings, result_row
from shipid.report.html import write_report
from shipid.result import Result

#: Method name -> ``fallback(seed) -> Result`` on simulated data: each registered method's
#: ``demo.fallback`` (filled on first use; an entry set beforehand is kept).
FALLBACKS: dict[str, Callable] = {}

#: Method name -> ``real_data(seed) -> Result | None`` (None: the shared real data are not there):
#: each registered method's ``demo.real_data`` (filled on first use; an entry set beforehand is kept).
REAL_DATA: dict[str, Callable] = {}


def _demo_hooks(table: dict[str, Callable], name: str) -> dict[str, Callable]:
    for method, info in registry.methods().items():
        if info.has_module("demo"):
            fn = getattr(info.submodule("demo"), name, None)
            if callable(fn):
                table.setdefault(method, fn)
    return table


def fallbacks() -> dict[str, Callable]:
    """:data:`FALLBACKS`, completed from the ``demo`` modules of the methods in :mod:`shipid.registry`."""
    return _demo_hooks(FALLBACKS, "fallback")


def real_data_runs() -> dict[str, Callable]:
    """:data:`REAL_DATA`, completed from the ``demo`` modules of the methods in :mod:`shipid.registry`."""
    return _demo_hooks(REAL_DATA, "real_data")

def collect_results(ctx: DemoContext) -> dict[str, object]:
    """Results produced by earlier steps: ``ctx.results`` and result JSON files in ``ctx.files``."""
    found: dict[str, object] = {}
    for name, res in (getattr(ctx, "results", None) or {}).items():
        if isinstance(res, Result):
            found[str(name)] = res
    for path in list(ctx.files):
        p = Path(path)
        if p.suffix.lower() != ".json" or not p.is_file():
            continue
        try:
            data = json.loads(p.read_text(encoding="utf-8"))
            if isinstance(data, dict) and "method" in data and isinstance(data.get("estimates"), dict):
                found.setdefault(p.stem, Result.from_dict(data))
        except (OSError, ValueError, TypeError, KeyError):
            continue
    return found


@demo_step("report", order=900, description="an HTML report for each method's result")
def report_step(ctx: DemoContext) -> list[dict]:
    """Write ``report-<name>.html`` for every result of this demo run (and the three methods)."""
    results = collect_results(ctx)
    rows: list[dict] = []
    have = {getattr(r, "method", None) for r in results.values()}
    for method, fallback in fallbacks().items():
        if method in have:
            continue
        try:
            res = fallback(ctx.seed)
        except Exception as err:  # noqa: BLE001 - a method in progress must not stop the demo
            why = f"{type(err).__name__}: {' '.join(str(err).split())[:120]}"
            rows.append({"result": method, "method": method, "report": f"skipped: {why}"})
            ctx.skip(f"report of {method} (simulated data)", why)
            continue
        json_path = ctx.out_dir / f"result-{method}.json"
        res.write_json(json_path, force=ctx.force)
        ctx.files.append(json_path)
        results[f"result-{method}"] = res
    for method, run in real_data_runs().items():
        info = registry.get(method)
        if have & set(info.result_methods):
            continue
        what = getattr(run, "what", f"real-data {method} identification") + " and its report"
        try:
            res = run(ctx.seed)
        except Exception as err:  # noqa: BLE001
            res = None
            why = f"{type(err).__name__}: {' '.join(str(err).split())[:120]}"
            rows.append({"result": f"realdata-{method}", "method": method, "report": f"skipped: {why}"})
            ctx.skip(what, why)
        else:
            if res is None:  # no real data: named in the demo's list of skipped parts
                ctx.skip(what, "real data not found (set SHIPID_DATA or place the shared data at ../shared/data)")
        if res is not None:
            json_path = ctx.out_dir / f"result-realdata-{res.method}.json"
            res.write_json(json_path, force=ctx.force)
            ctx.files.append(json_path)
            results[f"result-realdata-{res.method}"] = res
    for name, res in results.items():
        stem = name[len("result-"):] if name.startswith("result-") else name
        path = ctx.out_dir / f"report-{stem}.html"
        write_report(res, path, force=ctx.force)
        ctx.files.append(path)
        rows.append({"result": name, "method": res.method, **result_row(res), "report": path.name})
        ctx.findings.extend(result_findings(name, res))
    return rows
