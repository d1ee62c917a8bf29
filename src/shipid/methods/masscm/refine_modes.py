"""The values of ``MassCMOptions.refine`` (Linder et al. 2015; the refinement of
:mod:`shipid.methods.masscm.refine`), in a module without dependencies so that the CLI's option list can name them
without importing the refinement engines.
"""

from __future__ import annotations

#: The values of ``MassCMOptions.refine``: ``"auto"`` the rule of :mod:`shipid.methods.masscm.refine`, ``"none"``
#: Algorithm 1 alone, or an engine of :data:`shipid.methods.masscm.refine.ENGINES` run unconditionally.
REFINE_MODES = ("auto", "none", "pem", "whittle")

__all__ = ["REFINE_MODES"]
