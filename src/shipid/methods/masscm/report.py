"""Default report section for ``mass-cm`` (Linder et al. 2015, seed 000).

Draws, when the result carries them: the cost over (m, z̄_m) (``contours["cost"]``,
paper Fig. 4) and the spread of the estimates over repeated runs
(``tables["spread"]`` and ``xy["spread"]``, paper Table 3).
"""

from __future__ import annotations

from shipid.report.registry import Entry, register_section
from shipid.report.sections._util import entries


def masscm_section(result) -> list:
    """Linder et al. (2015): cost map and spread of the estimates"""
    frags: list = []
    for name, _ in entries(result, "contours", names=("cost",), prefixes=("cost_",)):
        frags.append(Entry("contours", name, paper="Fig. 4",
                           title="Identification cost over mass m and vertical centre of mass z̄_m; "
                                 "markers show the estimate and, for simulated data, the true value."))
    for name, _ in entries(result, "tables", names=("spread",), prefixes=("spread_",)):
        frags.append(Entry("tables", name, paper="Table 3",
                           title="Spread of the estimates over repeated runs."))
    for name, _ in entries(result, "xy", names=("spread",), prefixes=("spread_",)):
        frags.append(Entry("xy", name, paper="Table 3",
                           title="Estimates of the repeated runs (spread)."))
    return frags


register_section("mass-cm", masscm_section, default=True)
