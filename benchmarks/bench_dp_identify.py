"""Benchmark: ``identify dp`` with estimated noise and observed information vs the EKF alone, same run.

Six simulated trials (surge ×2, sway–yaw ×2, azimuth ×2, ``--duration`` s each, 1 Hz or ``--dt``; the
noise of :func:`shipid.methods.dp.coverage.study_noise` at nominal scales). Timed, on one
thread (BLAS/numba threads set to 1 before NumPy is imported):

* ``observed`` — :func:`shipid.methods.dp.estimator.identify_dp` with its defaults (EKF passes, then the
  likelihood maximisation over θ and the noise levels and the Hessian, :mod:`shipid.methods.dp.pem`);
* ``ekf`` — the same with ``covariance="ekf"`` (the paper's method, two EKF passes per scheme,
  noise levels assumed): the method before issue 15;
* ``floor`` — ``covariance="ekf", passes=1``: one EKF pass per scheme, the least any
  EKF-based identification of these trials can cost.

Prints seconds and the ratios observed/ekf and observed/floor. The numba kernels are compiled
(or loaded from the cache) before timing. Target: observed ≤ 60 s on one core.

Run: ``python benchmarks/bench_dp_identify.py [--duration 1500] [--seed 5] [--repeat 1] [--dt 0.1] [--smoke]``
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse  # noqa: E402
import time  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=1500.0)
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--smoke", action="store_true",
                    help="120-s trials, the two EKF modes only (the test suite's smoke test; observed takes a minute)")
    ap.add_argument("--dt", type=float, default=1.0, help="sample interval of the trials, s (0.1: a 10-Hz logger)")
    args = ap.parse_args()
    if args.smoke:
        args.duration, args.repeat = 120.0, 1

    import numpy as np

    import shipid.methods.dp.loglik  # noqa: F401  (compile / load the kernels before timing)
    from shipid.methods.dp.estimator import DPOptions, identify_dp
    from shipid.methods.dp.coverage import study_noise
    from shipid.methods.dp.trials import simulate_dp_trials
    from shipid.models.dp import dp_vessel
    from shipid.vessels import load_vessel

    v = dp_vessel(load_vessel("supply"))
    tr = simulate_dp_trials(v, args.seed, duration=args.duration, noise=study_noise(1.0, 1.0), dt=args.dt)
    modes = {"observed": DPOptions(), "ekf": DPOptions(covariance="ekf"),
             "floor": DPOptions(covariance="ekf", passes=1)}
    if args.smoke:
        del modes["observed"]
    best = {}
    for name, opt in modes.items():
        ts = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            res = identify_dp(tr["surge"], tr["sway-yaw"], tr["azimuth"], v, opt, theta_true=v.theta)
            ts.append(time.perf_counter() - t0)
        best[name] = min(ts)
        es = np.asarray(res.diagnostics["error_sigma"])
        stages = ", ".join(f"{k} {s['seconds']:.1f} s" for k, s in res.diagnostics["stages"].items())
        print(f"{name:9s} {best[name]:7.2f} s  ({stages}); max |error|/std {np.max(np.abs(es)):.2f}")
    if args.smoke:
        print(f"six {args.duration:.0f}-s trials: ekf / floor = {best['ekf'] / best['floor']:.2f} (smoke: no observed)")
        return
    print(f"six {args.duration:.0f}-s trials at {1 / args.dt:g} Hz: observed / ekf = {best['observed'] / best['ekf']:.2f}, "
          f"observed / floor = {best['observed'] / best['floor']:.2f}; target observed <= 60 s: "
          f"{'met' if best['observed'] <= 60 else 'NOT met'}")


if __name__ == "__main__":
    main()
