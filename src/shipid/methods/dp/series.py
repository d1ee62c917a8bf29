"""Report series of the DP identification (Fossen, Sagatun & Sørensen 1996, seed 001; issue 8).

Adds to a ``dp`` :class:`~shipid.result.Result` what ``shipid report`` draws beyond the
parameter histories (Fig. 8, built by :mod:`shipid.methods.dp.estimator`):

* ``residuals["innovation_<scheme>_<channel>"]`` — the innovations of the final filter pass of
  each scheme (SI1: distance run along the heading, eq. 32; SI2, SI3: x, y, ψ, eqs. 44–45) for
  the first trial of the scheme, with ``std`` = the square root of the diagonal of the
  innovation covariance S that the EKF predicted. For a consistent filter about 95 % of the
  innovations lie inside ±2σ and they are white; the report tests both.
* ``overlays["SI2_psi"]`` — measured heading of the first sway–yaw trial against the EKF's
  one-step-ahead model prediction (measurement − innovation).
* ``provenance["inputs"]`` — a :func:`~shipid.report.convention.trial_summary` per trial.

Positions are converted from the bis system (eqs. 26–28) back to metres, time to seconds.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from shipid.report.convention import overlay, residual, trial_summary

#: Measured channels of each scheme's model (:func:`shipid.methods.dp.stage_models.prepare`).
CHANNELS = {"surge": (("s", "distance run along the heading s", "m"),),
            "momentum": (("x", "north position x", "m"), ("y", "east position y", "m"),
                         ("psi", "heading ψ", "rad"))}
INPUT_CHANNELS = ("x", "y", "psi", "p1", "p2", "p3", "p4", "p5", "p6", "alpha6")


def innovations(stages, vessel, trials_by_stage: dict[str, Sequence]) -> tuple[dict, dict]:
    """Innovation residuals (with σ) and one-step overlays of the first trial of every scheme.

    Parameters
    ----------
    stages : sequence of :class:`shipid.methods.dp.estimator.StageResult`
    vessel : DPVessel
    trials_by_stage : dict
        Scheme name (``"SI1"`` ...) -> the trials it ran on, in the same order.
    """
    res, ov = {}, {}
    L = float(vessel.bis.L)
    for st in stages:
        trials = trials_by_stage.get(st.name) or []
        if not trials:
            continue
        ekf = st.ekf
        tr = trials[0]
        nu = np.asarray(ekf.innovations[0], dtype=float)             # (n, nz) bis
        n, nz = nu.shape
        S = np.asarray(ekf.combined.S, dtype=float)[:n, :nz, :nz]    # trial 0 is the first block
        sd = np.sqrt(np.clip(np.einsum("kii->ki", S), 0.0, None))
        t = np.asarray(tr.t, dtype=float)[:n]
        t = t - t[0]
        chans = CHANNELS["surge" if nz == 1 else "momentum"]
        src = tr.meta.get("source") or f"{st.name} trial 1"
        for j, (ch, label, unit) in enumerate(chans):
            scale = L if unit == "m" else 1.0
            v, s = nu[:, j] * scale, sd[:, j] * scale
            s = np.where(np.isfinite(v), s, np.nan)
            res[f"innovation_{st.name}_{ch}"] = residual(
                t, v, unit, std=s, label=f"{st.name} innovation of {label}",
                title=f"Innovation of {label} ({st.name}, {src}, final pass) with the EKF's predicted ±2σ "
                      "(√ of the diagonal of S); about 95 % inside and white for a consistent filter.")
            if st.name == "SI2" and ch == "psi" and ch in tr.channels:
                meas = np.asarray(tr[ch], dtype=float)[:n].copy()
                if ch == "psi":  # unwrapped over the valid fixes, as the filter sees it
                    ok = np.isfinite(meas)
                    meas[ok] = np.unwrap(meas[ok])
                ov[f"SI2_{ch}"] = overlay(
                    t, meas, meas - v, unit, kind="fit", label=f"{label} ({src})",
                    title=f"{label} of the first sway–yaw trial ({src}): measured and the EKF's one-step-ahead "
                          "model prediction (final SI2 pass); residual = innovation, with its autocorrelation.")
    return res, ov


def inputs(trials_by_stage: dict[str, Sequence]) -> list[dict]:
    """``provenance["inputs"]``: one trial summary per trial, noting the scheme that used it."""
    out = []
    for name, trials in trials_by_stage.items():
        for k, tr in enumerate(trials):
            try:
                chans = [c for c in INPUT_CHANNELS if c in tr.channels]
                out.append(trial_summary(tr, name=tr.meta.get("source") or f"{name} trial {k + 1}",
                                         channels=chans, note=f"scheme {name}"))
            except Exception:  # noqa: BLE001 - an odd trial must not break the method
                out.append({"name": f"{name} trial {k + 1}", "note": f"scheme {name}"})
    return out


def attach(result, stages, vessel, surge, sway_yaw, azimuth) -> None:
    """Add innovations, one-step overlays and input summaries to ``result`` (never raises)."""
    by = {"SI1": list(surge), "SI2": list(sway_yaw), "SI3": list(azimuth)}
    try:
        res, ov = innovations(stages, vessel, by)
        if res:
            result.series.setdefault("residuals", {}).update(res)
        if ov:
            result.series.setdefault("overlays", {}).update(ov)
    except Exception as err:  # noqa: BLE001 - report extras must never lose the estimate
        result.diagnostics.setdefault("warnings", []).append(
            f"report series: innovations not built ({type(err).__name__}: {err})")
    prov = result.provenance
    if not isinstance(prov.get("inputs"), list) or all(isinstance(x, str) for x in prov.get("inputs", [])):
        files = prov.get("inputs")
        summ = inputs(by)
        if isinstance(files, list) and len(files) == len(summ):   # keep the file paths the CLI recorded
            for e, f in zip(summ, files):
                e["name"] = str(f)
        prov["inputs"] = summ


__all__ = ["innovations", "inputs", "attach"]
