"""Default report section for ``dp`` (Fossen, Sagatun & Sørensen 1996).

Draws, when the result carries them: every parameter history with its ±σ band
(``histories``, paper Fig. 8, as small multiples), then the innovation checks:
each ``residuals`` entry whose name starts with ``innovation`` with its predicted
±2σ band and autocorrelation, followed by the table of residual statistics.

:func:`enrich` makes those series on request for a result that has none (one from :func:`shipid.identify`
or :func:`~shipid.methods.dp.estimator.identify_dp`, which do no report work):
:func:`shipid.methods.dp.series.with_series` reads the trials again from the files the result records,
reruns SI1 → SI3, checks that it reproduces the stored estimates and adds the series.
"""

from __future__ import annotations

from shipid.methods.dp.series import with_series
from shipid.report.registry import Entry, Group, register_section
from shipid.report.render import paper_ref
from shipid.report.sections._util import entries


def dp_section(result) -> list:
    """Fossen, Sagatun & Sørensen (1996): parameter histories and innovation checks"""
    frags: list = []
    # every history, grouped by its own paper reference (default Fig. 8), 12 panels per figure
    groups: dict[str, list[str]] = {}
    for n, e in entries(result, "histories", where=lambda n, e: True):
        groups.setdefault(str(e.get("paper") or "Fig. 8"), []).append(n)
    for ref, hist in groups.items():
        for i in range(0, len(hist), 12):
            names = tuple(hist[i:i + 12])
            frags.append(Group("histories", names,
                               "Parameter estimates versus time with ±σ bands (dashed: true value where known)"
                               + (f", part {i // 12 + 1}" if len(hist) > 12 else "")
                               + f" ({paper_ref('dp', ref)})."))
    innov = entries(result, "residuals", prefixes=("innovation",))
    for name, _ in innov:
        frags.append(Entry("residuals", name, title="Innovation check:"))
    if innov:
        frags.append("residual-checks")
    return frags


register_section("dp", dp_section, default=True)


def enrich(result):
    """``result`` with its report series made from the files it records (:func:`~shipid.methods.dp.series.with_series`);
    ``result`` itself when it has them already or records no files."""
    return with_series(result)


__all__ = ["dp_section", "enrich"]
