"""Online monitoring of a ship's load mass and centre of mass (Linder et al. 2015 run recursively).

The monitor is run on a stream (``shipid monitor mass-cm``), not through ``shipid.identify``;
``Options`` is :class:`~shipid.methods.monitor.estimator.MonitorOptions`.
"""

from shipid.registry import MethodInfo, lazy_attributes

METHOD = MethodInfo(
    name="monitor", title="online mass and centre-of-mass monitor with change detection",
    paper="Linder et al. 2015, recursive", trials="a stream of IMU + rudder samples", package=__name__,
    result_methods=("mass-cm-monitor",))

#: Public names, imported from their modules on first use (PEP 562): importing the package (which the
#: registry does to read ``METHOD``) loads no numerics.
_LAZY = {
    "MonitorOptions": ("shipid.methods.monitor.estimator", "MonitorOptions"),
    "Options": ("shipid.methods.monitor.estimator", "MonitorOptions"),
}


__getattr__ = lazy_attributes(globals(), _LAZY)


__all__ = ["Options", "MonitorOptions", "METHOD"]
