"""Report hook of ``mmg-ebm`` results (``shipid identify mmg``; the section is :mod:`shipid.methods.ebm.report`'s).

:func:`enrich` makes the report series on request for a result that has none:
:func:`shipid.methods.mmg.series.with_series` re-reads the training runs the result records for the data
summary and the open-loop fit overlays.
"""

from __future__ import annotations

from shipid.methods.mmg.series import with_series


def enrich(result):
    """``result`` with its report series made from the files it records (:func:`~shipid.methods.mmg.series.with_series`);
    ``result`` itself when it has them already or records no training runs."""
    return with_series(result)


__all__ = ["enrich"]
