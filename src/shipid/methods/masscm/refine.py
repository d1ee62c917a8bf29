"""When to refine Algorithm 1's mass / CM estimate: the ``refine="auto"`` rule (Linder et al. 2015).

Beyond the paper. Algorithm 1 (the rudder-instrument refined IV) is at the Cramér–Rao bound of
:mod:`shipid.methods.masscm.crlb_kf` with sensor noise alone (spread / bound ~0.9) but 1.5–1.7 x it with waves and
sensor noise, where the maximum-likelihood refinement of :mod:`shipid.methods.masscm.pem` reaches the bound. That
refinement's model is singular when the sensors are noise-free (waves alone, the noise-free Table 3 data): there it
fails after 30–50 s and Algorithm 1's estimate is kept. :func:`choose` therefore refines only when the data show
both sensor noise and coloured (wave) equation error, by two cheap tests:

(a) **Sensor noise** (:func:`sensor_noise_level`, before any refinement; a few ms for three 300-s datasets). With
    noise-free sensors the sampled outputs of the linearised roll–sway–yaw model are a linear function of a few
    lags of the measured channels, whatever the wave moment: the single unmeasured input ``tau`` enters ``a_s`` directly
    (through ``p'`` and ``v'``, eq. 8), so it and the state are reconstructed from lags of ``(p, a_s, r, delta)``.
    Per dataset and gyro channel ``x`` in ``(p, r)`` the statistic is the relative RMS residual of the
    least-squares one-step prediction

        x_k ~ c + sum_{j=1..PREDICTION_LAGS} (a_j p_{k-j} + b_j a_{s,k-j} + c_j r_{k-j} + d_j delta_{k-j}),
        s = rms(residual) / std(x),

    which is what the discretisation and model leave with noise-free sensors (~1e-3 here) and is raised to the white
    gyro noise over the signal (~0.02 at the combined wave and sensor noise) by sensor noise. The level is the smallest ``s`` over
    the datasets and channels; sensor noise is detected when it exceeds :data:`SENSOR_NOISE_MIN`.
(b) **Coloured (wave) roll disturbance** (:func:`wave_colour`; a few ms). The roll rate is predicted one step
    ahead from lags ``1..WAVE_LAGS`` of ``(p, r, delta)`` only (``a_s``, which carries the wave moment, left out),
    by least squares; with a roll moment that is not the rudder's the residual keeps the disturbance's colour
    beyond the prediction's horizon, with white sensor noise alone it is white there. The statistic is the
    Ljung–Box portmanteau ``Q = N (N+2) sum_l rho_l^2/(N-l)`` of that residual over the lags between
    :data:`WAVE_LAG_WINDOW` s (0.2–3 s: beyond the prediction's 8 samples, over the roll and wave periods),
    standardised ``z = (Q - L)/sqrt(2 L)`` (``L`` lags; ~N(0, 1) for a white residual). The level is the smallest
    ``z`` over the datasets; colour is detected when it exceeds :data:`WAVE_Z_MIN`. (Algorithm 1's own noise model
    cannot tell: its Box–Jenkins factor ``(1 - c q^-2)^k`` is chosen with sensor noise alone too, because the
    differenced regressors of (37) put that factor on the sensor noise; measured 30 of 30 sensors runs.)

Engine (:func:`auto_engine`): the exact time-domain likelihood of :mod:`shipid.methods.masscm.pem` for records of
up to :data:`EXACT_MAX_SAMPLES` samples per dataset, the banded Whittle likelihood of
:mod:`shipid.methods.masscm.whittle` beyond (the same model, start and search; the two likelihoods differ by O(1)
against O(N), and Whittle's cost per iteration does not grow with the record length). On 300-s records
Whittle's rho standard error falls short of its spread (docs/validation/mass-cm.md), so the exact likelihood is
used where its cost (linear in the length) is affordable.

Rule: refine (with :func:`auto_engine`) iff z_f is known, (a) and (b). With noise-free sensors (a) fails
whatever (b) says (the noise-free rudder response leaves a small but coloured residual, so (b) alone would
refine the noise-free data). Otherwise Algorithm 1's estimate is the
answer and no warning is written (a skipped refinement is the rule's decision, not a failure); a refinement that
runs and fails keeps Algorithm 1's estimate with one warning line (:mod:`shipid.methods.masscm.pem_result`). The
decision and both statistics are in ``diagnostics["refine"]``.

Measured figures, with the commands that regenerate them: ``docs/validation/mass-cm.md``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from shipid.methods.masscm.pem_result import refine_result as _pem
from shipid.methods.masscm.whittle_result import refine_result as _whittle
from shipid.methods.masscm.plausibility import Judgement, judge
from shipid.methods.masscm.refine_modes import REFINE_MODES
from shipid.models.roll_reduced import THETA_NAMES
from shipid.numerics.linalg import one_blas_thread


#: Refinement engines: ``name -> f(result, datasets, known, z_f) -> result`` (the result's ``diagnostics["refine"]``
#: with ``applied`` and ``reason``; a failure keeps Algorithm 1's estimate with one warning line).
ENGINES = {"pem": _pem, "whittle": _whittle}

#: Engines ``refine="auto"`` dispatches to when the rule says refine (keys of :data:`ENGINES`): the exact
#: likelihood up to :data:`EXACT_MAX_SAMPLES` samples per dataset, the Whittle likelihood beyond (:func:`auto_engine`).
AUTO_ENGINES = ("pem", "whittle")

#: Longest dataset (samples) refined by the exact time-domain likelihood under ``"auto"`` (10 min at 50 Hz).
EXACT_MAX_SAMPLES = 30_000


def auto_engine(datasets) -> str:
    """``"pem"`` when every dataset has at most :data:`EXACT_MAX_SAMPLES` samples, else ``"whittle"``."""
    n = max((len(np.asarray(tr["p"])) for _, tr in datasets), default=0)
    return AUTO_ENGINES[0] if n <= EXACT_MAX_SAMPLES else AUTO_ENGINES[1]

#: Lags of every channel in the one-step prediction of test (a).
PREDICTION_LAGS = 4

#: Lags of each channel in the one-step prediction of test (b).
WAVE_LAGS = 8

#: Lag window (s) of the portmanteau statistic of test (b).
WAVE_LAG_WINDOW = (0.2, 3.0)

#: Test (b) threshold on the standardised portmanteau statistic. Over 100 simulated 300-s records per regime: sensor noise
#: alone -1.2 to 3.5; waves and sensor noise 89 to 157 (waves with noise-free sensors 7 to 62, noise-free 245 to
#: 310: there test (a) decides). 10 is ten standard deviations of the white-residual null.
WAVE_Z_MIN = 10.0

#: Test (a) threshold on the relative one-step prediction residual. Over 100 simulated 300-s records per regime: noise-free
#: sensors give levels 1.03e-3 to 1.17e-3 with waves, 3.3e-4 to 3.7e-4 without; the sensors and both regimes (gyro
#: noise 0.002 rad/s) 1.51e-2 to 1.77e-2 and 1.81e-2 to 1.97e-2. The threshold is near the geometric mean of
#: 1.2e-3 and 1.5e-2.
SENSOR_NOISE_MIN = 4e-3

_CHANNELS = ("p", "a_s", "r", "delta")
_TESTED = ("p", "r")


def _lagged(x: dict, chans, lags: int) -> np.ndarray:
    """Regressors of a one-step prediction: a constant and lags ``1..lags`` of each channel of ``chans``
    (``x[k]`` equal-length arrays), rows ``k = lags .. N-1`` (filled row by row by :func:`_fill_lagged`)."""
    N = x[chans[0]].size
    X = np.empty((N - lags, len(chans) * lags + 1))
    _fill_lagged(np.stack([np.asarray(x[k], dtype=float) for k in chans]), lags, X)
    return X


@njit(cache=True)
def _fill_lagged(xs, lags, X):
    """``X[r] = [1, xs[0, r + lags - 1], .., xs[0, r], xs[1, r + lags - 1], ..]``: row ``r`` holds the constant and
    lags ``1..lags`` of each row of ``xs`` at sample ``r + lags`` (copies only, in the memory order of ``X``)."""
    for r in range(X.shape[0]):
        X[r, 0] = 1.0
        c = 1
        for k in range(xs.shape[0]):
            for j in range(1, lags + 1):
                X[r, c] = xs[k, r + lags - j]
                c += 1


def _ls_residual(X: np.ndarray, Gs: np.ndarray, d: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``y - X beta`` of the least-squares ``beta``, from the normal equations scaled to unit diagonal (``Gs = X^T
    X / (d d^T)``, ``d = sqrt(diag X^T X)``; least squares on ``X`` if singular)."""
    try:
        beta = np.linalg.solve(Gs, (X.T @ y) / d) / d
    except np.linalg.LinAlgError:
        beta = np.linalg.lstsq(X, y, rcond=None)[0]
    return y - X @ beta


