"""Mass and centre of mass of a load from an IMU and the rudder (Linder et al. 2015).

``identify`` runs Algorithm 1 (iterative instrumental variables over the nominal, calibration and
loaded datasets); ``Options`` is :class:`~shipid.methods.masscm.estimator.MassCMOptions`.
"""

from shipid.registry import MethodInfo, lazy_attributes

METHOD = MethodInfo(
    name="mass-cm", title="mass and centre of mass from IMU + rudder", paper="Linder et al. 2015",
    trials="mapping nominal/calibration/loaded -> trial(s)", package=__name__,
    result_methods=("mass-cm",), aliases=("masscm", "mass-and-cm"))

#: Public names, imported from their modules on first use (PEP 562): importing the package (which the
#: registry does to read ``METHOD``) loads no numerics.
_LAZY = {
    "identify": ("shipid.methods.masscm.entry", "identify"),
    "COVERAGE": ("shipid.methods.masscm.estimator", "COVERAGE"),
    "REQUIRED": ("shipid.methods.masscm.estimator", "REQUIRED"),
    "MassCMOptions": ("shipid.methods.masscm.estimator", "MassCMOptions"),
    "Options": ("shipid.methods.masscm.estimator", "MassCMOptions"),
}


__getattr__ = lazy_attributes(globals(), _LAZY)


__all__ = ["identify", "Options", "MassCMOptions", "COVERAGE", "REQUIRED", "METHOD"]
