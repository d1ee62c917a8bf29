"""Hand-made example results that exercise every part of the report convention.

These are NOT identification results: the numbers are synthetic (seeded random
draws around made-up values) and exist to test and demonstrate the report, and
to show method authors what a fully populated :class:`~shipid.result.Result`
looks like. ``example(method)`` returns one (``from report.examples import example`` in the tests, which
put ``tests/`` on ``sys.path``).
"""

from __future__ import annotations

import numpy as np

from shipid.report.convention import contour, history, matrix, overlay, residual, signal, table, xy
from shipid.result import Estimate, Result

_NOTE = "synthetic example for the report (not an identification)"


def _ar1(rng, n, rho, sigma):
    e = rng.normal(0.0, sigma, n)
    x = np.empty(n)
    x[0] = e[0]
    for k in range(1, n):
        x[k] = rho * x[k - 1] + e[k]
    return x


def mass_cm_example(seed: int = 0) -> Result:
    """A ``mass-cm`` result: roll-rate overlay, Fig. 4 cost map, Table-3 spread."""
    rng = np.random.default_rng(seed)
    dt, n = 0.05, 2400
    t = np.arange(n) * dt
    w, zeta = 2 * np.pi / 8.0, 0.06
    p_model = 0.05 * np.exp(-zeta * w * t) * np.sin(w * np.sqrt(1 - zeta ** 2) * t) + 0.01 * np.sin(0.7 * t)
    p_meas = p_model + rng.normal(0.0, 0.002, n)
    m_true, z_true = 14.2e3, -0.35
    m_hat, z_hat = m_true + rng.normal(0, 150), z_true + rng.normal(0, 0.02)
    mg = np.linspace(12.0e3, 16.5e3, 61)
    zg = np.linspace(-0.7, 0.0, 51)
    M, Z = np.meshgrid(mg, zg)
    dm, dz = (M - m_hat) / 600.0, (Z - z_hat) / 0.08
    cost = 1.0 + dm ** 2 + dz ** 2 - 1.6 * dm * dz
    runs = 20
    m_runs = m_true + rng.normal(0, 420, runs)
    z_runs = z_true + rng.normal(0, 0.06, runs)
    cov = np.array([[420.0 ** 2, 0.8 * 420 * 0.06], [0.8 * 420 * 0.06, 0.06 ** 2]])
    return Result(
        method="mass-cm",
        estimates={
            "m": Estimate(m_hat, 420.0, "kg"),
            "z_m": Estimate(z_hat, 0.06, "m", note="vertical CoM below the IMU, positive down"),
            "I_xx": Estimate(3.1e4, float("inf"), "kg*m^2", note="not identifiable: set by z_f"),
            "z_f": Estimate(-0.9, float("nan"), "m", status="fixed", note="known input"),
        },
        model={"vessel": "example-rib", "structure": "roll, 1 DOF (eq. 8)", "g": 9.81},
        covariance=cov,
        covariance_names=["m", "z_m"],
        diagnostics={"converged": True, "iterations": 14, "cost": float(cost.min()),
                     "warnings": ["example: I_xx is not identifiable from these data"]},
        series={
            "overlays": {"p": overlay(t, p_meas, p_model, "rad/s", label="roll rate p")},
            "contours": {"cost": contour(mg, zg, cost, x_label="m", x_unit="kg", y_label="z̄_m", y_unit="m",
                                         z_label="cost [-]", log=True,
                                         points=[{"x": m_hat, "y": z_hat, "label": "estimate"},
                                                 {"x": m_true, "y": z_true, "label": "true"}])},
            "tables": {"spread": table(["statistic", "m", "z_m"],
                                       [["mean", float(m_runs.mean()), float(z_runs.mean())],
                                        ["std", float(m_runs.std(ddof=1)), float(z_runs.std(ddof=1))],
                                        ["true", m_true, z_true]], units=["", "kg", "m"])},
            "xy": {"spread": xy(m_runs, {"runs": z_runs}, x_label="m", x_unit="kg", y_label="z_m",
                                y_unit="m", style="scatter")},
        },
        provenance={"inputs": [{"name": "example_roll.csv", "channels": {"p": "rad/s", "a_s": "m/s^2",
                                                                          "delta": "rad"},
                                "n_samples": n, "duration_s": float(t[-1]), "dt_s": dt, "note": _NOTE}],
                    "seed": seed, "command": "tests/report/examples.py: mass_cm_example"},
    )


def dp_example(seed: int = 1) -> Result:
    """A ``dp`` result: Fig. 8 parameter histories, innovations with ±2σ, position overlays."""
    rng = np.random.default_rng(seed)
    dt, n = 1.0, 1800
    t = np.arange(n) * dt
    names = {"m11": ("kg", 5.1e6), "m22": ("kg", 7.9e6), "m33": ("kg*m^2", 3.2e9), "d11": ("kg/s", 5.2e4),
             "d22": ("kg/s", 2.7e5), "d33": ("kg*m^2/s", 4.1e8)}
    hists, est = {}, {}
    for k, (nm, (unit, true)) in enumerate(names.items()):
        s = 0.5 * abs(true) / np.sqrt(1.0 + t / 60.0)
        v = true * (1.0 + 0.6 * np.exp(-t / 300.0) * (1 if k % 2 else -1)) + s * _ar1(rng, n, 0.995, 0.05)
        hists[nm] = history(t, v, s, unit, true=true)
        est[nm] = Estimate(float(v[-1]), float(s[-1]), unit)
    innov = {}
    for ch, unit, sd in (("x", "m", 0.8), ("y", "m", 0.8), ("psi", "rad", 0.004)):
        std = np.full(n, sd)
        innov[f"innovation_{ch}"] = residual(t, rng.normal(0, sd, n), unit, std=std, label=f"innovation {ch}")
    x = 20 * np.sin(2 * np.pi * t / 900)
    return Result(
        method="dp",
        estimates=est,
        model={"vessel": "example-supply", "structure": "3-DOF low-frequency model (eq. 1)", "trials": 3},
        diagnostics={"converged": True, "iterations": n, "log_likelihood": -1234.5},
        series={"histories": hists, "residuals": innov,
                "overlays": {"x": overlay(t, x + rng.normal(0, 0.8, n), x, "m", label="north position x")}},
        provenance={"inputs": [{"name": f"example_dp_{i}.csv", "channels": ["x", "y", "psi", "p1", "p2"],
                                "n_samples": n, "duration_s": float(t[-1]), "dt_s": dt, "note": _NOTE}
                               for i in range(3)], "seed": seed},
    )


