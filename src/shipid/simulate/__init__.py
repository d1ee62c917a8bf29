"""Simulation: integrators, manoeuvres, noise and disturbance generators.

The package is also callable: ``shipid.simulate(vessel, manoeuvre, ...)`` is
:func:`shipid.simulate.run.simulate_vessel` (a packaged vessel through a standard manoeuvre), so the
public name and the subpackage can share one name.
"""

import sys
import types

from shipid.simulate.run import simulate_vessel


class _CallableModule(types.ModuleType):
    def __call__(self, vessel, manoeuvre, **kwargs):
        """``shipid.simulate(vessel, manoeuvre, ...)``: see :func:`shipid.simulate.run.simulate_vessel`."""
        return simulate_vessel(vessel, manoeuvre, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
