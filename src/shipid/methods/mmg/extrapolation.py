"""Does an MMG model identified from small-angle zig-zags carry to large rudder angles? (KVLCC2, HSVA)

A cross-validation within the HSVA zig-zags, standing in for the question the
turning circles of another basin ask (35° rudder, steady turn): every candidate
structure is fitted on the 10° and 15° zig-zags only (:data:`TRAIN`) and predicts the
20°, 25° and 30° ones (:data:`VALIDATE`), which are all training runs of the frozen
overshoot study (:mod:`shipid.methods.mmg.study`); its held-out runs
(:data:`shipid.methods.mmg.study.KVLCC2_TEST`) are never read here. Per validation run:

* **open-loop replay** — the measured rudder and propeller replayed from the measured
  state at execute over the whole run (:func:`replay`), the way a turning circle of
  another basin is predicted: RMS heading error (deg) and the relative error of the
  peak yaw rate reached on each side (%), the quantity that sets a turning circle's
  diameter (``D ≈ 2 U / r`` in the steady turn);
* **closed-loop overshoots** — the zig-zag with the tank autopilot measured on the
  training runs (:func:`shipid.methods.mmg.zigzag.kvlcc2_autopilot`), first and second
  overshoot errors (deg).

The score (lower is better) is the RMS over runs and sides of the peak-yaw-rate errors
(%) plus the RMS heading error (deg) — what a turning circle measures, and the whole
record. Candidates: the frozen study's six (:data:`shipid.methods.mmg.candidates.CANDIDATES`)
the same three free sets with the L7 asymmetry of γ_R applied to the other side
(``swapped``: the HSVA rudder sign was inferred and the model propeller's sense of
rotation is not among the particulars), two with a quarter, half and three quarters
of the L7 asymmetry of γ_R kept about its mean (between the symmetric and the L7 values), the three symmetric-γ_R ones with the
non-dimensional regression weighting (:func:`shipid.methods.mmg.estimator.row_weights`:
each sample counts by its non-dimensional force, so the slower, larger-drift parts of
the bigger zig-zags weigh as much as the fast straight runs), and each of these with the port/starboard asymmetry terms of the ``yasukawa2015-asym``
structure (:data:`shipid.models.mmg.COEFS`: propeller side force and moment ∝ thrust,
rudder force per side), and four with the rudder normal force of a low-aspect-ratio
foil, ``f_α sin α_R + C_Dc sin α_R |sin α_R|`` with the cross-flow drag coefficient
``C_Dc = 1`` fixed a priori (Hoerner, Fluid-Dynamic Lift, 1985, ch. 3: 0.8–1.2 for
square tips; ``rudder_crossflow`` of :func:`shipid.models.mmg_forces.basis_yasukawa`),
which the 10°/15° zig-zags cannot separate from ``f_α`` but which grows with the angle.
The γ_R asymmetry calibrated on the training zig-zags' peak yaw rates is
:mod:`shipid.methods.mmg.side_calibration`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from shipid.io.basins import read_kvlcc2
from shipid.io.trial import Trial
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import validate as V
from shipid.methods.mmg.candidates import CANDIDATES
from shipid.methods.mmg.zigzag import execute_index, kvlcc2_autopilot
from shipid.models import mmg
from shipid.methods.mmg.study import zigzag_overshoots

TRAIN = ("HSVA_CPMC_KVLCC2_Z_10_01.dat", "HSVA_CPMC_KVLCC2_Z_10_05.dat", "HSVA_CPMC_KVLCC2_Z_10_10_P.dat",
         "HSVA_CPMC_KVLCC2_Z_10_10_S.dat", "HSVA_CPMC_KVLCC2_Z_15_01.dat", "HSVA_CPMC_KVLCC2_Z_15_05.dat")
VALIDATE = ("HSVA_CPMC_KVLCC2_Z_20_05.dat", "HSVA_CPMC_KVLCC2_Z_25_05.dat", "HSVA_CPMC_KVLCC2_Z_30_05.dat")
ASYM = {"Y": ("YP_T", "YR_asym"), "N": ("NP_T", "NR_asym")}


def candidates() -> dict[str, dict]:
    """The frozen study's yasukawa2015 candidates, three with γ_R swapped, and each with the asymmetry terms free."""
    base = dict(CANDIDATES["yasukawa2015"])
    for name in ("full", "linear-hull+rudder", "hull-only"):     # the L7 asymmetry of γ_R on the other side
        base[name + "/swapped-gamma_R"] = dict(base[name], particulars={"gamma_R": "swapped"})
    for name in ("full", "linear-hull+rudder"):                  # part of the L7 asymmetry of γ_R
        for a in (0.25, 0.5, 0.75):
            base[f"{name}/gamma_R-asymmetry-{a:g}"] = dict(base[name], particulars={"gamma_R_asymmetry": a})
    for name in ("full", "linear-hull+rudder", "hull-only"):     # non-dimensional regression weighting
        base[name + "/symmetric-gamma_R/nondimensional"] = dict(base[name + "/symmetric-gamma_R"],
                                                                weighting="nondimensional")
    out = dict(base)
    for name, c in base.items():
        a = dict(c, structure="yasukawa2015-asym")
        for m, extra in ASYM.items():
            a[m] = tuple(c[m]) + extra
        out[name + "+asym"] = a
    for name in ("full/symmetric-gamma_R", "linear-hull+rudder/symmetric-gamma_R", "hull-only/symmetric-gamma_R",
                 "linear-hull+rudder/gamma_R-asymmetry-0.25"):   # rudder normal force with cross-flow drag
        out[name + "/rudder-crossflow-1"] = dict(base[name], particulars=dict(base[name].get("particulars") or {},
                                                                              rudder_crossflow=1.0))
    return out


