"""Reproduction of the simulation study of Yoon & Rhee (2003, §5.1, Tables 3–5, Figs. 4 and 6).

``study("standard")``: identify from the 35° turning circles to both sides and the
20°/20° zig-zag (Table 3/4; target: the combined coefficients of eq. 21 within 5 %).
``study("optimal-prbs")``: identify from one D-optimal PRBS run (Table 5; target:
every linear coefficient within 15 %). Both report the step-1 accuracy (smoothed
v_r and r against the truth, Fig. 4) and a validation on a held-out ±10° PRBS run
simulated with the identified and with the true coefficients (Fig. 6).
"""

from __future__ import annotations

import numpy as np

from shipid.methods.ebm import estimator as ebm
from shipid.methods.ebm.series import add_validation, with_series
from shipid.methods.ebm.trials import STANDARD_TRIALS, VALIDATION_TRIAL, simulate_trial
from shipid.models import abkowitz as ab
from shipid.result import Result

#: The paper's D-optimal PRBS (Fig. 7: amplitude 35°, clock period 105 s), the input of its Table 5.
#: On our simulated criterion the amplitude agrees but the best period is 40 s, with 105 s lower by
#: 0.57 ± 0.26 in log10 |WᵀW| (see :mod:`shipid.methods.ebm.design`); the Table-5 reproduction keeps the
#: paper's input.
OPTIMAL_PRBS = (35.0, 105.0)
OPTIMAL_DURATION = 1800.0
LINEAR = ("Y_v", "Y_r", "N_v", "N_r", "Y_delta", "N_delta")

_NAMES = ab.THETA_X_NAMES + ab.THETA_Y_NAMES + ab.THETA_N_NAMES
#: The "Estimated" column of Yoon & Rhee (2003) Table 3 (standard manoeuvres), read
#: from the seed text (the table is partly garbled there; the values are in the
#: order of eq. 13), for side-by-side comparison only.
PAPER_TABLE3 = dict(zip(_NAMES, (
    -1.10e-4, -2.45e-5, 4.53e-7, -1.28e-3, 9.49e-3, 6.28e-3, -1.07e-2, -2.26e-3,
    -3.13e-5, -5.99e-2, -9.25e-3, 3.56e0, 3.97e0, 1.43e0, 1.78e-1, 3.67e-3, 4.42e-3,
    -1.53e-5, -1.39e-2, -6.34e-3, 5.66e-1, 6.25e-1, 2.51e-1, 2.95e-1, -2.55e-3, 2.24e-3)))
#: The "Estimated" column of Table 5 (sub-optimal PRBS input).
PAPER_TABLE5 = dict(zip(_NAMES, (
    -3.85e-4, -1.25e-5, 3.07e-7, -1.63e-2, 3.87e-3, 5.93e-3, -2.43e-3, -1.84e-3,
    -1.48e-5, -2.44e-2, 6.17e-3, -1.29e-1, -3.27e-2, -5.06e-2, -6.11e-3, 5.67e-3, -2.56e-3,
    -3.17e-6, -1.08e-2, -4.81e-3, -3.80e-4, -1.29e-2, 9.51e-3, -9.88e-4, -2.32e-3, 8.00e-4)))
#: Table 4 of the paper (standard manoeuvres): kappa, R, Cp per mode.
PAPER_TABLE4 = {"surge": (3.7220e4, 0.9890, 8.0545), "sway": (2.8251e6, 0.9823, 9.0536),
                "yaw": (2.8166e6, 0.9198, 9.0808)}


def true_coefficients(p: ab.AbkowitzParams) -> dict[str, float]:
    names = ab.THETA_X_NAMES + ab.THETA_Y_NAMES + ab.THETA_N_NAMES
    return dict(zip(names, p.theta_X + p.theta_Y + p.theta_N))


def make_trials(kind: str, seed: int, scale: float = 1.0):
    """The identification trials of ``kind`` (``scale`` < 1 shortens them for quick runs)."""
    if kind == "standard":
        return [simulate_trial(m, d * scale, seed=seed + i) for i, (m, d) in enumerate(STANDARD_TRIALS.values())]
    if kind == "optimal-prbs":
        a, T = OPTIMAL_PRBS
        return [simulate_trial(f"prbs-{a:g}-{T:g}", OPTIMAL_DURATION * scale, seed=seed)]
    raise ValueError(f"unknown study input {kind!r} (standard, optimal-prbs)")


