"""When to refine Algorithm 1's mass / CM estimate: the ``refine="auto"`` rule (Linder et al. 2015, seed 000).

Beyond the paper. Algorithm 1 (the rudder-instrument refined IV) is at the Cramér–Rao bound of
:mod:`shipid.methods.masscm.crlb_kf` with sensor noise alone (spread / bound ~0.9) but 1.5–1.7 x it with waves and
sensor noise, where the maximum-likelihood refinement of :mod:`shipid.methods.masscm.pem` reaches the bound. That
refinement's model is singular when the sensors are noise-free (waves alone, the noise-free Table 3 data): there it
fails after 30–50 s and Algorithm 1's estimate is kept. :func:`choose` therefore refines only when the data show
both sensor noise and coloured (wave) equation error, by two cheap tests:

(a) **Sensor noise** (:func:`sensor_noise_level`, before any refinement; a few ms for three 300-s datasets). With
    noise-free sensors the sampled outputs of the roll–sway–yaw model are an exact linear function of a few lags of
    the measured channels, whatever the wave moment: the single unmeasured input ``tau`` enters ``a_s`` directly
    (through ``p'`` and ``v'``, eq. 8), so it and the state are reconstructed from lags of ``(p, a_s, r, delta)``.
    Per dataset and gyro channel ``x`` in ``(p, r)`` the statistic is the relative RMS residual of the
    least-squares one-step prediction

        x_k ~ c + sum_{j=1..PREDICTION_LAGS} (a_j p_{k-j} + b_j a_{s,k-j} + c_j r_{k-j} + d_j delta_{k-j}),
        s = rms(residual) / std(x),

    which is what the discretisation and model leave with noise-free sensors (~1e-3 here) and is raised to the white
    gyro noise over the signal (~0.02 at the issue-3 noise) by sensor noise. The level is the smallest ``s`` over
    the datasets and channels; sensor noise is detected when it exceeds :data:`SENSOR_NOISE_MIN`.
(b) **Coloured (wave) equation error** (:func:`waves_detected`, free: read from Algorithm 1's own noise model,
    ``diagnostics["noise_model_selected"]``): some dataset's Box–Jenkins prefilter has a wave factor
    ``(1 - c q^-2)^k`` with ``k >= 1`` and ``c > 0`` (:mod:`shipid.methods.masscm.noise_bj`, chosen by the
    innovation likelihood).

Rule: refine (with :data:`AUTO_ENGINE`) iff z_f is known, (a) and (b). Otherwise Algorithm 1's estimate is the
answer and no warning is written (a skipped refinement is the rule's decision, not a failure); a refinement that
runs and fails keeps Algorithm 1's estimate with one warning line (:mod:`shipid.methods.masscm.pem_result`). The
decision and both statistics are in ``diagnostics["refine"]``.

Thresholds, chosen on ``SeedSequence([s, 0])``, ``s = 100..199`` only (300-s records, the regimes of
:mod:`shipid.methods.masscm.coverage`), measured by ``benchmarks/diag_masscm_refine_rule.py``: see
:data:`SENSOR_NOISE_MIN`.
"""

from __future__ import annotations

import numpy as np

from shipid.methods.masscm.pem_result import refine_result as _pem

#: The values of ``MassCMOptions.refine``: ``"auto"`` the rule of this module, ``"none"`` Algorithm 1 alone, or an
#: engine of :data:`ENGINES` run unconditionally.
REFINE_MODES = ("auto", "none", "pem")

#: Refinement engines: ``name -> f(result, datasets, known, z_f) -> result`` (the result's ``diagnostics["refine"]``
#: with ``applied`` and ``reason``; a failure keeps Algorithm 1's estimate with one warning line).
ENGINES = {"pem": _pem}

#: Engine ``refine="auto"`` dispatches to when the rule says refine (a name :func:`refine_with` knows).
AUTO_ENGINE = "pem"

#: Lags of every channel in the one-step prediction of test (a).
PREDICTION_LAGS = 4

#: Test (a) threshold on the relative one-step prediction residual. On seeds 100..199 (300-s records): noise-free
#: sensors (waves, and no noise at all) give levels 1.0e-3 to 1.3e-3; the sensors and both regimes (gyro noise
#: 0.002 rad/s) 1.5e-2 to 2.2e-2. The threshold is near the geometric mean of the two ranges.
SENSOR_NOISE_MIN = 4e-3

_CHANNELS = ("p", "a_s", "r", "delta")
_TESTED = ("p", "r")


