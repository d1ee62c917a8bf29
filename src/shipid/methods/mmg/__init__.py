"""MMG manoeuvring models from free-running model tests (Yoon & Rhee 2003's EBM on the MMG structure).

``identify`` smooths the measured runs, recovers the forces and fits the MMG coefficients by ridge
regression per mode, choosing the structure by cross-validation; ``Options`` is
:class:`~shipid.methods.mmg.estimator.FitConfig`.
"""

from shipid.registry import MethodInfo, lazy_attributes

METHOD = MethodInfo(
    name="mmg", title="MMG model from free-running model tests (EBM adapted)",
    paper="Yoon & Rhee 2003 applied to the MMG structure", trials="sequence of trials", package=__name__,
    result_methods=("mmg-ebm", "realdata"), aliases=("mmg-ebm",))

#: Public names, imported from their modules on first use (PEP 562): importing the package (which the
#: registry does to read ``METHOD``) loads no numerics.
_LAZY = {
    "identify": ("shipid.methods.mmg.entry", "identify"),
    "FitConfig": ("shipid.methods.mmg.estimator", "FitConfig"),
    "Options": ("shipid.methods.mmg.estimator", "FitConfig"),
}


__getattr__ = lazy_attributes(globals(), _LAZY)


__all__ = ["identify", "Options", "FitConfig", "METHOD"]
