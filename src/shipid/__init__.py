"""shipid: identify ship dynamics from motion data.

Three methods, each reproduced from its paper and extended:

* mass and centre of mass from an IMU and the rudder (Linder et al. 2015);
* DP low-frequency model identification with a parallel state-augmented EKF
  (Fossen, Sagatun & Sørensen 1996);
* Estimation-Before-Modelling of manoeuvring coefficients (Yoon & Rhee 2003).
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("shipid")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0.0.0+unknown"

__all__ = ["__version__"]