def tracking_rms(state: ebm.StateEstimate) -> dict[str, float]:
    """RMS of smoothed minus true v_r, r, X, Y, N on a simulated trial (Fig. 4)."""
    tr = state.trial
    x = state.smooth.x
    out = {}
    for name, i, key in (("v_r", 1, "true_v_r"), ("r", 2, "true_r"), ("X", 6, "true_X"), ("Y", 9, "true_Y"),
                         ("N", 12, "true_N")):
        e = x[:, i] - tr[key]
        out[name] = float(np.sqrt(np.mean(e ** 2)))
        out[name + "_truth_rms"] = float(np.sqrt(np.mean(tr[key] ** 2)))
    return out


def validate(theta_hat: ab.AbkowitzParams, seed: int, scale: float = 1.0) -> dict[str, float]:
    """Fig. 6: held-out ±10° PRBS with identified vs true coefficients, noise-free; RMS differences."""
    man, dur = VALIDATION_TRIAL
    ref = simulate_trial(man, dur * scale, seed=seed + 500, noise=False)
    try:
        est = simulate_trial(man, dur * scale, seed=seed + 500, noise=False, theta=theta_hat)
    except Exception as err:  # the identified model may be unstable
        return {"diverged": True, "error": f"{type(err).__name__}: {err}"}
    out: dict[str, float | bool] = {"diverged": False}
    for k in ("true_u_r", "true_v_r", "true_r", "true_psi", "true_x", "true_y", "true_X", "true_Y", "true_N"):
        out[k[5:]] = float(np.sqrt(np.mean((est[k] - ref[k]) ** 2)))
        out[k[5:] + "_ref_rms"] = float(np.sqrt(np.mean((ref[k] - (ref[k][0] if k in ("true_x", "true_y") else 0)) ** 2)))
    out["max_position_error_m"] = float(np.max(np.hypot(est["true_x"] - ref["true_x"], est["true_y"] - ref["true_y"])))
    return out


def study(kind: str = "standard", seed: int = 0, *, scale: float = 1.0,
          config: ebm.EbmConfig = ebm.EbmConfig(), progress=None, validation: bool = True) -> Result:
    """Run the Table 3 (``"standard"``) or Table 5 (``"optimal-prbs"``) reproduction."""
    p = ab.params_from_vessel()  # the simulated ship: for the comparison with the truth only
    trials = make_trials(kind, seed, scale)
    states, fit, p_id = ebm.identify_states(trials, "esso-osaka", config=config, progress=progress)
    res = with_series(ebm.EbmRun(ebm.build_result(states, fit, p_id, config, "esso-osaka"), states, fit, p_id))
    truth = true_coefficients(p)
    table = []
    paper = PAPER_TABLE3 if kind == "standard" else PAPER_TABLE5
    for name, tv in truth.items():
        e = res.estimates[name]
        table.append({"coefficient": name, "true": tv, "estimated": e.value, "se": e.std,
                      "rel_error": (e.value - tv) / abs(tv), "paper_estimated": paper[name],
                      "paper_rel_error": (paper[name] - tv) / abs(tv)})
    comb = res.diagnostics["combined_eq21"]
    ct = ebm.combined_coefficients(p.theta_Y, p.theta_N, fit.alpha)
    ctrue = {"Yv+Yr/alpha": ct[0], "Nv*alpha+Nr": ct[1]}
    comb_err = {k: (comb[k] - ctrue[k]) / abs(ctrue[k]) for k in ("Yv+Yr/alpha", "Nv*alpha+Nr")}
    tc = ab.trial_conditions()
    cx, cy = tc["current_speed"] * np.cos(tc["current_dir"]), tc["current_speed"] * np.sin(tc["current_dir"])
    res.diagnostics.update({
        "study": kind, "seed": seed, "scale": scale,
        "table": table,
        "combined_eq21_rel_error": comb_err,
        "combined_eq21_true": ctrue,
        "linear_max_rel_error": float(max(abs(r["rel_error"]) for r in table if r["coefficient"] in LINEAR)),
        "tracking_rms": [dict(tracking_rms(s), manoeuvre=s.trial.meta.get("manoeuvre", "")) for s in states],
        "current_true": [cx, cy],
        "paper_table": "Table 3/4" if kind == "standard" else "Table 5",
        "paper_table4": PAPER_TABLE4,
    })
    if validation:
        th = p.with_theta(fit.surge.theta, fit.sway.theta, fit.yaw.theta)
        res.diagnostics["validation"] = validate(th, seed, scale)
        add_validation(res, VALIDATION_TRIAL[0], min(VALIDATION_TRIAL[1] * scale, 300.0), seed=seed + 500)
    res.method = "ebm-study"
    res.provenance.update({"seed": seed, "study": f"ebm-esso-osaka --input {kind}"})
    return res


__all__ = ["PAPER_TABLE3", "PAPER_TABLE5", "PAPER_TABLE4", "study", "make_trials", "validate", "tracking_rms", "true_coefficients", "OPTIMAL_PRBS", "LINEAR"]
