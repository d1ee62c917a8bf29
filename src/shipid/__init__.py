"""shipid: identify ship dynamics from motion data.

Four identification methods, registered in :mod:`shipid.registry`, and an online monitor:

* ``mass-cm``: load mass and centre of mass from an IMU and the rudder (Linder et al. 2015);
* ``dp``: DP low-frequency model identification with a parallel state-augmented EKF
  (Fossen, Sagatun & Sørensen 1996);
* ``ebm``: Estimation-Before-Modelling of Abkowitz manoeuvring coefficients (Yoon & Rhee 2003);
* ``mmg``: an MMG manoeuvring model from free-running model tests (EBM on the MMG structure);
* ``shipid monitor mass-cm`` (:mod:`shipid.methods.monitor`): mass and centre of mass online, with change
  detection.

From Python: ``shipid.identify(method, trials, vessel=..., options=...)``, ``shipid.validate``,
``shipid.simulate``, ``shipid.read_trial``, ``shipid.load_vessel`` (:mod:`shipid.api`).
"""

#: The public names, loaded on first use (PEP 562) so that ``import shipid`` stays cheap
#: (``__version__`` too: importlib.metadata alone takes about 0.1 s to import).
_LAZY = {
    "identify": "shipid.api", "validate": "shipid.api", "METHODS": "shipid.api",
    "read_trial": "shipid.io.files", "write_trial": "shipid.io.files", "Trial": "shipid.io.trial",
    "Result": "shipid.result", "Estimate": "shipid.result", "load_vessel": "shipid.vessels",
}

__all__ = ["__version__", "simulate", *_LAZY]


def _version() -> str:
    """The installed distribution's version (``0.0.0+unknown`` in a source tree without installation)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("shipid")
    except PackageNotFoundError:
        return "0.0.0+unknown"


def __getattr__(name: str):
    if name == "__version__":
        globals()["__version__"] = v = _version()
        return v
    if name == "simulate":       # the subpackage, callable as shipid.api.simulate
        import importlib

        return importlib.import_module("shipid.simulate")
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'shipid' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY) | {"__version__", "simulate"})
