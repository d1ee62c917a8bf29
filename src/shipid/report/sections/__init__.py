"""Default report sections of the three methods.

Each module registers, for its method, a section that presents the entries the
method is expected to carry under the report convention (see :mod:`shipid.report`)
with the caption of the paper figure or table they reproduce. They only draw
what is present; a method's own sections (``register_section``) come after.
"""

from __future__ import annotations

from shipid.report.sections import dp, ebm, masscm  # noqa: F401  (registration side effects)
