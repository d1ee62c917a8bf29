"""Estimation-Before-Modelling of Abkowitz coefficients (Yoon & Rhee 2003).

``identify`` runs the EKF and modified Bryson–Frazier smoother, then the ridge regressions of the
hydrodynamic forces; ``Options`` is :class:`~shipid.methods.ebm.estimator.EbmConfig`.
"""

from shipid.registry import MethodInfo, lazy_attributes

METHOD = MethodInfo(
    name="ebm", title="Estimation-Before-Modelling of Abkowitz coefficients", paper="Yoon & Rhee 2003",
    trials="sequence of trials", package=__name__, result_methods=("ebm",))

#: Public names, imported from their modules on first use (PEP 562): importing the package (which the
#: registry does to read ``METHOD``) loads no numerics.
_LAZY = {
    "identify": ("shipid.methods.ebm.entry", "identify"),
    "COVERAGE": ("shipid.methods.ebm.estimator", "COVERAGE"),
    "REQUIRED": ("shipid.methods.ebm.estimator", "REQUIRED"),
    "EbmConfig": ("shipid.methods.ebm.estimator", "EbmConfig"),
    "Options": ("shipid.methods.ebm.estimator", "EbmConfig"),
}


__getattr__ = lazy_attributes(globals(), _LAZY)


__all__ = ["identify", "Options", "EbmConfig", "COVERAGE", "REQUIRED", "METHOD"]