def _scaled_normal(X: np.ndarray):
    """``(X^T X / (d d^T), d)`` with ``d = sqrt(diag X^T X)``: the normal matrix of :func:`_ls_residual`."""
    G = X.T @ X
    d = np.sqrt(np.maximum(np.diag(G), 1e-300))
    return G / np.outer(d, d), d


def prediction_residual(sig: dict, lags: int = PREDICTION_LAGS) -> dict:
    """Relative RMS residual of the one-step linear prediction of each gyro channel (test (a) of the module
    docstring) for one dataset: ``{"p": s_p, "r": s_r}``. ``sig`` maps ``p, a_s, r, delta`` to equal-length
    arrays. The normal equations are solved after scaling to unit diagonal (float64; the regressors are
    well conditioned at the sample rates used); a constant column absorbs the sensor biases."""
    x = {k: np.asarray(sig[k], dtype=float) for k in _CHANNELS}
    if x["p"].size <= 4 * (len(_CHANNELS) * lags + 1):
        return {k: float("nan") for k in _TESTED}
    X = _lagged(x, _CHANNELS, lags)
    Gs, d = _scaled_normal(X)
    out = {}
    for k in _TESTED:
        y = x[k][lags:]
        sd = float(np.std(y))
        if not sd > 0:
            out[k] = float("nan")
            continue
        e = _ls_residual(X, Gs, d, y)
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


