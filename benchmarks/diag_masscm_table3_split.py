"""Diagnostic (not a timing benchmark against a peer): where the CPU time of one Table-3 run goes.

Runs the Table-3 study in this process (:func:`shipid.methods.masscm.study.run_one`, z_f known, init "given",
data seed 0, campaign seed 0, runs 1 .. RUNS, one BLAS thread) twice: once plain (the CPU time per run), once
with every compiled kernel and LAPACK call of the fast path wrapped by a CPU-time counter (replaced in the
modules that call them, in this process only): the steps of :mod:`shipid.methods.masscm.step` (equation
error, AR fit, closed-loop instruments, FIR prefilter, lag products, delayed-y columns), the compression of
:func:`shipid.estimate.iv.iv_compress_products_compiled` (``np.linalg.eigh``, ``project_qr``) and the searches
and maps of :mod:`shipid.methods.masscm.criterion` / :mod:`~shipid.methods.masscm.iteration`. Printed: ms per
run of each part, their sum, and the rest (Python between the kernels, with the counters' own cost, about 1 µs
per call), each against the flop floor of ``bench_masscm_table3_peer.py`` (98 Mflop per run at the
single-thread DGEMM rate measured here, CPU clock). The sum of the kernels is what a run costs with no Python
at all, the bound of any change that keeps the kernels' arithmetic (and so the answers, bit for bit).

Then the eigen-decompositions alone, on the Gram matrices ``Z^T Z`` of the first runs (captured from the
wrapped ``eigh``): µs per matrix by numpy's ``eigh`` one at a time (the package), by one stacked
``np.linalg.eigh`` call, by scipy's ``dsyevd`` and ``dsyevr``, whether each gives numpy's numbers bit for bit,
and the smallest eigenvalues relative to the largest (where the rank rule's threshold 1e-12 falls).

Usage:  python benchmarks/diag_masscm_table3_split.py [RUNS=300]
        python benchmarks/diag_masscm_table3_split.py --smoke     (3 runs)
"""

import os

for _v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from scipy.linalg import lapack  # noqa: E402

import shipid.estimate.iv as iv  # noqa: E402
import shipid.methods.masscm.criterion as criterion  # noqa: E402
import shipid.methods.masscm.iteration as iteration  # noqa: E402
import shipid.methods.masscm.step as step  # noqa: E402
from shipid.methods.masscm.study import run_one  # noqa: E402

FLOPS_PER_RUN = 98e6           # the estimate of bench_masscm_table3_peer.py
GRAMS: list = []
CPU: dict = {}
CALLS: dict = {}


def _wrap(mod, name: str, label: str, capture: bool = False):
    fn = getattr(mod, name)

    def timed(*args, **kwargs):
        t0 = time.process_time()
        out = fn(*args, **kwargs)
        CPU[label] = CPU.get(label, 0.0) + time.process_time() - t0
        CALLS[label] = CALLS.get(label, 0) + 1
        if capture and len(GRAMS) < 300:
            GRAMS.append(np.array(args[0]))
        return out

    setattr(mod, name, timed)
    return fn


def _dgemm_rate() -> float:
    a, b = np.random.default_rng(0).standard_normal((2, 512, 512))
    a @ b
    best = float("inf")
    for _ in range(5):
        t0 = time.process_time()
        for _ in range(10):
            a @ b
        best = min(best, (time.process_time() - t0) / 10)
    return 2 * 512 ** 3 / best


def _runs(n: int) -> float:
    t0 = time.process_time()
    for i in range(1, n + 1):
        run_one(i, 0)
    return (time.process_time() - t0) / n


