"""Report material of ``mass-cm`` results (Linder et al. 2015).

Default section: draws, when the result carries them, the cost over (m, z̄_m) (``contours["cost"]``,
paper Fig. 4) and the spread of the estimates over repeated runs (``tables["spread"]`` and ``xy["spread"]``,
paper Table 3).

:func:`enrich` makes the report series on request for a result that has none (one from
:func:`shipid.identify` or :func:`~shipid.methods.masscm.estimator.estimate_mass_cm`, which do no report work):
:func:`shipid.methods.masscm.series.with_series` reads the datasets again from the files the result records,
reruns Algorithm 1, checks that it reproduces the stored m and adds the roll-rate overlays, prefiltered equation
errors, the Fig. 4 cost map and the trial summaries.
"""

from __future__ import annotations

from shipid.methods.masscm.series import with_series
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


def enrich(result):
    """``result`` with its report series made from the files it records (:func:`~shipid.methods.masscm.series.with_series`,
    Fig. 4 map included); ``result`` itself when it has them already or records no files."""
    return with_series(result, cost_map=True)


__all__ = ["masscm_section", "enrich"]
