"""Simulation: integrators, manoeuvres, noise and disturbance generators.

The package is also callable: ``shipid.simulate(vessel, manoeuvre, ...)`` is
:func:`shipid.api.simulate` (a packaged vessel through a standard manoeuvre), so the public
name and the subpackage can share one name.
"""

import sys
import types


class _CallableModule(types.ModuleType):
    def __call__(self, vessel, manoeuvre, **kwargs):
        """``shipid.simulate(vessel, manoeuvre, ...)``: see :func:`shipid.api.simulate`."""
        from shipid.api import simulate   # shipid.api imports this package: resolved at call time

        return simulate(vessel, manoeuvre, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
