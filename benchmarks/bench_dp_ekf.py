"""Benchmark: the DP parallel augmented EKF (SI2, N = 2) against filterpy in the same run.

Peer: filterpy 2.0 ``ExtendedKalmanFilter`` driven step by step on the same stacked
augmented model (eqs. 20–25): its ``predict_x`` is overridden to propagate with the same
RK4 map, ``F`` and ``Q`` are set to the same Φ and Q each step, and ``update`` gets the
same H, R and heading-wrapping residual (filterpy also uses the Joseph form). Prints wall times, the
ratio and the largest difference of the parameter estimates (they must agree). Ours: the compiled
kernel :func:`shipid.methods.dp.fast_ekf.run_parallel` (what ``identify dp`` runs) and the Python
filter :func:`shipid.estimate.ekf_augmented.parallel_augmented_ekf`.

Run: ``.venv/bin/python benchmarks/bench_dp_ekf.py [--duration 600] [--repeat 3] [--smoke]`` (needs filterpy).
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=600.0)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--smoke", action="store_true", help="60 s trials, one round (the test suite's smoke test)")
    args = ap.parse_args()
    if args.smoke:
        args.duration, args.repeat = 60.0, 1

    from filterpy.kalman import ExtendedKalmanFilter
    from scipy.linalg import block_diag

    from shipid.estimate.ekf_augmented import parallel_augmented_ekf
    from shipid.methods.dp import estimator as m
    from shipid.methods.dp.fast_ekf import run_parallel
    from shipid.methods.dp.stage_models import momentum_model, prepare
    from shipid.methods.dp.trials import simulate_dp_trial
    from shipid.models.dp import dp_vessel
    from shipid.vessels import load_vessel

    v = dp_vessel(load_vessel("supply"))
    trials = [simulate_dp_trial(v, "sway-yaw", args.duration, 21 + j) for j in range(2)]
    opt = m.DPOptions()
    free = list(m.STAGES["SI2"])
    theta = np.array(opt.theta0)
    theta[[0, 5, 8]] = v.theta[[0, 5, 8]]
    data = [prepare(t, v, "sway-yaw") for t in trials]
    models = [momentum_model(v, theta, free, d["t"], False) for d in data]
    b = v.bis
    sp = opt.sigma_pos / b.L
    a2 = np.array([1.0, 1.0, opt.yaw_arm ** 2])
    P0x = np.diag(np.concatenate([[opt.h0_std ** 2] * 3, [sp ** 2, sp ** 2, opt.sigma_psi ** 2], opt.b0_std ** 2 * a2]))
    R = np.diag([sp ** 2, sp ** 2, opt.sigma_psi ** 2])
    dts = [np.diff(d["t"]) for d in data]
    Qx = [lambda k, dt=dt: np.diag(np.concatenate([opt.q_h * dt[k] * a2, np.zeros(3), opt.q_b * dt[k] * a2]))
          for dt in dts]
    th0 = theta[free]
    P0t = np.diag(np.asarray(opt.theta0_std)[free] ** 2)
    Qt = np.zeros((len(free), len(free)))
    x0 = [np.concatenate([np.zeros(3), d["Z"][0], np.zeros(3)]) for d in data]
    Z = [d["Z"] for d in data]
    U = [d["U"] for d in data]

    qdiag = np.concatenate([opt.q_h * a2, np.zeros(3), opt.q_b * a2])

    def ours():
        return run_parallel("sway-yaw", data, v, theta, free, x0, P0x, P0t, qdiag, Qt, R).theta_final

    def python_path():
        return parallel_augmented_ekf(models[0], x0, th0, P0x, P0t, Qx, Qt, R, Z, U, models=models).theta_final

    nx, p, n = 9, len(free), Z[0].shape[0]

    def peer():
        class EKF(ExtendedKalmanFilter):
            def predict_x(self, u=0):
                k = self._k
                th = self.x[2 * nx:, 0]
                xs = [models[i].f(k, self.x[i * nx:(i + 1) * nx, 0], U[i][k], th) for i in range(2)]
                self.x = np.concatenate(xs + [th])[:, None]

        f = EKF(dim_x=2 * nx + p, dim_z=6)
        f.x = np.concatenate(x0 + [th0])[:, None]
        f.P = block_diag(P0x, P0x, P0t)
        f.R = block_diag(R, R)
        H = np.zeros((6, 2 * nx + p))
        H[0:3, 3:6] = np.eye(3)
        H[3:6, nx + 3:nx + 6] = np.eye(3)

        def resid(a, bb):
            d = a - bb
            d[2] = np.arctan2(np.sin(d[2]), np.cos(d[2]))
            d[5] = np.arctan2(np.sin(d[5]), np.cos(d[5]))
            return d

        for k in range(n):
            z = np.concatenate([Z[0][k], Z[1][k]])[:, None]
            f.update(z, lambda x: H, lambda x: H @ x, residual=resid)
            if k == n - 1:
                break
            th = f.x[2 * nx:, 0]
            F = np.eye(2 * nx + p)
            for i in range(2):
                a, bb = models[i].f_jac(k, f.x[i * nx:(i + 1) * nx, 0], U[i][k], th)
                F[i * nx:(i + 1) * nx, i * nx:(i + 1) * nx] = a
                F[i * nx:(i + 1) * nx, 2 * nx:] = bb
            f.F = F
            f.Q = block_diag(Qx[0](k), Qx[1](k), Qt)
            f._k = k
            f.predict()
        return f.x[2 * nx:, 0]

    ours()  # compile (or load numba's cache) outside the timing
    t_ours, t_py, t_peer = [], [], []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        a = ours()
        t_ours.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        b2 = python_path()
        t_py.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        c = peer()
        t_peer.append(time.perf_counter() - t0)
    to, tpy, tp = np.median(t_ours), np.median(t_py), np.median(t_peer)
    print(f"SI2 parallel augmented EKF, N=2, {n} steps, state dim {2 * nx + p}, medians of {args.repeat}")
    print(f"shipid compiled (dp.fast_ekf): {to:.4f} s   shipid Python (parallel_augmented_ekf): {tpy:.3f} s   "
          f"filterpy ExtendedKalmanFilter: {tp:.3f} s")
    print(f"speed-up vs filterpy: compiled {tp / to:.1f} x, Python path {tp / tpy:.2f} x")
    print(f"max |theta_compiled - theta_python| / |theta| = {np.max(np.abs(a - b2) / np.abs(b2)):.2e}")
    print(f"max |theta_compiled - theta_filterpy| / |theta| = {np.max(np.abs(a - c) / np.abs(c)):.2e}")


if __name__ == "__main__":
    main()
