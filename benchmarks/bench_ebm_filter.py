"""Benchmark: EBM step 1 (17-state CD-EKF + smoother) against filterpy in the same run.

Peer: filterpy 2.0 ``ExtendedKalmanFilter`` (predict/update per sample, with the
same Φ, Q_d and RK4 state propagation supplied to it, since filterpy has no
continuous–discrete filter) followed by ``KalmanFilter.rts_smoother`` on filterpy's
conventions (linear prediction ``F x`` in the backward pass).

Ours, two paths:

* compiled — :func:`shipid.methods.ebm.compiled.ebm_cd_ekf` +
  :func:`~shipid.methods.ebm.compiled.mbf_smoother_fast` (numba, what
  :func:`shipid.methods.ebm.estimator.estimate_states` uses);
* reference — :func:`shipid.estimate.cd_ekf.cd_ekf` + :func:`~shipid.estimate.smoothers.mbf_smoother`
  (pure Python/numpy, the definition the compiled path is tested against).

Timings are the best of ``--repeat`` runs of process CPU time (``--clock wall`` for wall
time; every contender is single-threaded), the contenders interleaved so that load
from other processes hits them alike; the machine's load average is printed
(timings on a shared machine are noisy; the ratios measured in the same run are what
count). Then the cost versus data length: both the compiled path and the peer at
several trial durations, ms per sample and the exponent of a log–log fit
(1 = linear).

Run: ``.venv/bin/python benchmarks/bench_ebm_filter.py [--duration 1200] [--repeat 5]
[--lengths 300 600 1200 2400]``
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np


def _problem(duration: float):
    from shipid.methods.ebm.estimator import EbmConfig, measurements, prior_cov, process_noise
    from shipid.methods.ebm.trials import simulate_trial
    from shipid.models import abkowitz as ab
    from shipid.models.ebm_state import EbmModel, initial_state, measurement_noise

    tr = simulate_trial("zigzag-20", duration, seed=0)
    p = ab.params_from_vessel()
    tc = ab.trial_conditions()
    cfg = EbmConfig(rudder_q_gain=0.0)
    model = EbmModel.from_abkowitz(p, tc["x_D"], tc["y_D"], tc["y_S"], q_force=cfg.q_force, q_current=cfg.q_current)
    Q = process_noise(model, tr["delta"], cfg)
    R = measurement_noise(tc["sigma_xy"], tc["sigma_xy_dot"], tc["sigma_psi"], tc["sigma_u_log"])
    z = measurements(tr)
    t = tr.t - tr.t[0]
    x0 = initial_state(z[0], model)
    P0 = prior_cov(False)
    return tr, model, Q, R, t, z, x0, P0


def _contenders(model, Q, R, t, z, x0, P0):
    from filterpy.kalman import ExtendedKalmanFilter, KalmanFilter

    from shipid.estimate.cd_ekf import cd_ekf, rk4_propagate, taylor_discretise
    from shipid.methods.ebm.compiled import ebm_cd_ekf, mbf_smoother_fast
    from shipid.estimate.smoothers import mbf_smoother

    N = t.size

    def fast():
        fr = ebm_cd_ekf(model, Q, R, t, z, x0, P0)
        return fr, mbf_smoother_fast(fr)

    def reference():
        fr = cd_ekf(model.f, model.F, model.h, model.H, Q, R, t, z, x0, P0)
        return fr, mbf_smoother(fr)

    def peer():
        ekf = ExtendedKalmanFilter(dim_x=17, dim_z=6)
        ekf.x = x0.copy()
        ekf.P = P0.copy()
        ekf.R = R
        Xs = np.empty((N, 17)); Ps = np.empty((N, 17, 17))
        Fs = np.empty((N, 17, 17)); Qs = np.empty((N, 17, 17))
        for k in range(N):
            if k > 0:
                h = t[k] - t[k - 1]
                Phi, Qd = taylor_discretise(model.F(t[k - 1], ekf.x), Q, h)
                ekf.F = Phi
                ekf.Q = Qd
                ekf.x = rk4_propagate(model.f, t[k - 1], ekf.x, h)  # nonlinear predict_x
                ekf.P = Phi @ ekf.P @ Phi.T + Qd
                Fs[k - 1], Qs[k - 1] = Phi, Qd
            ekf.update(z[k], lambda x, tk: model.H(tk, x), lambda x, tk: model.h(tk, x),
                       args=(t[k],), hx_args=(t[k],))
            Xs[k] = ekf.x
            Ps[k] = ekf.P
        Fs[-1], Qs[-1] = np.eye(17), np.zeros((17, 17))
        kf = KalmanFilter(dim_x=17, dim_z=6)
        xs, ps, _, _ = kf.rts_smoother(Xs, Ps, Fs, Qs)
        return Xs, xs

    return {"fast": fast, "reference": reference, "peer": peer}


CLOCK = time.process_time  # set by --clock


def _best(fns: dict, repeat: int) -> tuple[dict, dict]:
    times = {k: [] for k in fns}
    outs = {}
    for _ in range(repeat):
        for k, fn in fns.items():
            t0 = CLOCK()
            outs[k] = fn()
            times[k].append(CLOCK() - t0)
    return {k: min(v) for k, v in times.items()}, outs


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=1200.0)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--lengths", type=float, nargs="*", default=[300.0, 600.0, 1200.0, 2400.0])
    ap.add_argument("--clock", choices=("cpu", "wall"), default="cpu",
                    help="process CPU time (default: on a shared machine it is what the computation costs, "
                         "all single-threaded here) or wall time")
    ap.add_argument("--smoke", action="store_true", help="one 120-s run, two lengths (the test suite's smoke test)")
    args = ap.parse_args()
    if args.smoke:
        args.duration, args.repeat, args.lengths = 120.0, 1, [60.0, 120.0]
    global CLOCK
    CLOCK = time.process_time if args.clock == "cpu" else time.perf_counter

    from shipid.estimate.smoothers import rts_smoother

    print(f"load average at start: {os.getloadavg()}")
    t0 = time.perf_counter()
    import shipid.methods.ebm.compiled as fast_mod
    tr, model, Q, R, t, z, x0, P0 = _problem(args.duration)
    fast_mod.mbf_smoother_fast(fast_mod.ebm_cd_ekf(model, Q, R, t[:5], z[:5], x0, P0))
    print(f"compiled path ready in {time.perf_counter() - t0:.2f} s (import + numba cache load, "
          "or compile on the first run on a machine; not in the timings below)")
    N = t.size
    fns = _contenders(model, Q, R, t, z, x0, P0)
    best, outs = _best(fns, args.repeat)
    fr, mbf = outs["fast"]
    fr_ref, mbf_ref = outs["reference"]
    Xf_peer, Xs_peer = outs["peer"]
    rts = rts_smoother(fr)
    scale = np.array([1, 1, 1e-3, 10, 10, 1e-3, 1e6, 1e4, 1e2, 1e6, 1e4, 1e2, 1e8, 1e6, 1e4, 1, 1])
    dfilt = np.max(np.abs(fr.x_filt - Xf_peer) / scale)
    def relmax(a, b):  # per state, relative to the largest magnitude of that state in the reference
        return float(np.max(np.abs(a - b).max(axis=0) / np.maximum(np.abs(b).max(axis=0), 1e-300)))

    dref = max(relmax(fr.x_filt, fr_ref.x_filt), relmax(mbf.x, mbf_ref.x))
    dmr = np.max(np.abs(mbf.x - rts.x) / scale)

    def rms(a, key):
        return float(np.sqrt(np.mean((a - tr[key]) ** 2)))

    print(f"EBM step 1, 17 states, {N} samples (zig-zag 20/20, {args.duration:g} s), best of {args.repeat}, "
          f"{args.clock} time")
    for lab, key in (("shipid compiled EKF + MBF  ", "fast"), ("shipid reference EKF + MBF ", "reference"),
                     ("filterpy EKF + rts_smoother", "peer")):
        print(f"  {lab}: {best[key]:8.4f} s  ({1e3 * best[key] / N:.4f} ms/sample)")
    print(f"  ratio filterpy / shipid compiled  : {best['peer'] / best['fast']:8.2f}   (goal >= 5)")
    print(f"  ratio filterpy / shipid reference : {best['peer'] / best['reference']:8.2f}   (the path before)")
    print(f"  compiled vs reference, max |difference| / max |state| (filtered, smoothed): {dref:.2e}")
    print(f"  filtered states, max |shipid - filterpy| / typical magnitude: {dfilt:.2e}")
    print(f"  smoothed, max |MBF - our RTS| / typical magnitude: {dmr:.2e}")
    print("  RMS error vs truth      v_r [m/s]    r [rad/s]    Y [N]")
    for lab, X in (("filter", fr.x_filt), ("shipid MBF", mbf.x), ("shipid RTS", rts.x),
                   ("filterpy RTS", Xs_peer)):
        print(f"    {lab:<14}{rms(X[:, 1], 'true_v_r'):>14.4g}{rms(X[:, 2], 'true_r'):>13.3g}"
              f"{rms(X[:, 9], 'true_Y'):>11.3g}")
    print("  (filterpy's rts_smoother predicts with F x, the linear-KF convention; for the EKF")
    print("   f(x) != F x, so its smoothed states are wrong where the model is nonlinear)")

    if args.lengths:
        print(f"\nCost versus data length (best of {args.repeat}, {args.clock} time, compiled vs filterpy "
              "interleaved)")
        print(f"  {'duration s':>10} {'samples':>8} {'compiled s':>11} {'ms/sample':>10} {'filterpy s':>11}"
              f" {'ms/sample':>10} {'ratio':>7}")
        Ns, tf, tp = [], [], []
        for d in args.lengths:
            _, model, Q, R, t, z, x0, P0 = _problem(d)
            fns = _contenders(model, Q, R, t, z, x0, P0)
            b, _ = _best({"fast": fns["fast"], "peer": fns["peer"]}, args.repeat)
            Ns.append(t.size); tf.append(b["fast"]); tp.append(b["peer"])
            print(f"  {d:>10g} {t.size:>8d} {b['fast']:>11.4f} {1e3 * b['fast'] / t.size:>10.4f} "
                  f"{b['peer']:>11.4f} {1e3 * b['peer'] / t.size:>10.4f} {b['peer'] / b['fast']:>7.2f}")
        lN = np.log(Ns)
        ef = np.polyfit(lN, np.log(tf), 1)[0]
        ep = np.polyfit(lN, np.log(tp), 1)[0]
        print(f"  fitted exponent, time ~ N^a: compiled a = {ef:.3f}, filterpy a = {ep:.3f}  (1 = linear)")
    print(f"load average at end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
