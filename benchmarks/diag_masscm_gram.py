"""Diagnostic (not a timing benchmark): cheaper factorisations of the IV Gram matrix in the Table-3 study.

Step B(c) of Algorithm 1 (Linder et al. 2015, eqs. 40-41) compresses the IV moments of each dataset with
``Q = (Z^T Z)^-1``; :func:`shipid.estimate.iv.iv_compress_products_compiled` does it by the eigen-decomposition
of the 50 x 50 ``Z^T Z`` and drops the directions with eigenvalues below 1e-12 of the largest (the rank rule).
This script runs the Table-3 study in this process (:func:`shipid.methods.masscm.study.run_one`, z_f known,
init "given", data seed 0, campaign seed 0, runs 0 .. RUNS-1) once per rule, the rule injected by replacing
``shipid.methods.masscm.iteration.iv_compress_products_compiled`` in this process only (nothing in the package
changes):

* ``eigh``: the package's rule; also counts how many directions each decomposition keeps (one more
  ``eigvalsh`` per decomposition, included in its time);
* ``ridge``: Cholesky of ``Z^T Z + 1e-12 tr(Z^T Z) I`` (Tikhonov instead of truncation), then the same QR;
* ``pivoted``: LAPACK's pivoted Cholesky (``dpstrf``, tolerance 1e-12 of the largest diagonal entry), the IV
  criterion of the instruments it selects.

Printed per rule: CPU ms per run (the rules other than ``eigh`` in numpy/scipy, not compiled), mean iterations,
flagged runs, and mean / std over the runs of the nine parameters with the digits (5 / 3 significant) of
``shipid study mass-cm-sensitivity``; then the largest per-run difference from ``eigh``.

Usage:  python benchmarks/diag_masscm_gram.py [RUNS=2000] [RULES=eigh,ridge,pivoted]
        python benchmarks/diag_masscm_gram.py --smoke     (3 runs, every rule)
"""

import sys
import time
import warnings

import numpy as np
import scipy.linalg as sl
from scipy.linalg import lapack

import shipid.methods.masscm.iteration as iteration
from shipid.estimate.iv import IVMoments, iv_compress_products_compiled
from shipid.methods.masscm.study import TABLE3_ORDER, run_one, summarise, warm_up

KEPT: list[int] = []


def _moments(Rq: np.ndarray, nc: int, n: int, rank: int) -> IVMoments:
    Rf = np.zeros((nc, nc))
    Rf[:Rq.shape[0]] = Rq
    ng = nc - 1
    return IVMoments(R=Rf[:ng, :ng].copy(), r=Rf[:ng, ng].copy(), rss0=float(Rf[ng, ng] ** 2), n=n,
                     rank_ok=rank >= ng)


def eigh(ZtZ, ZtP, n, rtol=1e-12):
    s = np.linalg.eigvalsh(ZtZ)
    KEPT.append(int(np.sum(s > rtol * max(s[-1], 1e-300))))
    return iv_compress_products_compiled(ZtZ, ZtP, n, rtol)


def ridge(ZtZ, ZtP, n, rtol=1e-12):
    L = np.linalg.cholesky(ZtZ + rtol * np.trace(ZtZ) * np.eye(ZtZ.shape[0]))
    P = sl.solve_triangular(L, ZtP, lower=True)
    return _moments(np.linalg.qr(P, mode="r"), ZtP.shape[1], n, ZtZ.shape[0])


def pivoted(ZtZ, ZtP, n, rtol=1e-12):
    c, piv, rank, _info = lapack.dpstrf(ZtZ, lower=1, tol=rtol * np.max(np.diag(ZtZ)))
    L = np.tril(c)[:rank, :rank]
    P = sl.solve_triangular(L, ZtP[piv[:rank] - 1], lower=True)
    return _moments(np.linalg.qr(P, mode="r"), ZtP.shape[1], n, rank)


RULES = {"eigh": eigh, "ridge": ridge, "pivoted": pivoted}


def main():
    smoke = "--smoke" in sys.argv
    argv = [a for a in sys.argv[1:] if a != "--smoke"]
    runs = 3 if smoke else int(argv[0]) if argv else 2000
    rules = list(RULES) if smoke or len(argv) < 2 else argv[1].split(",")
    warnings.simplefilter("ignore")
    warm_up()
    print(f"Table 3 (z_f known, init given, data seed 0, seed 0), runs 0..{runs - 1}, in one process")
    theta = {}
    for name in rules:
        iteration.iv_compress_products_compiled = RULES[name]
        KEPT.clear()
        t0 = time.process_time()
        outs = [run_one(i, 0) for i in range(runs)]
        cpu = (time.process_time() - t0) / runs
        iteration.iv_compress_products_compiled = iv_compress_products_compiled
        s = summarise(outs)
        theta[name] = np.array([[o[p] for p in TABLE3_ORDER] for o in outs])
        print(f"{name}: {1e3 * cpu:.2f} ms/run CPU, {s['mean_iterations']:.3f} iterations on average, "
              f"{s['flagged']} of {runs} flagged")
        if KEPT:
            kept, count = np.unique(KEPT, return_counts=True)
            print(f"  directions kept of 50 by the rank rule, over {len(KEPT)} decompositions: "
                  + ", ".join(f"{k}: {c}" for k, c in zip(kept, count)))
        print("  " + "; ".join(f"{p} {s['parameters'][p]['mean']:.5g} ± {s['parameters'][p]['std']:.3g}"
                               for p in TABLE3_ORDER))
    if "eigh" in theta:
        for name in theta:
            if name != "eigh":
                d = np.max(np.abs(theta[name] - theta["eigh"]), axis=0)
                print(f"largest per-run |{name} - eigh|: " + ", ".join(f"{p} {x:.2g}" for p, x in zip(TABLE3_ORDER, d)))


if __name__ == "__main__":
    main()