def main():
    runs = 3 if "--smoke" in sys.argv else int(sys.argv[1]) if len(sys.argv) > 1 else 300
    run_one(0, 0)                                         # compile / load the kernels, build the datasets
    plain = _runs(runs)
    parts = [(step, "equation_error", "equation error (42)"), (step, "ar_fit", "AR fit (43)"),
             (step, "instrument_signals", "closed-loop instruments (46)-(47)"),
             (step, "fir_filter", "FIR prefilter, 8 signals"), (step, "lag_moments", "lag products Z^T Z, Z^T T"),
             (step, "instrument_products", "delayed-y columns"), (iv, "project_qr", "projection + QR"),
             (criterion, "gauss_newton_compiled", "searches (GN)"), (criterion, "levenberg_marquardt", "searches (LM)"),
             (criterion, "g_and_jac", "map (33)"), (iteration, "sim_terms", "instrument terms")]
    originals = [(m, n, _wrap(m, n, lab)) for m, n, lab in parts]
    eigh = _wrap(np.linalg, "eigh", "eigh (LAPACK dsyevd, 50 x 50)", capture=True)   # iv looks it up per call
    try:
        wrapped = _runs(runs)
    finally:
        np.linalg.eigh = eigh
        for m, n, fn in originals:
            setattr(m, n, fn)
    floor = FLOPS_PER_RUN / _dgemm_rate()
    print(f"Table 3, {runs} runs in one process (z_f known, init given, seeds 0), one BLAS thread, CPU time; "
          f"flop floor {1e3 * floor:.2f} ms/run")
    print(f"  plain run: {1e3 * plain:.2f} ms/run = {plain / floor:.2f} x the floor; with the counters "
          f"{1e3 * wrapped:.2f} ms/run")
    total = 0.0
    for label, t in sorted(CPU.items(), key=lambda kv: -kv[1]):
        total += t
        print(f"  {label:36s} {1e3 * t / runs:6.3f} ms/run  ({CALLS[label] / runs:5.1f} calls/run, "
              f"{1e6 * t / CALLS[label]:6.1f} us/call)")
    rest = wrapped - total / runs
    print(f"  kernels and LAPACK together: {1e3 * total / runs:.2f} ms/run = {total / runs / floor:.2f} x the floor "
          f"(a run without any Python); the rest {1e3 * rest:.2f} ms/run")
    A = np.array(GRAMS[:300 if runs > 3 else 10])
    reps = 2 if runs <= 3 else 10

    def per_matrix(f) -> float:
        f()
        t0 = time.process_time()
        for _ in range(reps):
            f()
        return (time.process_time() - t0) / reps / len(A) * 1e6

    ref = [np.linalg.eigh(a) for a in A]
    stacked = np.linalg.eigh(A)
    evd = [lapack.dsyevd(a, lower=1)[:2] for a in A]
    evr = [lapack.dsyevr(a, lower=1)[:2] for a in A]

    def same(out):
        return all(np.array_equal(w, r[0]) and np.array_equal(v, r[1]) for (w, v), r in zip(out, ref))

    print(f"eigen-decompositions of {len(A)} Gram matrices of these runs (us per matrix; bit-identical to "
          f"numpy's eigh one at a time):")
    print(f"  numpy eigh, one call each {per_matrix(lambda: [np.linalg.eigh(a) for a in A]):7.1f}")
    print(f"  numpy eigh, one stacked call {per_matrix(lambda: np.linalg.eigh(A)):7.1f}  "
          f"{same(list(zip(stacked[0], stacked[1])))}")
    print(f"  scipy dsyevd {per_matrix(lambda: [lapack.dsyevd(a, lower=1) for a in A]):7.1f}  {same(evd)}")
    print(f"  scipy dsyevr {per_matrix(lambda: [lapack.dsyevr(a, lower=1) for a in A]):7.1f}  {same(evr)}")
    rel = np.array([w / w[-1] for w, _ in ref])[:, :16]
    print("  the 16 smallest eigenvalues over the largest (median, min, max over the matrices; the rank rule drops "
          "those below 1e-12):")
    for q, name in ((np.median, "median"), (np.min, "min"), (np.max, "max")):
        print(f"    {name:6s} " + " ".join(f"{x:8.1e}" for x in q(rel, axis=0)))


if __name__ == "__main__":
    main()
