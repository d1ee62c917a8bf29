"""Mass and centre of mass of a load from an IMU and the rudder (Linder et al. 2015).

``identify`` runs Algorithm 1 (iterative instrumental variables over the nominal, calibration and
loaded datasets); ``Options`` is :class:`~shipid.methods.masscm.estimator.MassCMOptions`.
"""

from shipid.methods.masscm.entry import identify
from shipid.methods.masscm.estimator import COVERAGE, REQUIRED, MassCMOptions
from shipid.registry import MethodInfo

Options = MassCMOptions

METHOD = MethodInfo(
    name="mass-cm", title="mass and centre of mass from IMU + rudder", paper="Linder et al. 2015",
    trials="mapping nominal/calibration/loaded -> trial(s)", package=__name__,
    result_methods=("mass-cm",), aliases=("masscm", "mass-and-cm"))

__all__ = ["identify", "Options", "MassCMOptions", "COVERAGE", "REQUIRED", "METHOD"]