def ebm_example(seed: int = 2) -> Result:
    """An ``ebm`` result: signals (Figs 4, 9), regressor correlation, Table 4, Fig. 7 map, validation."""
    rng = np.random.default_rng(seed)
    dt, n = 0.5, 1200
    t = np.arange(n) * dt
    delta = np.deg2rad(20) * np.sign(np.sin(2 * np.pi * t / 120))
    r = 0.012 * np.sin(2 * np.pi * t / 120 - 0.6)
    v = -0.3 * np.sin(2 * np.pi * t / 120 - 0.4)
    coeffs = {"Y_v": (-1.1e-2, 6e-4), "Y_r": (2.4e-3, 3e-4), "Y_delta": (2.6e-3, 1e-4),
              "N_v": (-3.8e-3, 2e-4), "N_r": (-1.7e-3, 5e-5), "N_delta": (-1.2e-3, 4e-5)}
    est = {k: Estimate(val + rng.normal(0, sd), sd, "-") for k, (val, sd) in coeffs.items()}
    names = list(coeffs)
    A = rng.normal(size=(6, 6))
    C = A @ A.T + 6 * np.eye(6)
    d = np.sqrt(np.diag(C))
    corr = C / np.outer(d, d)
    cov = corr * np.outer([s for _, s in coeffs.values()], [s for _, s in coeffs.values()])
    reg = ["v", "r", "delta", "v|v|", "r|r|", "v²r"]
    R = np.corrcoef(np.vstack([v, r, delta, v * np.abs(v), r * np.abs(r), v ** 2 * r])
                    + rng.normal(0, 0.02, (6, n)))
    amp = np.linspace(5, 35, 31)
    per = np.linspace(20, 200, 37)
    P, Am = np.meshgrid(per, amp)
    dopt = np.log(1 + Am / 10) * np.exp(-((P - 110) / 70) ** 2)
    r_val = 0.01 * np.sin(2 * np.pi * t / 90)
    return Result(
        method="ebm",
        estimates=est,
        model={"vessel": "example-tanker", "structure": "Abkowitz 3-DOF, sway-yaw (eq. 2)", "L": 320.0},
        covariance=cov, covariance_names=names,
        diagnostics={"converged": True, "iterations": 5, "ridge_k": 0.012,
                     "warnings": ["example: ridge parameter chosen at the edge of the search range"]},
        series={
            "signals": {
                "r": signal(t, {"measured": r + rng.normal(0, 4e-4, n), "smoothed": r}, "rad/s",
                            std={"smoothed": np.full(n, 2e-4)}, label="yaw rate r"),
                "v": signal(t, {"smoothed": v}, "m/s", std={"smoothed": np.full(n, 0.02)}, label="sway v"),
                "Y": signal(t, {"estimated": 1e5 * np.sin(2 * np.pi * t / 120)}, "N", label="sway force Y"),
                "current": signal(t, {"u_c": 0.2 + 0 * t, "v_c": -0.1 + 0 * t}, "m/s", label="current"),
            },
            "matrices": {"regressor_correlation": matrix(R, reg, reg, vmin=-1, vmax=1)},
            "tables": {"conditioning": table(["model", "κ", "R²", "Cp"],
                                             [["full", 812.0, 0.991, 7.0], ["reduced", 35.2, 0.987, 5.1]],
                                             units=["", "-", "-", "-"])},
            "contours": {"d_optimal": contour(per, amp, dopt, x_label="zig-zag period", x_unit="s",
                                              y_label="rudder amplitude", y_unit="deg",
                                              z_label="log det M [-]")},
            "overlays": {
                "r": overlay(t, r + rng.normal(0, 4e-4, n), r, "rad/s", label="yaw rate r"),
                "r_validation": overlay(t, r_val + _ar1(rng, n, 0.9, 2e-4), r_val, "rad/s",
                                        label="yaw rate r (20/20 zig-zag)", kind="validation"),
            },
        },
        provenance={"inputs": [{"name": "example_zigzag.csv", "channels": {"x": "m", "y": "m", "psi": "rad",
                                                                            "delta": "rad"},
                                "n_samples": n, "duration_s": float(t[-1]), "dt_s": dt, "note": _NOTE}],
                    "seed": seed},
    )


EXAMPLES = {"mass-cm": mass_cm_example, "dp": dp_example, "ebm": ebm_example}


def example(method: str) -> Result:
    """The example result of ``method`` (``"mass-cm"``, ``"dp"`` or ``"ebm"``)."""
    return EXAMPLES[method]()
