"""DP ship identification (Fossen, Sagatun & Sørensen 1996).

``identify`` runs the state-augmented EKF in parallel over the decoupled surge, sway-yaw and azimuth
trials; ``Options`` is :class:`~shipid.methods.dp.estimator.DPOptions`.
"""

from shipid.registry import MethodInfo, lazy_attributes

METHOD = MethodInfo(
    name="dp", title="DP low-frequency model, parallel state-augmented EKF",
    paper="Fossen, Sagatun & Sorensen 1996", trials="mapping surge/sway-yaw/azimuth -> trials",
    package=__name__, result_methods=("dp",))

#: Public names, imported from their modules on first use (PEP 562): importing the package (which the
#: registry does to read ``METHOD``) loads no numerics.
_LAZY = {
    "identify": ("shipid.methods.dp.entry", "identify"),
    "REQUIRED": ("shipid.methods.dp.entry", "REQUIRED"),
    "COVERAGE": ("shipid.methods.dp.estimator", "COVERAGE"),
    "DPOptions": ("shipid.methods.dp.estimator", "DPOptions"),
    "Options": ("shipid.methods.dp.estimator", "DPOptions"),
}


__getattr__ = lazy_attributes(globals(), _LAZY)


__all__ = ["identify", "Options", "DPOptions", "COVERAGE", "REQUIRED", "METHOD"]
