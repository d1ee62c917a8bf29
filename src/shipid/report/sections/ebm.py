"""Default report section for ``ebm`` (Yoon & Rhee 2003, seed 002).

Draws, when the result carries them: smoothed motion, forces and current
(``signals``, paper Figs 4 and 9), the regressor correlation heat maps
(``matrices["regressor_correlation..."]``, Tables 1-2), the conditioning table
κ / R / Cp (``tables["conditioning"]``, Table 4), the D-optimal input map
(``contours["d_optimal"]``, Fig. 7) and validation overlays (``overlays`` with
``kind = "validation"``, Figs 6 and 10).
"""

from __future__ import annotations

from shipid.report.registry import Entry, Group, register_section
from shipid.report.sections._util import entries


def ebm_section(result) -> list:
    """Seed 002 (Yoon & Rhee 2003): EBM stages, collinearity and validation"""
    frags: list = []
    groups: dict[str, list[str]] = {}
    for n, e in entries(result, "signals", where=lambda n, e: True):
        groups.setdefault(str(e.get("paper") or "Figs 4, 9"), []).append(n)
    for ref, sig in groups.items():
        for i in range(0, len(sig), 6):
            names = tuple(sig[i:i + 6])
            frags.append(Group("signals", names, f"{ref} — smoothed motion, estimated forces and current "
                                                 "(shaded: ±2σ where given)."))
    for name, _ in entries(result, "matrices", prefixes=("regressor_correlation",)):
        frags.append(Entry("matrices", name, paper="Tables 1–2",
                           title="Correlation of the regressors (|ρ| near 1: collinear, coefficients hard to "
                                 "separate)."))
    for name, _ in entries(result, "tables", names=("conditioning",), prefixes=("conditioning_",)):
        frags.append(Entry("tables", name, paper="Table 4",
                           title="Collinearity diagnostics: condition number κ, R and Cp."))
    for name, _ in entries(result, "contours", names=("d_optimal",), prefixes=("d_optimal_",)):
        frags.append(Entry("contours", name, paper="Fig. 7", title="D-optimality criterion of the input."))
    val = entries(result, "overlays", where=lambda n, e: e.get("kind") == "validation")
    for name, _ in val:
        frags.append(Entry("overlays", name, paper="Figs 6, 10", title="Validation:"))
    if val:
        frags.append("residual-checks")
    return frags


register_section("ebm", ebm_section, default=True)
