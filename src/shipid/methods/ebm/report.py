"""Default report section for ``ebm`` (Yoon & Rhee 2003).

Draws, when the result carries them: smoothed motion, forces and current
(``signals``, paper Figs 4 and 9), the regressor correlation heat maps
(``matrices["regressor_correlation..."]``, Tables 1-2), the conditioning table
κ / R / Cp (``tables["conditioning"]``, Table 4), the D-optimal input map
(``contours["d_optimal"]``, Fig. 7) and validation overlays (``overlays`` with
``kind = "validation"``, Figs 6 and 10).

:func:`enrich` makes the report series on request for an ``ebm`` result that has none (one from
:func:`shipid.identify` or :func:`~shipid.methods.ebm.estimator.identify`, which do no report work):
:func:`shipid.methods.ebm.series.with_series` reads the trials again from the files the result records,
reruns both EBM steps, checks that they reproduce the stored estimates and adds the series.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from shipid.methods.ebm.series import with_series
from shipid.report import figures as F
from shipid.report.registry import Entry, Group, register_section
from shipid.report.render import paper_ref
from shipid.report.sections._util import entries


def ebm_section(result) -> list:
    """Yoon & Rhee (2003): EBM stages, collinearity and validation"""
    frags: list = []
    # one figure per paper reference and trial: names "<trial>_<signal>" (shipid.methods.ebm.series)
    # share the prefix; a title common to the whole group becomes its caption
    groups: dict[tuple[str, str], list[tuple[str, Mapping]]] = {}
    for n, e in entries(result, "signals", where=lambda n, e: True):
        prefix = n.split("_", 1)[0] if "_" in n else ""
        groups.setdefault((str(e.get("paper") or "Figs 4, 9"), prefix), []).append((n, e))
    for (ref, _), sig in groups.items():
        for i in range(0, len(sig), 6):
            part = sig[i:i + 6]
            titles = {e.get("title") for _, e in part}
            text = titles.pop() if len(titles) == 1 and None not in titles else \
                "smoothed motion, estimated forces and current (shaded: ±2σ where given)."
            text = text.rstrip().rstrip(".")
            frags.append(Group("signals", tuple(n for n, _ in part), f"{text} ({paper_ref(result.method, ref)})."))
    for name, _ in entries(result, "matrices", prefixes=("regressor_correlation",)):
        frags.append(Entry("matrices", name, paper="Tables 1–2",
                           title="Correlation of the regressors (|ρ| near 1: collinear, coefficients hard to "
                                 "separate)."))
    if not entries(result, "matrices", prefixes=("regressor_correlation",)):
        frags += _correlation_from_diagnostics(result)
    cond = entries(result, "tables", names=("conditioning",), prefixes=("conditioning_",))
    for name, _ in cond:
        frags.append(Entry("tables", name, paper="Table 4",
                           title="Collinearity diagnostics: condition number κ, R and Cp."))
    if not cond:
        frags += _conditioning_from_diagnostics(result)
    for name, _ in entries(result, "contours", names=("d_optimal",), prefixes=("d_optimal_",)):
        frags.append(Entry("contours", name, paper="Fig. 7", title="D-optimality criterion of the input."))
    val = entries(result, "overlays", where=lambda n, e: e.get("kind") == "validation")
    for name, _ in val:
        frags.append(Entry("overlays", name, paper="Figs 6, 10", title="Validation:"))
    if val:
        frags.append("residual-checks")
    return frags


def _correlation_from_diagnostics(result) -> list:
    """Tables 1-2 from ``diagnostics["correlation"]`` = {mode: 2-D matrix} when no series entry exists."""
    corr = (result.diagnostics or {}).get("correlation")
    if not isinstance(corr, Mapping):
        return []
    frags = []
    for mode, m in corr.items():
        try:
            a = np.asarray(m, dtype=float)
        except (TypeError, ValueError):
            continue
        if a.ndim != 2 or a.shape[0] != a.shape[1] or a.shape[0] < 2:
            continue
        labels = _regressor_names(result, mode, a.shape[0])
        entry = {"values": a.tolist(), "rows": labels, "cols": labels, "vmin": -1.0, "vmax": 1.0,
                 "unit": "correlation [-]"}
        fig = F.matrix_figure(entry)
        frags.append((fig, f"Correlation of the {mode} regressors (from diagnostics; |ρ| near 1: collinear) "
                           f"({paper_ref(result.method, 'Tables 1–2')})."))
    return frags


def _regressor_names(result, mode: str, n: int) -> list[str]:
    names = [k for k in result.estimates if k.upper().startswith({"surge": "X", "sway": "Y", "yaw": "N"}
                                                                  .get(mode, "?"))]
    return names if len(names) == n else [str(i + 1) for i in range(n)]


def _conditioning_from_diagnostics(result) -> list:
    """Table 4 from ``diagnostics["modes"]`` = {mode: {kappa, R2, Cp, k, ...}} when no table entry exists."""
    d = result.diagnostics or {}
    modes = d.get("modes") if isinstance(d.get("modes"), Mapping) else d.get("ridge")
    if not isinstance(modes, Mapping) or not modes:
        return []
    keys = [("kappa", "κ"), ("R2", "R²"), ("Cp", "Cp"), ("p", "p"), ("k", "ridge k"), ("n", "n")]
    present = [(k, lab) for k, lab in keys if any(isinstance(v, Mapping) and k in v for v in modes.values())]
    if not present:
        return []
    rows = [[str(mode)] + [v.get(k) if isinstance(v, Mapping) else None for k, _ in present]
            for mode, v in modes.items()]
    return [{"columns": ["mode"] + [lab for _, lab in present], "rows": rows, "paper": "Table 4",
             "title": "Collinearity diagnostics per mode (from diagnostics): condition number κ, R², "
                      "Mallows Cp, ridge parameter k."}]


register_section("ebm", ebm_section, default=True)
register_section("mmg-ebm", ebm_section, default=True)
register_section("ebm-study", ebm_section, default=True)  # shipid study ebm-esso-osaka; real-data EBM with the MMG model


def enrich(result):
    """``result`` with its report series made from the files it records (:func:`~shipid.methods.ebm.series.with_series`);
    ``result`` itself when it has them already or records no files."""
    return with_series(result)