def prediction_residual(sig: dict, lags: int = PREDICTION_LAGS) -> dict:
    """Relative RMS residual of the one-step linear prediction of each gyro channel (test (a) of the module
    docstring) for one dataset: ``{"p": s_p, "r": s_r}``. ``sig`` maps ``p, a_s, r, delta`` to equal-length
    arrays. The normal equations are solved after scaling to unit diagonal (float64; the regressors are
    well conditioned at the sample rates used); a constant column absorbs the sensor biases."""
    n = lags
    x = {k: np.asarray(sig[k], dtype=float) for k in _CHANNELS}
    N = x["p"].size
    if N <= 4 * (len(_CHANNELS) * n + 1):
        return {k: float("nan") for k in _TESTED}
    X = np.empty((N - n, len(_CHANNELS) * n + 1))
    X[:, 0] = 1.0
    c = 1
    for k in _CHANNELS:
        for j in range(1, n + 1):
            X[:, c] = x[k][n - j:N - j]
            c += 1
    G = X.T @ X
    d = np.sqrt(np.maximum(np.diag(G), 1e-300))
    Gs = G / np.outer(d, d)
    out = {}
    for k in _TESTED:
        y = x[k][n:]
        sd = float(np.std(y))
        if not sd > 0:
            out[k] = float("nan")
            continue
        try:
            beta = np.linalg.solve(Gs, (X.T @ y) / d) / d
        except np.linalg.LinAlgError:
            beta = np.linalg.lstsq(X, y, rcond=None)[0]
        e = y - X @ beta
        out[k] = float(np.sqrt(np.mean(e * e)) / sd)
    return out


def sensor_noise_level(datasets) -> dict:
    """Test (a) over all datasets (``[(condition, trial), ...]``): ``level`` (the smallest statistic), ``per``
    (each dataset's ``{"p", "r"}``) and ``detected`` (``level > SENSOR_NOISE_MIN``)."""
    per = []
    for _cond, tr in datasets:
        per.append(prediction_residual({k: tr[k] for k in _CHANNELS}))
    vals = [v for d in per for v in d.values() if np.isfinite(v)]
    level = float(min(vals)) if vals else float("nan")
    return {"level": level, "threshold": SENSOR_NOISE_MIN, "detected": bool(vals) and level > SENSOR_NOISE_MIN,
            "per_dataset": per}


def waves_detected(result) -> dict:
    """Test (b): a wave factor ``(1 - c q^-2)^k``, ``k >= 1``, ``c > 0`` in some dataset's Algorithm 1 noise model."""
    sel = result.diagnostics.get("noise_model_selected") or {}
    cs, ks = list(sel.get("c") or []), list(sel.get("k") or [])
    hit = any(float(c) > 0 and int(k) >= 1 for c, k in zip(cs, ks))
    return {"detected": bool(hit), "c": [float(c) for c in cs], "k": [int(k) for k in ks]}


def choose(datasets, result, z_f) -> tuple[str, dict]:
    """The rule of the module docstring: ``(engine, record)``, engine ``"none"`` or :data:`AUTO_ENGINE`; the
    record (for ``diagnostics["refine"]``) holds the decision, its reason and both tests."""
    sens = sensor_noise_level(datasets)
    wav = waves_detected(result)
    if z_f is None:
        engine, why = "none", "z_f not known"
    elif not sens["detected"]:
        engine, why = "none", "no sensor noise detected: Algorithm 1 kept"
    elif not wav["detected"]:
        engine, why = "none", "no wave structure in Algorithm 1's noise model: Algorithm 1 kept"
    else:
        engine, why = AUTO_ENGINE, "sensor noise and wave structure detected"
    rec = {"mode": "auto", "decision": engine, "decision_reason": why,
           "sensor_test": {k: sens[k] for k in ("level", "threshold", "detected")}, "wave_test": wav}
    return engine, rec


def apply(result, datasets, known, z_f, mode: str = "auto"):
    """``result`` (Algorithm 1's) refined as ``mode`` says (:data:`REFINE_MODES`); the decision is recorded in
    ``diagnostics["refine"]`` (``mode``, ``decision``, ``decision_reason``, with ``"auto"`` the two tests, and the
    engine's own record when one ran). Only a refinement that ran, or was requested by name, and failed writes a
    warning line."""
    if mode not in REFINE_MODES:
        raise ValueError(f"refine must be one of {', '.join(REFINE_MODES)}")
    datasets = list(datasets)
    if mode == "none":
        result.diagnostics["refine"] = {"mode": "none", "decision": "none", "decision_reason": "not requested",
                                        "applied": False}
        return result
    if mode == "auto":
        engine, rec = choose(datasets, result, z_f)
    else:
        engine, rec = mode, {"mode": mode, "decision": mode, "decision_reason": "requested"}
    if engine == "none":
        result.diagnostics["refine"] = {**rec, "applied": False}
        return result
    out = ENGINES[engine](result, datasets, known, z_f)
    out.diagnostics["refine"] = {**rec, **(out.diagnostics.get("refine") or {})}
    return out


__all__ = ["REFINE_MODES", "ENGINES", "apply", "AUTO_ENGINE", "PREDICTION_LAGS", "SENSOR_NOISE_MIN", "prediction_residual", "sensor_noise_level",
           "waves_detected", "choose"]