def replay(model: mmg.MmgModel, tr) -> dict[str, Any]:
    """Open-loop replay of the measured inputs from the measured state at execute."""
    Z = V.measured_states(tr)
    U = V.trial_inputs(tr)
    k0 = execute_index(tr["delta"])
    t = np.asarray(tr.t[k0:], float)
    X = mmg.simulate_batch(model, t - t[0], Z[k0][None], U[k0:][None])[0]
    zr, xr = Z[k0:, 5], X[:, 5]
    e_psi = np.degrees(np.unwrap(X[:, 2]) - np.unwrap(Z[k0:, 2]))
    out = {"psi_rms": float(np.sqrt(np.mean(e_psi ** 2))) if np.all(np.isfinite(e_psi)) else float("inf")}
    for side, sg in (("stbd", 1.0), ("port", -1.0)):
        m_pk, p_pk = float(np.max(sg * zr)), float(np.max(sg * xr)) if np.all(np.isfinite(xr)) else float("nan")
        out[f"r_peak_{side}_err_pct"] = 100.0 * (p_pk - m_pk) / m_pk if np.isfinite(p_pk) else float("inf")
    return out


def large_angle_split(root: Path | None = None):
    """The large-angle cross-validation's data: ``(prior, train, runs, autopilot, validate)``.

    The kvlcc2_hsva prior, the :data:`TRAIN` zig-zags read and smoothed, the autopilot identified from
    them (:func:`~shipid.methods.mmg.zigzag.kvlcc2_autopilot`) and the :data:`VALIDATE` zig-zags read; no
    other run is read.
    """
    prior = mmg.load_published("kvlcc2_hsva", root)
    train = [read_kvlcc2(f, root) for f in TRAIN]
    runs = [R.smooth_run(tr) for tr in train]
    ap = kvlcc2_autopilot(train, TRAIN)
    val = [read_kvlcc2(f, root) for f in VALIDATE]
    return prior, train, runs, ap, val


def score_validation(model: mmg.MmgModel, val: Sequence[Trial], names: Sequence[str], ap: dict) -> dict:
    """The :func:`cross_validate` row of one model on the validation runs ``val`` (file names ``names``):
    peak-yaw-rate errors per side (%), heading RMS (deg), overshoot errors (deg), score = peak RMS + heading."""
    per = {}
    for f, tr in zip(names, val):
        row = replay(model, tr)
        row["overshoot_err_deg"] = zigzag_overshoots(model, tr, f, ap)["error"]
        per[f] = row
    rp = np.array([[r[f"r_peak_{s}_err_pct"] for s in ("stbd", "port")] for r in per.values()])
    psi = np.array([r["psi_rms"] for r in per.values()])
    ov = np.array([e for r in per.values() for e in r["overshoot_err_deg"]])
    row = {"r_peak_rms_pct": float(np.sqrt(np.mean(rp ** 2))), "r_peak_stbd_mean_pct": float(rp[:, 0].mean()),
           "r_peak_port_mean_pct": float(rp[:, 1].mean()), "psi_rms_deg": float(np.sqrt(np.mean(psi ** 2))),
           "overshoot_rms_deg": float(np.sqrt(np.mean(ov ** 2))) if ov.size else float("nan"), "runs": per}
    row["score"] = row["r_peak_rms_pct"] + row["psi_rms_deg"]
    if not np.isfinite(row["score"]):
        row["score"] = float("inf")
    return row


def cross_validate(cands: Mapping[str, Mapping] | None = None, *, root: Path | None = None,
                   progress=None) -> dict[str, dict]:
    """Fit every candidate on :data:`TRAIN`, score it on :data:`VALIDATE` (module docstring)."""

    cands = candidates() if cands is None else cands
    prior, train, runs, ap, val = large_angle_split(root)
    table: dict[str, dict] = {}
    for cname, cand in cands.items():
        cprior, free = R.apply_candidate(prior, cand)
        cfg = R.candidate_config(R.FitConfig(), cand)
        try:
            model = R.fit(runs, cprior, free, cfg).model
        except Exception as err:  # noqa: BLE001  (a candidate that cannot be fitted scores infinity)
            table[cname] = {"score": float("inf"), "error": str(err)}
            continue
        table[cname] = score_validation(model, val, VALIDATE, ap)
        if progress is not None:
            progress(cname)
    return table


def format_table(table: Mapping[str, dict]) -> str:
    """One line per candidate: score, peak-yaw-rate errors per side, heading RMS, overshoot RMS."""
    lines = [f"  {'candidate':<56} {'score':>7} {'r_pk rms%':>9} {'stbd%':>7} {'port%':>7} {'psi deg':>8} "
             f"{'ovs deg':>8}"]
    best = min(table, key=lambda c: table[c]["score"])
    for c, r in table.items():
        if "error" in r:
            lines.append(f"  {c:<56} failed: {r['error']}")
            continue
        lines.append(f"  {c:<56} {r['score']:7.2f} {r['r_peak_rms_pct']:9.2f} {r['r_peak_stbd_mean_pct']:7.2f} "
                     f"{r['r_peak_port_mean_pct']:7.2f} {r['psi_rms_deg']:8.2f} {r['overshoot_rms_deg']:8.2f}"
                     + ("  <-" if c == best else ""))
    return "\n".join(lines)


__all__ = ["large_angle_split", "score_validation", "TRAIN", "VALIDATE", "candidates", "replay", "cross_validate", "format_table"]
