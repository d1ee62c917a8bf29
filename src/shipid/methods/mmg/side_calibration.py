"""Port/starboard asymmetry of the rudder inflow, calibrated on what the training zig-zags measure.

The force regression of :mod:`shipid.methods.mmg.estimator` fits the sway force and yaw
moment sample by sample; the port/starboard difference of a single-screw ship is a few
per cent of those forces and, at the 10°/15° rudder of the training zig-zags, it is
confounded with the hull terms: fitted as a free coefficient (``yasukawa2015-asym``:
propeller side force ∝ thrust, rudder force per side) it makes the large-angle prediction
worse (:mod:`shipid.methods.mmg.extrapolation`). What the training runs do measure well is
the yaw rate each side reaches. So the one asymmetry parameter — the flow-straightening
coefficient per side, ``γ_R± = γ̄ ± a·Δ`` with ``γ̄``, ``Δ`` the mean and half-difference
of the prior's values (``a = 1``: the KVLCC2 L7 asymmetry, ``a = 0``: symmetric, ``a < 0``:
the other side; Yasukawa & Yoshimura 2015 eq. 26: the effective rudder inflow angle
``α_R = δ − atan(v_R/u_R)``, ``v_R = U γ_R β_R``) — is chosen on a grid by an
output-error criterion on the TRAINING runs: each grid value's model is fitted by the
regression as usual and the measured rudder and propeller of every training zig-zag
with a switch heading of 5° or more are replayed open loop from execute
(:func:`shipid.methods.mmg.extrapolation.replay`); the score is the RMS over runs and
sides of the relative error of the peak yaw rate (%), the quantity a turning circle's
diameter depends on. (The 1°-switch runs are excluded a priori: their yaw-rate peaks
are a few tenths of a degree per second and set by the switching, not by the turn.)
The rest of the model (free coefficients, weighting) is the candidate's. The grid's best
is refined by the vertex of a parabola through it and its neighbours (the grid alone
could not resolve the minimum, which lies between 0 and 0.25 in both cases below; this
refinement was added after the grid-only numbers were seen).

Large-angle CV (``shipid study kvlcc2-sides``; trained on the 10°/15°
zig-zags, scored on the 20°, 25°, 30° ones as :mod:`shipid.methods.mmg.extrapolation`
scores: RMS peak-yaw-rate error % + RMS heading error deg; mean peak error per side;
RMS overshoot error), base candidate ``linear-hull+rudder``::

    candidate                                  a      score  r_pk%  stbd%   port%  psi°   ovs°
    symmetric γ_R (the frozen study's best)    0      15.96  6.29   +1.19   -8.64  9.67   1.11
    γ_R asymmetry calibrated                   0.126  14.11  5.50   -0.47   -7.51  8.61   1.33
    C_Dc = 1, symmetric γ_R                    0      14.07  5.22   +4.29   -5.83  8.85   0.73
    C_Dc = 1, γ_R asymmetry calibrated         0.116  11.79  4.15   +2.82   -4.89  7.63   0.85
    C_Dc = 1, symmetric γ_R, side gain s       -0.014 11.58  3.74   +2.09   -4.57  7.84   0.87

(the last: the rudder effectiveness per side ``F_N (1 + s sign δ)`` calibrated the same way
instead of γ_R, ``parameter="rudder_side_gain"``, grid :data:`SIDE_GAIN_GRID`; the training
criterion pins it sharply, 3.20 % at s = 0 and 5.3 % at s = −0.05, yet the port peaks of the
larger zig-zags stay low: the asymmetry grows with the rudder angle beyond what 10°/15° show.)

(``C_Dc``: the cross-flow drag part of the rudder normal force, ``rudder_crossflow`` of
:func:`shipid.models.mmg_forces.basis_yasukawa`.) The heading RMS is dominated by the 30°
run (16.5° symmetric, 11.3° with both changes); on the 20° and 25° runs it grows
(2.2 → 5.9°, 2.1 → 3.6°). The port peaks stay 4–6 % low.
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from shipid.io.trial import Trial
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg.candidates import apply_candidate, candidate_config
from shipid.methods.mmg.extrapolation import TRAIN, VALIDATE, candidates, large_angle_split, replay, score_validation
from shipid.methods.mmg.zigzag import zigzag_angles
from shipid.models import mmg

#: γ_R asymmetry fractions tried (module docstring).
GRID = (-0.5, -0.25, 0.0, 0.25, 0.5, 0.75, 1.0)
#: Port/starboard rudder-effectiveness values tried (``rudder_side_gain``).
SIDE_GAIN_GRID = (-0.15, -0.1, -0.05, 0.0, 0.05, 0.1, 0.15)
#: Smallest switch heading (deg) of a zig-zag whose peak yaw rates enter the criterion.
MIN_SWITCH_DEG = 5.0


def with_asymmetry(cand: Mapping, a: float, parameter: str = "gamma_R_asymmetry") -> dict:
    """``cand`` with the particular ``parameter`` set to ``a`` (for the γ_R asymmetry fraction, in place
    of any γ_R override of its own; ``"rudder_side_gain"``: the port/starboard rudder effectiveness
    ``F_N (1 + s sign δ)`` of :func:`shipid.models.mmg_forces.basis_yasukawa`)."""
    c = dict(cand)
    drop = ("gamma_R", "gamma_R_asymmetry") if parameter == "gamma_R_asymmetry" else (parameter,)
    part = {k: v for k, v in (cand.get("particulars") or {}).items() if k not in drop}
    part[parameter] = float(a)
    c["particulars"] = part
    return c


def fit_candidate(runs: Sequence[R.SmoothedRun], prior: mmg.MmgModel, cand: Mapping,
                  config: R.FitConfig = R.FitConfig()) -> mmg.MmgModel:
    """The regression fit of ``cand`` on ``runs``."""
    cprior, free = apply_candidate(prior, cand)
    return R.fit(runs, cprior, free, candidate_config(config, cand)).model


def peak_score(model: mmg.MmgModel, trials: Sequence[Trial], names: Sequence[str]) -> float:
    """RMS over the zig-zags with switch ≥ :data:`MIN_SWITCH_DEG` and both sides of the peak-yaw-rate error (%)."""
    errs = []
    for tr, nm in zip(trials, names):
        if np.degrees(zigzag_angles(nm)[1]) < MIN_SWITCH_DEG - 1e-9:
            continue
        r = replay(model, tr)
        errs += [r["r_peak_stbd_err_pct"], r["r_peak_port_err_pct"]]
    e = np.asarray(errs, float)
    return float(np.sqrt(np.mean(e ** 2))) if e.size and np.all(np.isfinite(e)) else float("inf")


def calibrate(runs: Sequence[R.SmoothedRun], trials: Sequence[Trial], names: Sequence[str], prior: mmg.MmgModel,
              cand: Mapping, grid: Sequence[float] = GRID, *, refine: bool = True,
              parameter: str = "gamma_R_asymmetry") -> tuple[float, dict[float, float]]:
    """The γ_R asymmetry with the lowest :func:`peak_score` on the training runs, and the score of
    every value tried: the grid's best (the first on a tie), then, with ``refine`` and an interior
    best, the vertex of the parabola through it and its neighbours' mean-square scores
    (:func:`refine_minimum`), kept if it scores lower."""
    def score(a):
        try:
            return peak_score(fit_candidate(runs, prior, with_asymmetry(cand, a, parameter)), trials, names)
        except (ValueError, np.linalg.LinAlgError):
            return float("inf")

    table = {float(a): score(a) for a in grid}
    best = min(table, key=lambda a: table[a])
    if refine:
        g = sorted(table)
        i = g.index(best)
        if 0 < i < len(g) - 1 and all(np.isfinite(table[g[j]]) for j in (i - 1, i, i + 1)):
            a = refine_minimum(g[i - 1:i + 2], [table[g[j]] ** 2 for j in (i - 1, i, i + 1)])
            sa = score(a)
            table[a] = sa
            if sa < table[best]:
                best = a
    return best, table


def refine_minimum(x: Sequence[float], y: Sequence[float]) -> float:
    """Vertex of the parabola through three points whose middle one is lowest (clipped to their span)."""
    (x0, x1, x2), (y0, y1, y2) = x, y
    den = (x0 - x1) * (x0 - x2) * (x1 - x2)
    A = (x2 * (y1 - y0) + x1 * (y0 - y2) + x0 * (y2 - y1)) / den
    B = (x2 * x2 * (y0 - y1) + x1 * x1 * (y2 - y0) + x0 * x0 * (y1 - y2)) / den
    if not A > 0:
        return float(x1)
    return float(np.clip(-B / (2 * A), x0, x2))


def cross_validate(bases: Sequence[str] = ("linear-hull+rudder", "full"), *, root: Path | None = None,
                   grid: Sequence[float] = GRID, every_grid_value: bool = False,
                   particulars: Mapping[str, float] | None = None, parameter: str = "gamma_R_asymmetry",
                   progress=None) -> dict[str, dict]:
    """Fit on :data:`~shipid.methods.mmg.extrapolation.TRAIN` with the γ_R asymmetry calibrated on
    those runs, score on :data:`~shipid.methods.mmg.extrapolation.VALIDATE` (as the extrapolation
    study scores). ``every_grid_value``: also score each grid value's model (a diagnostic of how well
    the training criterion chose; not a selection). ``particulars``: further overrides of every
    base candidate (e.g. ``{"rudder_crossflow": 1.0}``)."""
    cands = candidates()
    if particulars:
        cands = {k: dict(c, particulars=dict(c.get("particulars") or {}, **particulars)) for k, c in cands.items()}
    suffix = "".join(f"/{k}-{v:g}" for k, v in (particulars or {}).items())
    prior, train, runs, ap, val = large_angle_split(root)
    out: dict[str, dict] = {}
    for base in bases:
        a, table = calibrate(runs, train, TRAIN, prior, cands[base], grid, parameter=parameter)
        model = fit_candidate(runs, prior, with_asymmetry(cands[base], a, parameter))
        row = score_validation(model, val, VALIDATE, ap)
        row.update(calibrated_asymmetry=a, training_peak_score=table)
        out[f"{base}/{parameter}-calibrated{suffix}"] = row
        if progress is not None:
            progress(base)
        if every_grid_value:
            for g in grid:
                m = fit_candidate(runs, prior, with_asymmetry(cands[base], g, parameter))
                r = score_validation(m, val, VALIDATE, ap)
                r["training_peak_score"] = table[float(g)]
                out[f"{base}/{parameter}-{g:g}{suffix}"] = r
    return out


__all__ = ["GRID", "SIDE_GAIN_GRID", "MIN_SWITCH_DEG", "with_asymmetry", "fit_candidate", "peak_score", "calibrate",
           "refine_minimum", "cross_validate"]
