"""Which EBM coefficients the data determine, and which trials cannot be used (Yoon & Rhee 2003).

Yoon & Rhee (2003) identify every coefficient of eq. 13 from whatever the trials hold;
their Table 3 shows what that gives on the standard manoeuvres (Y'_vvv ten times too
large, wrong signs of the cubic terms). Here each coefficient gets a verdict from the
information in the data:

* **excitation** (:func:`check_excitation`, before anything is estimated): a set of trials
  whose rudder angle or speed barely varies is refused with one line naming the missing
  excitation — the rudder columns of eq. 14 are then proportional to other columns and
  the surge regressors ``u², L n u, L² n²`` collinear;
* **step 1 observability**: the rank test of eq. 11 (:mod:`shipid.analysis.observability`)
  along the smoothed trajectory; a rank deficit anywhere leaves every coefficient
  undetermined;
* per coefficient, from the ridge fit (:func:`shipid.estimate.ridge.ridge`, HAC standard
  errors including the ridge bias):

  - relative standard error ``se / |θ̂|`` above ``max_rel_se`` (the sign is not
    determined: ``|θ̂| < 2 se`` for the default 0.5),
  - variance inflation factor ``VIF_j = (WᵀW)⁻¹_jj`` of the unit-length-scaled regressors
    (eq. 16) above ``max_vif``: the column is, to that degree, a combination of the others,
  - ridge-bias share ``|bias_j| / se_sampling_j`` above ``max_bias_share``: the value is
    mostly the shrinkage of eq. 18, not the data,
  - the mode's ``R²`` below ``min_r2``: the model does not explain the smoothed force;
  - the offset terms ``Y_0``, ``N_0`` (regressor ``(u_A∞/2)²``, nearly constant over a trial) are
    never ``estimated``: a constant error of the smoothed force goes into them whole and leaves
    no residual, so no residual-based std can cover it (on the perturbed-ship study their ±2-std
    coverage was 0.0 and 0.72 where the other tests passed them).

A coefficient that fails one test is ``not determined``: its value is kept in the Result
(status ``"not determined"``, the note says why) but it is named in a warning and never
printed as an estimate.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from shipid.errors import InputError


#: Coefficients of the nearly constant regressor (u_A∞/2)² (eq. 14): never determined (module docstring).
OFFSET_TERMS = ("Y_0", "N_0")


@dataclass(frozen=True)
class VerdictOptions:
    """Thresholds of the verdict (module docstring).

    ``max_rel_se = 0.5``: the sign must be determined (|θ̂| ≥ 2 se). ``max_vif = 1e4``: in the
    simulated coverage runs (:mod:`shipid.methods.ebm.coverage`) coefficients with VIF above
    it were the cubic terms of the zig-zag-only trial; the linear ones stayed below 200 in the PRBS runs. ``max_bias_share = 1``: the ridge shrinkage larger than the sampling std.
    ``min_r2 = 0.5``: the mode's model explains less than half of the smoothed force. Rudder range
    2° and speed range 2 % (30-s means, so that the log noise of eq. 19 alone, well under 1 %, never passes).
    """

    max_rel_se: float = 0.5
    max_vif: float = 1e4
    max_bias_share: float = 1.0
    min_r2: float = 0.5
    min_rudder_range_deg: float = 2.0
    min_speed_range: float = 0.02
    speed_window_s: float = 30.0


def _smooth(x: np.ndarray, n: int) -> np.ndarray:
    n = max(1, min(int(n), x.size))
    k = np.ones(n) / n
    return np.convolve(x, k, mode="valid")


def check_excitation(trials: Sequence, options: VerdictOptions = VerdictOptions()) -> dict:
    """Refuse trials whose rudder or speed barely varies (:class:`shipid.errors.InputError`, one line).

    Over all trials together: the rudder range ``max δ − min δ`` must reach
    ``min_rudder_range_deg``, and the range of the speed log averaged over
    ``speed_window_s`` (which takes its white noise out) must reach ``min_speed_range``
    times its mean. Returns the two ranges.
    """
    d_lo, d_hi, rel = np.inf, -np.inf, 0.0
    for tr in trials:
        d = np.asarray(tr["delta"], float)
        d_lo, d_hi = min(d_lo, float(np.min(d))), max(d_hi, float(np.max(d)))
        u = np.asarray(tr["U"], float)
        dt = float(np.median(np.diff(tr.t))) if tr.t.size > 1 else 1.0
        us = _smooth(u, int(round(options.speed_window_s / max(dt, 1e-9))))
        m = float(np.mean(np.abs(u)))
        if m > 0:
            rel = max(rel, float((np.max(us) - np.min(us)) / m))
    src = ", ".join(str(t.meta.get("source", "trial")) for t in trials[:3])
    rng = float(np.rad2deg(d_hi - d_lo))
    if rng < options.min_rudder_range_deg:
        raise InputError(f"rudder barely varies (range {rng:.2g} deg < {options.min_rudder_range_deg:g} deg): "
                         "EBM needs rudder excitation (zig-zag, PRBS) to separate the rudder coefficients "
                         "Y_delta, N_delta from the hull's", file=src or None, channel="delta")
    if rel < options.min_speed_range:
        raise InputError(f"speed barely varies (range {100 * rel:.2g} % < {100 * options.min_speed_range:g} % "
                         "of the mean): EBM needs speed excitation (hard turns, large rudder) to separate the "
                         "surge coefficients eta_CR, eta_2, eta_3", file=src or None, channel="U")
    return {"rudder_range_deg": rng, "speed_range_rel": rel}


def coefficient_verdicts(fit, names: dict, observable: bool = True,
                         options: VerdictOptions = VerdictOptions()) -> dict[str, dict]:
    """Per coefficient: ``{"status", "reasons", "rel_se", "vif", "bias_share"}``.

    ``fit`` is an :class:`shipid.methods.ebm.estimator.EbmFit`; ``names`` maps mode → coefficient names.
    """
    out = {}
    for mode, f in (("surge", fit.surge), ("sway", fit.sway), ("yaw", fit.yaw)):
        se_s = f.se if f.se_sampling is None else f.se_sampling
        bias = np.zeros_like(f.theta) if f.bias is None else f.bias
        vif = np.full_like(f.theta, np.nan) if f.vif is None else f.vif
        for j, nm in enumerate(names[mode]):
            th, se = float(f.theta[j]), float(f.se[j])
            rel = se / abs(th) if th != 0 else np.inf
            share = abs(float(bias[j])) / float(se_s[j]) if se_s[j] > 0 else np.inf
            reasons = []
            if not observable:
                reasons.append("step 1 not observable (eq. 11)")
            if f.R2 < options.min_r2:
                reasons.append(f"{mode} model explains R^2 = {f.R2:.2f} of the force")
            if not np.isfinite(rel) or rel > options.max_rel_se:
                reasons.append(f"std {rel:.2g} of |value|")
            if not np.isfinite(vif[j]) or vif[j] > options.max_vif:
                reasons.append(f"variance inflation {vif[j]:.2g}")
            if share > options.max_bias_share:
                reasons.append(f"ridge bias {share:.2g} std")
            if nm in OFFSET_TERMS:
                reasons.append("offset term: takes up any constant error of the smoothed force")
            out[nm] = {"status": "not determined" if reasons else "estimated", "reasons": reasons,
                       "rel_se": float(rel), "vif": float(vif[j]), "bias_share": float(share)}
    return out


__all__ = ["OFFSET_TERMS", "VerdictOptions", "check_excitation", "coefficient_verdicts"]
