"""Wind-driven surface current: a run moved into the frame of the water it sails in.

The Esso Osaka 3-m runs were made on an outdoor pond (Inukai pond, Osaka University) in a true wind of
1-2 m/s (the logs' ``wind_velo_true``), at ship speeds of 0.1-0.35 m/s. Wind drags the surface water
downwind; a drift of 1-3 % of the wind speed, the usual order for wind-driven surface drift, is 2-6 cm/s
here, 5-50 % of the ship's speed. The MMG forces act on the velocity through the water, while the logs
measure the velocity over ground (the body velocities agree with the position derivative,
:mod:`shipid.methods.mmg.timing`), so an unmodelled current shows as a per-run drift of the predicted
track and heading. No current was measured; the model here ties it to what was:

    V_c(t) = c · W̄(t),    W̄ = causal first-order low-pass (time constant τ) of the true-wind air velocity

(``W = −U_T (cos γ_T, sin γ_T)`` in earth axes, γ_T the direction the wind blows from, as in
:func:`shipid.models.mmg_forces.apparent_wind`), earth-fixed, uniform over the pond, changing slowly. The
current is an input computed from measured channels, like the wind force: a prediction over a horizon
uses only the wind measured up to each instant.

:func:`to_water_frame` rewrites a run in the water frame: position minus the drift ``D(t) = ∫₀ᵗ V_c``,
body velocities minus the current in body axes, and the true wind minus the current (so the apparent
wind, air relative to the ship, is unchanged). For a current that is uniform and changes slowly the
rigid-body and hydrodynamic equations of the MMG model hold for the velocity through the water (Fossen
2011, *Handbook of Marine Craft Hydrodynamics and Motion Control*, §10.3, for an irrotational current
constant in earth axes), so the whole pipeline (smoother, regression, output error, validation) runs on
the water-frame run unchanged. A 60-s horizon restarted from the measured state and compared in the
water frame has the same position error as the water-frame prediction plus ``D`` compared over ground
(both sides move by the same ``D(t)``), and the heading is untouched: scores stay comparable with the
ground-frame ones.

Which ``c`` and ``τ`` (or none) is chosen by the training-run CV of
:func:`shipid.methods.mmg.study_ext2.cv_current`; the rule and the table are in that module.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from shipid.data.trial import Trial


@dataclass(frozen=True)
class DriftCurrent:
    """A wind-driven current: ``factor`` (current speed / true wind speed) and the low-pass time constant ``tau`` (s)."""

    factor: float
    tau: float = 60.0

    def to_dict(self) -> dict:
        return asdict(self)


def drift_velocity(t: np.ndarray, wind_speed: np.ndarray, wind_dir: np.ndarray,
                   current: DriftCurrent) -> tuple[np.ndarray, np.ndarray]:
    """Earth-axes current ``(c_x, c_y)`` (m/s) of :class:`DriftCurrent` from the true wind.

    The air velocity ``W`` is low-passed causally, ``dW̄/dt = (W − W̄)/τ`` (exact for ``W`` held over each
    sample interval, so gaps in the time base are handled), started at the first sample's ``W``; samples
    with a non-finite wind hold the last filtered value.
    """
    t = np.asarray(t, float)
    wx = -np.asarray(wind_speed, float) * np.cos(wind_dir)
    wy = -np.asarray(wind_speed, float) * np.sin(wind_dir)
    ok = np.isfinite(wx) & np.isfinite(wy)
    fx, fy = np.zeros_like(t), np.zeros_like(t)
    if not ok.any():
        return fx, fy
    k0 = int(np.flatnonzero(ok)[0])
    ax, ay = wx[k0], wy[k0]
    keep = np.exp(-np.maximum(np.diff(t, prepend=t[0]), 0.0) / current.tau)
    for k in range(t.size):
        if ok[k]:
            ax = keep[k] * ax + (1.0 - keep[k]) * wx[k]
            ay = keep[k] * ay + (1.0 - keep[k]) * wy[k]
        fx[k], fy[k] = ax, ay
    return current.factor * fx, current.factor * fy


def to_water_frame(trial: Trial, current: DriftCurrent) -> Trial:
    """``trial`` in the frame of the water (module docstring): x, y, u, v and the true wind moved by the
    current, recorded as a data repair in ``meta["repairs"]``. A run without true-wind channels is
    returned unchanged."""
    if current.factor == 0.0 or not all(c in trial for c in ("wind_speed", "wind_dir", "x", "y", "u", "v", "psi")):
        return trial
    t = np.asarray(trial.t, float)
    cx, cy = drift_velocity(t, trial["wind_speed"], trial["wind_dir"], current)
    dt = np.diff(t)
    dx = np.concatenate([[0.0], np.cumsum(0.5 * (cx[1:] + cx[:-1]) * dt)])
    dy = np.concatenate([[0.0], np.cumsum(0.5 * (cy[1:] + cy[:-1]) * dt)])
    psi = np.asarray(trial["psi"], float)
    c, s = np.cos(psi), np.sin(psi)
    wx = -np.asarray(trial["wind_speed"], float) * np.cos(trial["wind_dir"]) - cx
    wy = -np.asarray(trial["wind_speed"], float) * np.sin(trial["wind_dir"]) - cy
    out = trial.with_channels(x=np.asarray(trial["x"], float) - dx, y=np.asarray(trial["y"], float) - dy,
                              u=np.asarray(trial["u"], float) - (c * cx + s * cy),
                              v=np.asarray(trial["v"], float) - (-s * cx + c * cy),
                              wind_speed=np.hypot(wx, wy), wind_dir=np.mod(np.arctan2(-wy, -wx), 2 * np.pi))
    meta = dict(out.meta)
    text = (f"moved into the water frame of a wind-driven current {current.factor:g} x the true wind "
            f"(low-passed, time constant {current.tau:g} s): position, body velocities and true wind relative "
            f"to the water (mean current {np.mean(np.hypot(cx, cy)):.3f} m/s)")
    meta["repairs"] = list(meta.get("repairs", []) or []) + [{"kind": "water-frame", "text": text}]
    meta["current"] = current.to_dict()
    return Trial(out.t, out.channels, out.units, meta)


__all__ = ["DriftCurrent", "drift_velocity", "to_water_frame"]
