"""Coverage study of EBM on ships it has not been told about (Yoon & Rhee 2003).

Each run of the campaign (:func:`shipid.campaign.engine.run_campaign`, task :func:`run_one`)
draws, from its own ``SeedSequence``:

* an *unknown ship*: every coefficient of Table 3 (the packaged ESSO OSAKA, [abkowitz])
  multiplied by its own factor from U[0.7, 1.3], kept only when the straight run at the
  approach speed exists and is straight-line stable (:func:`draw_ship`); its approach
  propeller rate is the one that balances its own resistance
  (:func:`shipid.models.abkowitz.with_coefficients`);
* a current: speed U[0.5, 2] kn setting towards U[0, 360)°;
* the measurement noise of eq. 19 with every standard deviation scaled by one factor from
  U[0.5, 1.5] that the estimator is not told (it assumes eq. 19), and the noise and PRBS seeds.

The trial is the D-optimal PRBS of :data:`shipid.methods.ebm.study.OPTIMAL_PRBS`
(35°, 105 s) for ``duration`` seconds. :func:`shipid.methods.ebm.estimator.identify` sees only the
measured channels and the vessel's particulars. :func:`summarise` gives per coefficient
the bias and spread of the relative error, the mean |z| and the coverage of ±2 std, over
the runs where the coefficient is ``estimated`` (and how often it is).

Measured figures, with the commands that regenerate them: ``docs/validation/ebm.md``.
"""

from __future__ import annotations

import numpy as np

from shipid.methods.ebm import estimator as ebm
from shipid.methods.ebm.trials import simulate_trial
from shipid.models import abkowitz as ab

LINEAR = ("Y_v", "Y_r", "N_v", "N_r", "Y_delta", "N_delta")
NAMES = ab.THETA_X_NAMES + ab.THETA_Y_NAMES + ab.THETA_N_NAMES
KNOT = ab.KNOT


def straight_line_stable(p: ab.AbkowitzParams) -> bool:
    """Eigenvalues of the linearised (u, v, r) dynamics at the approach (δ = 0, n = n0) all in the left half-plane."""
    f = ab.make_dynamics(p)
    x0 = np.array([p.U0, 0.0, 0.0, 0.0, 0.0, 0.0])
    u = np.array([0.0, p.n0])
    J = np.zeros((3, 3))
    for j in range(3):
        h = 1e-6 * (p.U0 if j == 0 else 1.0) if j < 2 else 1e-7
        xp, xm = x0.copy(), x0.copy()
        xp[j] += h
        xm[j] -= h
        J[:, j] = (f(0.0, xp, u, p)[:3] - f(0.0, xm, u, p)[:3]) / (2 * h)
    return bool(np.all(np.linalg.eigvals(J).real < 0))


def draw_ship(rng: np.random.Generator, base: ab.AbkowitzParams | None = None, *, spread: float = 0.3,
              max_tries: int = 100) -> tuple[ab.AbkowitzParams, np.ndarray]:
    """A perturbed ship (module docstring) and its 26 factors; redraws until straight-line stable."""
    base = ab.params_from_vessel() if base is None else base
    th = np.array(base.theta_X + base.theta_Y + base.theta_N)
    nx, ny = len(base.theta_X), len(base.theta_Y)
    for _ in range(max_tries):
        fac = rng.uniform(1.0 - spread, 1.0 + spread, th.size)
        t = th * fac
        try:
            q = ab.with_coefficients(base, t[:nx], t[nx:nx + ny], t[nx + ny:])
        except ValueError:
            continue
        if straight_line_stable(q):
            return q, fac
    raise RuntimeError("no straight-line-stable ship drawn")


def simulate_unknown(q: ab.AbkowitzParams, rng: np.random.Generator, *, duration: float = 1200.0,
                     current: tuple[float, float] | None = None, noise_scale: float | None = None,
                     manoeuvre: str = "prbs-35-105"):
    """One measured trial of ship ``q`` (current and noise scale drawn from ``rng`` unless given)."""

    if current is None:
        current = (float(rng.uniform(0.5, 2.0)) * KNOT, float(rng.uniform(0.0, 2 * np.pi)))
    if noise_scale is None:
        noise_scale = float(rng.uniform(0.5, 1.5))
    seed = int(rng.integers(0, 2 ** 31 - 1))
    tr = simulate_trial(manoeuvre, duration, seed=seed, current=current, theta=q, noise_scale=noise_scale)
    return tr, current, noise_scale


def run_one(i: int, seed=0, *, duration: float = 1200.0) -> dict:
    """Campaign task: draw a ship, a current and noise (module docstring), identify, compare."""

    rng = np.random.default_rng(seed)
    q, fac = draw_ship(rng)
    tr, current, ns = simulate_unknown(q, rng, duration=duration)
    res = ebm.identify([tr])
    truth = dict(zip(NAMES, q.theta_X + q.theta_Y + q.theta_N))
    out = {"coefficients": {}, "factors": dict(zip(NAMES, map(float, fac))), "noise_scale": ns, "current_true": list(current), "n0_true": q.n0,
           "n0_used": res.model["n0"], "c0_true": q.c0, "c0_used": res.model["c0"],
           "converged": bool(res.diagnostics["converged"]), "warnings": list(res.diagnostics.get("warnings", []))}
    for nm in NAMES:
        e = res.estimates[nm]
        out["coefficients"][nm] = {"true": truth[nm], "value": e.value, "std": e.std, "status": e.status}
    cs = res.estimates["current_speed"]
    out["current_speed"] = {"true": current[0], "value": cs.value, "std": cs.std}
    return out


def summarise(outputs: list[dict | None], names=NAMES) -> dict:
    """Per coefficient over the runs: n estimated, bias and spread of the relative error, coverage of ±2 std."""
    runs = [o for o in outputs if o is not None]
    table = {}
    for nm in names:
        rows = [o["coefficients"][nm] for o in runs]
        est = [r for r in rows if r["status"] == "estimated"]
        rel = np.array([(r["value"] - r["true"]) / abs(r["true"]) for r in est])
        z = np.array([(r["value"] - r["true"]) / r["std"] for r in est])
        table[nm] = {"runs": len(rows), "estimated": len(est),
                     "bias_rel": float(np.mean(rel)) if rel.size else None,
                     "spread_rel": float(np.std(rel, ddof=1)) if rel.size > 1 else None,
                     "mean_abs_z": float(np.mean(np.abs(z))) if z.size else None,
                     "coverage_2std": float(np.mean(np.abs(z) <= 2.0)) if z.size else None,
                     "wrong_sign": int(sum(np.sign(r["value"]) != np.sign(r["true"]) for r in est))}
    lin = [table[n] for n in LINEAR if table[n]["estimated"]]
    hits = sum(t["coverage_2std"] * t["estimated"] for t in lin)
    tot = sum(t["estimated"] for t in lin)
    cur = np.array([o["current_speed"]["value"] - o["current_speed"]["true"] for o in runs]) if runs else np.array([])
    return {"runs": len(runs), "table": table,
            "linear_pooled_coverage": float(hits / tot) if tot else None,
            "linear_min_coverage": float(min(t["coverage_2std"] for t in lin)) if lin else None,
            "current_speed_error_max": float(np.max(np.abs(cur))) if cur.size else None}


__all__ = ["run_one", "summarise", "draw_ship", "simulate_unknown", "straight_line_stable", "LINEAR"]