def _residual_p(x: dict, chans, lags: int) -> np.ndarray:
    """Residual of the least-squares one-step prediction of ``p`` from lags ``1..lags`` of ``chans`` and a
    constant (normal equations scaled to unit diagonal)."""
    X = _lagged(x, chans, lags)
    return _ls_residual(X, *_scaled_normal(X), x["p"][lags:])


def portmanteau_z(e: np.ndarray, lo: int, hi: int) -> float:
    """Standardised Ljung–Box statistic ``(Q - L)/sqrt(2 L)`` of ``e`` over lags ``lo..hi`` (autocorrelation by
    FFT)."""
    e = np.asarray(e, dtype=float) - np.mean(e)
    n = e.size
    hi = min(hi, n // 4)
    if hi < lo or not np.dot(e, e) > 0:
        return float("nan")
    m = 1 << int(np.ceil(np.log2(2 * n)))
    f = np.fft.rfft(e, m)
    a = np.fft.irfft(f * np.conj(f), m)[:hi + 1]
    lags = np.arange(lo, hi + 1)
    rho = a[lo:hi + 1] / a[0]
    Q = n * (n + 2) * float(np.sum(rho * rho / (n - lags)))
    return float((Q - lags.size) / np.sqrt(2.0 * lags.size))


def wave_colour(datasets) -> dict:
    """Test (b) over all datasets (``[(condition, trial), ...]``): ``level`` (the smallest ``z``), ``per_dataset``
    and ``detected`` (``level > WAVE_Z_MIN``)."""
    per = []
    for _cond, tr in datasets:
        x = {k: np.asarray(tr[k], dtype=float) for k in ("p", "r", "delta")}
        t = np.asarray(tr.t, dtype=float)
        T = float((t[-1] - t[0]) / (t.size - 1)) if t.size > 1 else float("nan")
        if x["p"].size <= 8 * (3 * WAVE_LAGS + 1) or not T > 0:
            per.append(float("nan"))
            continue
        lo, hi = (max(int(round(s / T)), WAVE_LAGS + 1) for s in WAVE_LAG_WINDOW)
        per.append(portmanteau_z(_residual_p(x, ("p", "r", "delta"), WAVE_LAGS), lo, hi))
    vals = [v for v in per if np.isfinite(v)]
    level = float(min(vals)) if vals else float("nan")
    return {"level": level, "threshold": WAVE_Z_MIN, "detected": bool(vals) and level > WAVE_Z_MIN,
            "per_dataset": per}


def choose(datasets, result, z_f) -> tuple[str, dict]:
    """The rule of the module docstring: ``(engine, record)``, engine ``"none"`` or :func:`auto_engine`'s; the
    record (for ``diagnostics["refine"]``) holds the decision, its reason and both tests. ``result`` is Algorithm
    1's result (the present tests read the data only; an engine's rule may read it)."""
    with one_blas_thread():           # the statistics the same bits on any core count (long X^T X, dot products)
        sens = sensor_noise_level(datasets)
        wav = wave_colour(datasets)
    if z_f is None:
        engine, why = "none", "z_f not known"
    elif not sens["detected"]:
        engine, why = "none", "no sensor noise detected: Algorithm 1 kept"
    elif not wav["detected"]:
        engine, why = "none", "no wave colour detected: Algorithm 1 kept"
    else:
        engine, why = auto_engine(datasets), "sensor noise and wave structure detected"
    rec = {"mode": "auto", "decision": engine, "decision_reason": why,
           "sensor_test": {k: sens[k] for k in ("level", "threshold", "detected")},
           "wave_test": {k: wav[k] for k in ("level", "threshold", "detected")}}
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
    if out.diagnostics["refine"].get("applied"):
        rejudge(out, known, z_f)
    return out


def rejudge(result, known, z_f: float) -> None:
    """Judge plausibility again on the refined estimate, in place.

    Algorithm 1's result carries the :func:`~shipid.methods.masscm.plausibility.judge` of Algorithm 1's ``theta``
    (``implausible``, ``implausible_reasons``, ``nuisance_outside_physical`` and its warning line); after a
    refinement the estimates are the refinement's, so they are judged by the same function (m, zm_bar with their
    refined standard errors), the previous judgement's warning lines (those it writes, from the stored reasons) and labels are
    replaced by the new one's (an estimate Algorithm 1 left implausible but the refinement makes plausible is an
    estimate again); Algorithm 1's judgement is kept
    in ``diagnostics["refine"]["algorithm1_plausibility"]``. Judging twice replaces the first refined judgement.
    """
    d, est = result.diagnostics, result.estimates
    theta = np.array([float(z_f) if n == "z_f" else est[n].value for n in THETA_NAMES])
    conds = list(result.model.get("conditions") or [])
    verdict = judge(theta, known, conds, {"m": est["m"].std, "zm_bar": est["zm_bar"].std}, refined=True)
    previous = Judgement(list(d.get("implausible_reasons") or []), list(d.get("nuisance_outside_physical") or []),
                         refined="algorithm1_plausibility" in d["refine"])
    d["refine"].setdefault("algorithm1_plausibility", {k: d.get(k) for k in ("implausible", "implausible_reasons",
                                                                             "nuisance_outside_physical")})
    warn = list(d.get("warnings", []))
    for w in previous.warnings():
        if w in warn:
            warn.remove(w)
    result.estimates.update(verdict.mark(previous.unmark(est)))
    d.update({**verdict.diagnostics(), "warnings": warn + verdict.warnings()})


__all__ = ["REFINE_MODES", "ENGINES", "apply", "rejudge", "AUTO_ENGINES", "EXACT_MAX_SAMPLES", "auto_engine",
           "PREDICTION_LAGS", "SENSOR_NOISE_MIN", "prediction_residual", "sensor_noise_level", "WAVE_LAGS",
           "WAVE_LAG_WINDOW", "WAVE_Z_MIN", "portmanteau_z", "wave_colour", "choose"]
