"""HTML reports for any :class:`shipid.result.Result` .

``shipid report RESULT.json --out report.html [--force]`` writes ONE self-contained
HTML file (inline CSS, figures as base64 PNG data URIs drawn with matplotlib Agg, no
JavaScript, nothing fetched from the network). Python API::

    from shipid.report import build_report, write_report
    html = build_report(result)            # str
    write_report(result, "report.html", force=False)

The rest of this docstring is the convention every method follows so the report
can draw its results.

`shipid report RESULT.json --out report.html [--force]` renders ANY `shipid.result.Result`. Everything below is
optional: put in what you have; the report shows what is there and skips the rest.
Helpers that build these dicts (plain lists, NaN allowed, no matplotlib import):
`from shipid.report.convention import overlay, residual, history, signal, matrix, table, contour, xy, trial_summary`.

## Where the report looks
- `result.method`: "mass-cm" | "dp" | "ebm" (anything else gets the generic report).
- `result.model["vessel"]` (str) — shown in the header. Other scalar `model` entries are listed as "Model".
- `result.provenance`: `inputs` (see below), `seed`, `shipid_version`, `created`, `command` (str), anything else
  scalar is listed too.
- `provenance["inputs"]`: list; each item is a file path string OR a dict (use `trial_summary(trial, name=...)`):
  `{"name": "zigzag.csv", "channels": {"r": "rad/s", "delta": "rad"} (or a list of names), "n_samples": 6001,
    "duration_s": 600.0, "dt_s": 0.1, "t0_s": 0.0, "note": "..."}`
- `result.estimates`: value, std, unit, status, note. The table shows value ± SE, 95 % CI (value ± 1.96 SE),
  relative SE, unit, status, note; digits follow the SE (2 significant digits of the SE). std = inf shows
  "not identifiable", NaN shows "—".
- `result.covariance` + `covariance_names`: a correlation heat map is drawn automatically (|ρ| > 0.95 flagged).
- `result.diagnostics`: `converged` (bool), `iterations` (int), `warnings` (list of str, shown in a red box at the
  top), anything else scalar / small dict shown in a key-value table.

## `result.series` — plot data (all arrays are JSON lists, SI units, time in s)
Each kind maps NAME -> entry. Every entry may carry `"title"` (caption text) and `"paper"` (e.g. `"Fig. 8"`,
`"Table 4"`): entries with `"paper"` are gathered in the "Figures and tables from the paper" section, in paper order.
| key | entry | drawn as |
|---|---|---|
| `overlays` | `{"t", "measured", "model", "unit", "label"?, "kind"?: "fit"/"validation"}` | measured vs model + residual + residual ACF with ±1.96/√N bounds |
| `residuals` | `{"t", "values", "unit", "std"?: [...] (innovation σ, draws ±2σ band), "label"?}` | residual vs t + ACF ±1.96/√N + stats row (mean, RMS, % lags outside bounds, Ljung–Box p, % inside ±2σ) |
| `histories` | `{"t", "value", "std"?: [...], "unit", "true"?: scalar, "label"?}` | parameter vs time with ±σ band (Fig. 8 style), dashed line at `true` |
| `signals` | `{"t", "lines": {label: [...]}, "unit", "std"?: {label: [...]}, "label"?}` | time histories without a measured/model pair (smoothed states, forces, current: EBM Figs 4/9) |
| `matrices` | `{"values": [[...]], "rows": [...], "cols"?: [...], "unit"?, "vmin"?, "vmax"?, "annotate"?: bool}` | heat map (e.g. regressor correlation, Tables 1–2) |
| `tables` | `{"columns": [...], "rows": [[...], ...], "units"?: [...], "caption"?}` | HTML table (true vs estimated, κ/R/Cp Table 4, Table 3 spread) |
| `contours` | `{"x", "y", "z": [[...]] (len(y) rows × len(x) cols), "x_label", "x_unit", "y_label", "y_unit", "z_label"?, "log"?: bool, "points"?: [{"x", "y", "label"}]}` | filled contour (mass-cm Fig. 4 cost over (m, z̄_m); EBM Fig. 7 D-optimal map) |
| `xy` | `{"x", "lines": {label: [...]}, "x_label", "x_unit", "y_label", "y_unit", "style"?: "line"/"scatter"}` | any other x–y plot (Monte Carlo spread, …) |

If an overlay has no residual of the same name, the residual is computed as measured − model.
Long series are decimated for drawing only (≤ 4000 points); statistics use every sample.

## Well-known names used by the default method sections (when `"paper"` is absent)
- mass-cm: `contours["cost"]` → Fig. 4; `tables["spread"]` → Table 3; `xy["spread"]` → Table-3 scatter.
- dp: all `histories` → Fig. 8; `residuals` whose name starts with `innovation` → innovation checks.
- ebm: `signals` → Figs 4/9; `matrices["regressor_correlation"]` (or names starting with it) → Tables 1–2;
  `tables["conditioning"]` → Table 4 (κ, R, Cp); `contours["d_optimal"]` → Fig. 7;
  `overlays` with `"kind": "validation"` → Figs 6/10.

## Adding your own figures
```python
from shipid.report import register_section, Claim
from shipid.report.registry import Entry, Group
from shipid.report import figures as F
def my_section(result):            # -> list of fragments
    with F.style():                 # report look (fonts, grid); F.new_figure() gives an Agg-backed Figure
        fig = F.new_figure(height=3.0); ax = fig.add_subplot(); ax.plot(...); ax.set_xlabel("t [s]")
    return ["<p>raw trusted HTML</p>", (fig, "caption"), Claim("contours", "cost"),
            Entry("contours", "cost", paper="Fig. 4", title="..."),       # draw a convention entry here
            Group("histories", ("m11", "d11"), "Fig. 8 — ..."),           # several in one figure
            "residual-checks"]                                              # stats table of residuals so far
register_section("mass-cm", my_section)   # at import of your module; runs after the default section
```
`Claim(kind, name)` tells the generic part that you have drawn that series entry (it is not drawn twice).
The report imports `shipid.methods.<m>` and `shipid.methods.<m>.report` (m = method without "-", or with "_")
before building, so a `register_section` call in those modules is always picked up (import errors are shown as
a report warning, never a crash).

## What the three methods store (series modules)
`shipid.methods.masscm.series` (roll-rate overlays, equation errors, Fig. 4 map; Table 3 via
`shipid study mass-cm-sensitivity --out`), `shipid.methods.dp.series` (innovations with σ),
`shipid.methods.ebm.series` (signals, Tables 1–2 and 4, force fits; opt-in validation and Fig. 7 map,
`shipid identify ebm --figures`). Each is hooked where the method builds its Result and never raises.

## Try it
`PYTHONPATH=tests python -c "from report.examples import example; example('ebm').write_json('/tmp/e.json')"`
then `shipid report /tmp/e.json --out /tmp/e.html`. `tests/report/examples.py` holds a fully populated
synthetic Result per method: copy its shape.
"""

from __future__ import annotations

from shipid.report.registry import Claim, Entry, Group, register_section, sections_for

__all__ = ["build_report", "write_report", "register_section", "sections_for", "Claim", "Entry", "Group"]


def __getattr__(name: str):
    # Lazy: ``shipid.report.convention`` must stay importable without matplotlib.
    if name in ("build_report", "write_report"):
        from shipid.report import html as _html
        return getattr(_html, name)
    raise AttributeError(f"module 'shipid.report' has no attribute {name!r}")
