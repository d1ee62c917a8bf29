"""The :class:`Trial`: one recorded or simulated run, in SI units.

A trial is a strictly increasing time vector plus named channels, every channel
stored in SI units (its SI unit is kept beside it), plus metadata. Channel names
follow SNAME / Fossen notation (see :data:`CHANNELS`). Readers convert on the way
in; writers convert only when asked, and name the unit in every header.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterable, Mapping

import numpy as np

from shipid.errors import InputError

#: Standard channel names and their SI units (SNAME / Fossen 1994 notation).
CHANNELS: dict[str, str] = {
    "t": "s",
    "x": "m", "y": "m", "psi": "rad",          # earth-fixed position and heading
    "u": "m/s", "v": "m/s", "r": "rad/s",      # body-fixed surge, sway, yaw rate
    "p": "rad/s", "phi": "rad",                # roll rate and roll angle
    "x_dot": "m/s", "y_dot": "m/s",            # earth-fixed velocities (DGPS, Yoon & Rhee 2003 eq. 8)
    "U": "m/s",                                # speed (log)
    "u_r": "m/s", "v_r": "m/s",                # velocities relative to the water (Yoon & Rhee 2003 eq. 2)
    "delta": "rad", "n": "1/s",                # rudder angle, propeller revolutions
    "a_s": "m/s^2",                            # IMU tangential acceleration (Linder et al. 2015 eq. 8)
    "p1": "-", "p2": "-", "p3": "-", "p4": "-", "p5": "-", "p6": "-",  # thruster pitch ratios
    "alpha6": "rad",                           # azimuth angle of thruster 6 (Fossen et al. 1996 eq. 7)
    "X": "N", "Y": "N", "N": "N*m",            # forces and yaw moment
    "thrust": "N", "torque": "N*m",
    "wind_speed": "m/s", "wind_dir": "rad",
    "wind_speed_rel": "m/s", "wind_dir_rel": "rad",  # apparent wind (Esso Osaka 3 m data set)
}


@dataclass(frozen=True)
class Trial:
    """A time series of named channels in SI units.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Time in seconds, strictly increasing.
    channels : mapping of str to ndarray, each shape (n,)
        Channel values in SI units.
    units : mapping of str to str
        SI unit of each channel (``"rad"``, ``"m/s"``, ``"-"`` ...); defaults to
        :data:`CHANNELS` for standard names and ``"-"`` otherwise.
    meta : mapping
        Free metadata: ``vessel``, ``manoeuvre``, ``source`` (file), ``seed`` ...
    """

    t: np.ndarray
    channels: Mapping[str, np.ndarray]
    units: Mapping[str, str] = field(default_factory=dict)
    meta: Mapping[str, object] = field(default_factory=dict)

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float)
        chans = {k: np.asarray(v, dtype=float) for k, v in self.channels.items()}
        for k, v in chans.items():
            if v.shape != t.shape:
                raise InputError(f"has {v.size} samples but time has {t.size}",
                                 file=_src(self.meta), channel=k)
        units = {k: self.units.get(k, CHANNELS.get(k, "-")) for k in chans}
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "channels", chans)
        object.__setattr__(self, "units", units)
        object.__setattr__(self, "meta", dict(self.meta))

    # -- access -----------------------------------------------------------------
    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.channels[name]
        except KeyError:
            raise InputError(f"missing channel (has: {', '.join(self.channels) or 'none'})",
                             file=_src(self.meta), channel=name) from None

    def __contains__(self, name: str) -> bool:
        return name in self.channels

    def __len__(self) -> int:
        return self.t.size

    @property
    def names(self) -> list[str]:
        """Channel names in order."""
        return list(self.channels)

    @property
    def dt(self) -> float:
        """Sampling interval (median of the time steps), in seconds."""
        return float(np.median(np.diff(self.t))) if self.t.size > 1 else float("nan")

    @property
    def duration(self) -> float:
        """Last minus first time, in seconds."""
        return float(self.t[-1] - self.t[0]) if self.t.size else 0.0

    def require(self, names: Iterable[str], *, method: str | None = None) -> None:
        """Raise one :class:`InputError` for the first required channel that is missing."""
        for name in names:
            if name not in self.channels:
                what = f"required by {method} " if method else "required "
                raise InputError(f"{what}but missing (has: {', '.join(self.channels) or 'none'})",
                                 file=_src(self.meta), channel=name)

    def stack(self, names: Iterable[str]) -> np.ndarray:
        """Channels as columns of an ``(n, k)`` array."""
        return np.column_stack([self[n] for n in names])

    def with_channels(self, **new: np.ndarray) -> "Trial":
        """Return a copy with channels added or replaced (SI units)."""
        chans = dict(self.channels)
        chans.update(new)
        return Trial(self.t, chans, self.units, self.meta)

    def select(self, names: Iterable[str]) -> "Trial":
        """Return a copy with only the given channels."""
        names = list(names)
        self.require(names)
        return Trial(self.t, {n: self.channels[n] for n in names},
                     {n: self.units[n] for n in names}, self.meta)

    def slice_time(self, t0: float | None = None, t1: float | None = None) -> "Trial":
        """Samples with ``t0 <= t <= t1``."""
        lo = -np.inf if t0 is None else t0
        hi = np.inf if t1 is None else t1
        m = (self.t >= lo) & (self.t <= hi)
        return Trial(self.t[m], {k: v[m] for k, v in self.channels.items()}, self.units, self.meta)

    def to_frame(self):
        """A :class:`pandas.DataFrame` indexed by time, columns named ``name [unit]``."""
        import pandas as pd
        data = {f"{k} [{self.units[k]}]": v for k, v in self.channels.items()}
        df = pd.DataFrame(data, index=pd.Index(self.t, name="t [s]"))
        df.attrs.update(self.meta)
        return df


def _src(meta: Mapping[str, object]) -> str | None:
    s = meta.get("source") if meta else None
    return None if s is None else str(s)
