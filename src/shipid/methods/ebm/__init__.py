"""Estimation-Before-Modelling of Abkowitz coefficients (Yoon & Rhee 2003).

``identify`` runs the EKF and modified Bryson–Frazier smoother, then the ridge regressions of the
hydrodynamic forces; ``Options`` is :class:`~shipid.methods.ebm.estimator.EbmConfig`.
"""

from shipid.methods.ebm.entry import identify
from shipid.methods.ebm.estimator import COVERAGE, REQUIRED, EbmConfig
from shipid.registry import MethodInfo

Options = EbmConfig

METHOD = MethodInfo(
    name="ebm", title="Estimation-Before-Modelling of Abkowitz coefficients", paper="Yoon & Rhee 2003",
    trials="sequence of trials", package=__name__, result_methods=("ebm",))

__all__ = ["identify", "Options", "EbmConfig", "COVERAGE", "REQUIRED", "METHOD"]
