"""DP ship identification (Fossen, Sagatun & Sørensen 1996, seed 001).

``identify`` runs the state-augmented EKF in parallel over the decoupled surge, sway-yaw and azimuth
trials; ``Options`` is :class:`~shipid.methods.dp.estimator.DPOptions`.
"""

from shipid.methods.dp.entry import REQUIRED, identify
from shipid.methods.dp.estimator import COVERAGE, DPOptions
from shipid.registry import MethodInfo

Options = DPOptions

METHOD = MethodInfo(
    name="dp", title="DP low-frequency model, parallel state-augmented EKF",
    paper="Fossen, Sagatun & Sorensen 1996", trials="mapping surge/sway-yaw/azimuth -> trials",
    package=__name__, result_methods=("dp",))

__all__ = ["identify", "Options", "DPOptions", "COVERAGE", "REQUIRED", "METHOD"]
