"""Online monitoring of a ship's load mass and centre of mass (Linder et al. 2015 run recursively).

The monitor is run on a stream (``shipid monitor mass-cm``), not through ``shipid.identify``;
``Options`` is :class:`~shipid.methods.monitor.estimator.MonitorOptions`.
"""

from shipid.methods.monitor.estimator import MonitorOptions
from shipid.registry import MethodInfo

Options = MonitorOptions

METHOD = MethodInfo(
    name="monitor", title="online mass and centre-of-mass monitor with change detection",
    paper="Linder et al. 2015, recursive", trials="a stream of IMU + rudder samples", package=__name__,
    result_methods=("mass-cm-monitor",))

__all__ = ["Options", "MonitorOptions", "METHOD"]
