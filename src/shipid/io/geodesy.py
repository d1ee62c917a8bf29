"""Latitude/longitude to local north/east metres and back (WGS-84, local tangent plane).

Latitude/longitude become north/east ``x``, ``y`` in metres about the first fix
in the local tangent plane (flat earth) at that fix: the points, taken on the
WGS-84 ellipsoid (the GGA altitude is ignored), go to earth-centred earth-fixed
coordinates and are rotated into north-east-down at the origin (Fossen 2011,
eqs. 2.71 and 2.84); the vertical is dropped. Horizontal distances in the plane
are shorter than along the surface by about ``d^3 / (6 R^2)`` (``R ~ 6.37e6 m``):
5e-7 m at 500 m, 5e-4 m at 5 km; ignoring an antenna height ``h`` scales them by
``h / R`` (4 mm at 500 m for h = 50 m). The plain equirectangular formula
``x = R_M dphi``, ``y = R_N cos(phi0) dlambda`` would be off by ``~ d^2 tan(phi0) / (2R)``
(4 cm at 500 m and 60 deg), which is why it is not used.
"""

from __future__ import annotations

import math

import numpy as np

#: WGS-84 semi-major axis [m] and flattening.
WGS84_A = 6378137.0
WGS84_F = 1.0 / 298.257223563
E2 = WGS84_F * (2.0 - WGS84_F)


def ecef(lat_deg, lon_deg):
    """Earth-centred earth-fixed ``(x, y, z)`` in m of points on the WGS-84 ellipsoid (height 0;
    Fossen 2011, eq. 2.71)."""
    phi, lam = np.radians(lat_deg), np.radians(lon_deg)
    n = WGS84_A / np.sqrt(1.0 - E2 * np.sin(phi) ** 2)
    return n * np.cos(phi) * np.cos(lam), n * np.cos(phi) * np.sin(lam), n * (1.0 - E2) * np.sin(phi)


def flat_earth(lat_deg, lon_deg, lat0: float | None = None, lon0: float | None = None):
    """North/east metres about ``(lat0, lon0)`` (default: the first point) in the local tangent plane.

    Points on the WGS-84 ellipsoid (height 0) go to earth-centred earth-fixed
    coordinates and are rotated into the north-east-down frame at the origin
    (Fossen 2011, eqs. 2.71 and 2.84); the vertical is dropped. See the module
    docstring for the error bound.

    Returns
    -------
    x, y : ndarray
        North and east in metres.
    origin : dict
        ``{"lat": lat0, "lon": lon0}`` in degrees.
    """
    lat = np.asarray(lat_deg, dtype=np.float64)
    lon = np.asarray(lon_deg, dtype=np.float64)
    lat0 = float(lat.flat[0]) if lat0 is None else float(lat0)
    lon0 = float(lon.flat[0]) if lon0 is None else float(lon0)
    phi0, lam0 = math.radians(lat0), math.radians(lon0)
    x0, y0, z0 = ecef(np.array(lat0), np.array(lon0))
    xe, ye, ze = ecef(lat, lon)
    dx, dy, dz = xe - x0, ye - y0, ze - z0
    sp, cp, sl, cl = math.sin(phi0), math.cos(phi0), math.sin(lam0), math.cos(lam0)
    north = -sp * cl * dx - sp * sl * dy + cp * dz
    east = -sl * dx + cl * dy
    return north, east, {"lat": lat0, "lon": lon0}


def flat_earth_inverse(x, y, lat0: float, lon0: float, iterations: int = 6):
    """Latitude and longitude in degrees (on the ellipsoid) of north/east metres ``x``, ``y``.

    The inverse of :func:`flat_earth` by fixed-point iteration on the local radii
    (six iterations reach ~1e-9 m within 10 km).
    """
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    phi0 = math.radians(lat0)
    w = 1.0 - E2 * math.sin(phi0) ** 2
    r_m = WGS84_A * (1.0 - E2) / w ** 1.5
    r_n = WGS84_A / math.sqrt(w)
    lat = lat0 + np.degrees(x / r_m)
    lon = lon0 + np.degrees(y / (r_n * math.cos(phi0)))
    for _ in range(iterations):
        xa, ya, _ = flat_earth(lat, lon, lat0, lon0)
        lat = lat + np.degrees((x - xa) / r_m)
        lon = lon + np.degrees((y - ya) / (r_n * math.cos(phi0)))
    return lat, lon


__all__ = ["WGS84_A", "WGS84_F", "E2", "ecef", "flat_earth", "flat_earth_inverse"]
