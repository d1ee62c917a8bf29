"""MMG manoeuvring models from free-running model tests (Yoon & Rhee 2003's EBM on the MMG structure).

``identify`` smooths the measured runs, recovers the forces and fits the MMG coefficients by ridge
regression per mode, choosing the structure by cross-validation; ``Options`` is
:class:`~shipid.methods.mmg.estimator.FitConfig`.
"""

from shipid.methods.mmg.entry import identify
from shipid.methods.mmg.estimator import FitConfig
from shipid.registry import MethodInfo

Options = FitConfig

METHOD = MethodInfo(
    name="mmg", title="MMG model from free-running model tests (EBM adapted)",
    paper="Yoon & Rhee 2003 applied to the MMG structure", trials="sequence of trials", package=__name__,
    result_methods=("mmg-ebm", "realdata"), aliases=("mmg-ebm",))

__all__ = ["identify", "Options", "FitConfig", "METHOD"]
