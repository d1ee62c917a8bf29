"""Datasets of Algorithm 1 of Linder et al. (2015): checks, the regressors (35)/(37) and the black-box
instruments of step A (44).

Each dataset (a :class:`shipid.io.trial.Trial` with ``p`` roll rate (9a), ``a_s`` tangential acceleration (9b),
``r`` yaw rate (SNAME sign; ERRATA on 9c), ``delta`` rudder) becomes a :class:`Dataset` with

    Phi_t = [-y_{t-1}, -y_{t-2}, a_t - a_{t-2}, r_t - r_{t-2}, delta_t - delta_{t-2}]      (37)

and ARX(4, 5) simulations of ``y, a_s, r`` from the rudder (the iteration-0 instruments).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from shipid.io.trial import Trial
from shipid.errors import InputError
from shipid.estimate.iv import arx_fit, arx_simulate
from shipid.methods.masscm.options import REQUIRED, MassCMOptions
from shipid.models.roll_reduced import CALIBRATION, LOADED, NOMINAL

@dataclass
class Dataset:
    """One dataset ready for Algorithm 1 (signals mean-removed; see :func:`prepare`)."""

    condition: str
    T: float
    y: np.ndarray
    a_s: np.ndarray
    r: np.ndarray
    delta: np.ndarray
    Phi: np.ndarray = field(repr=False, default=None)       # regressors (35), full length
    r_hat0: np.ndarray = field(repr=False, default=None)    # black-box r simulation (44)
    y_hat0: np.ndarray = field(repr=False, default=None)
    a_hat0: np.ndarray = field(repr=False, default=None)
    cache: dict = field(repr=False, compare=False, default_factory=dict)   # iterate-independent products


def diff2(x: np.ndarray) -> np.ndarray:
    d = np.zeros_like(x)
    d[2:] = x[2:] - x[:-2]
    return d


def prepare(datasets: Sequence[tuple[str, Trial]], options: MassCMOptions = MassCMOptions()) -> list[Dataset]:
    """Check and condition the datasets; build regressors (35) and the black-box instruments (A).

    Sensor biases (9): the differences in ``mu`` (34) remove the biases of ``a_s`` and ``r``; a gyro
    bias ``b_1`` on ``y`` leaves a constant ``(1 + alpha1 + alpha2) b_1`` in the equation error, which is
    orthogonal to the (mean-removed) instruments. ``y`` itself is NOT mean-removed: the mean roll rate
    of a record is not zero (phi_end != phi_0), and removing it would put a constant into the equation.
    """
    if not datasets:
        raise InputError("mass-cm needs datasets")
    conds = [c for c, _ in datasets]
    for need in (NOMINAL, CALIBRATION, LOADED):
        if need not in conds:
            raise InputError(f"mass-cm needs at least one {need} dataset (has: {', '.join(conds)})")
    out = []
    for cond, tr in datasets:
        tr.require(list(REQUIRED), method="mass-cm") if hasattr(tr, "require") else None
        t = np.asarray(tr.t, dtype=float)
        dt = np.diff(t)
        if t.size < 200:
            raise InputError(f"{cond} dataset has only {t.size} samples (need >= 200)", file=tr.meta.get("source"))
        if np.ptp(dt) > 1e-6 * np.mean(dt):
            raise InputError(f"{cond} dataset is not uniformly sampled (resample first)", file=tr.meta.get("source"))
        sig = {k: np.asarray(tr[k], dtype=float) for k in REQUIRED}
        for k, v in sig.items():
            bad = np.flatnonzero(~np.isfinite(v))
            if bad.size:
                raise InputError("non-finite value", file=tr.meta.get("source"), channel=k, row=int(bad[0]))
        if np.std(sig["delta"]) == 0:
            raise InputError(f"{cond} dataset has a constant rudder: no excitation (§3.1)",
                             file=tr.meta.get("source"), channel="delta")
        y = sig["p"]
        ds = Dataset(condition=cond, T=float(np.mean(dt)), y=y, a_s=sig["a_s"], r=sig["r"],
                     delta=sig["delta"] - sig["delta"].mean())
        ylag1 = np.concatenate([[0.0], y[:-1]])
        ylag2 = np.concatenate([[0.0, 0.0], y[:-2]])
        ds.Phi = np.column_stack([-ylag1, -ylag2, diff2(ds.a_s), diff2(ds.r), diff2(ds.delta)])   # (37)
        sims = {}
        for name, sgl in (("y", y - y.mean()), ("a_s", ds.a_s - ds.a_s.mean()), ("r", ds.r - ds.r.mean())):
            b, a = arx_fit(sgl, ds.delta, options.arx_na, options.arx_nb)
            sims[name] = arx_simulate(b, a, ds.delta)       # the simulation B/A delta
        ds.y_hat0, ds.a_hat0, ds.r_hat0 = sims["y"], sims["a_s"], sims["r"]
        out.append(ds)
    return out


def first_row(options: MassCMOptions) -> int:
    return max(options.n_y, options.n_as, options.n_r, options.n_delta, 3) + 1


__all__ = ["Dataset", "diff2", "prepare", "first_row"]
