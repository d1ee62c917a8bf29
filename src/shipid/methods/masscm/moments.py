"""IV moments of one iteration of Algorithm 1 (Linder et al. 2015, eqs. 43–47).

For each dataset: the closed-loop instrument signals (46)–(47), the instrument matrix (45) of prefiltered lags
of ``y_hat`` and of the differences ``mu_hat``, the prefiltered regressors (37), and their products
``Z^T Z``, ``Z^T [Phi, y]`` compressed by :func:`shipid.estimate.iv.iv_compress_products` (the criterion (40)
as ``||R g - r||^2``). Three equivalent ways (tests compare them): the explicit instrument matrix
(:func:`instruments`, the reference), the lag structure without forming ``Z`` for any prefilter
(:func:`filtered_lag_moments`), and for a FIR prefilter ``L = A(q)`` (the AR noise model) the numpy
(:func:`fir_moments_numpy`) or compiled (:func:`fir_moments_compiled`, :mod:`shipid.estimate.fir_kernels`) path.
"""

from __future__ import annotations

import numpy as np

from shipid.estimate.fir_kernels import fir_filter, lag_moments
from shipid.numerics.iir_kernels import lfilter, lfilter_into
from shipid.estimate.iv import iv_compress, iv_compress_products, lag_gram_from, lag_matrix
from shipid.methods.masscm.data import Dataset, diff2, first_row
from shipid.methods.masscm.options import MassCMOptions
from shipid.models.roll_reduced import KnownParams, bilinear_tf

def instruments(ds: Dataset, y_hat, a_hat, r_hat, L, options: MassCMOptions) -> np.ndarray:
    """Instrument matrix (45): prefiltered lags of ``y_hat`` and of ``mu_hat`` (differences)."""
    base = np.column_stack([y_hat, diff2(a_hat), diff2(r_hat), diff2(ds.delta)])
    base = base - base.mean(axis=0)
    if L is not None:
        base = L.prefilter(base)
    s = first_row(options)
    if options.instruments == "regressors":
        # Young's refined / optimal IV: the prefiltered noise-free regressors (37) themselves
        return np.column_stack([-base[s - 1:-1, 0], -base[s - 2:-2, 0], base[s:, 1], base[s:, 2], base[s:, 3]])
    return np.column_stack([lag_matrix(base[:, 0], options.n_y, s), lag_matrix(base[:, 1], options.n_as, s),
                            lag_matrix(base[:, 2], options.n_r, s), lag_matrix(base[:, 3], options.n_delta, s)])


def closed_loop_sim(ds: Dataset, terms: dict, i: int, known: KnownParams) -> tuple[np.ndarray, np.ndarray] | None:
    """Noise-free instrument signals (46)–(47) for dataset i, or None if the model is unstable.

    With ``v'`` neglected in (20), ``a_s = z_s p' + g phi - U r`` and (18) gives
    ``(A1 s^2 + d s + k1) phi = (K_r + U B) r + K_delta delta``; ``r`` is the iteration-0 black-box
    simulation. This is (46)–(47) written with physical coefficients (``G/(1 - G F_y)``, ``F_y = z_s s + g/s``).
    """
    A1, d, k1 = terms["A1"][i], terms["d"][i], terms["k1"][i]
    if not (A1 > 0 and d > 0 and k1 > 0):
        return None
    u = terms["Kyaw"][i] * ds.r_hat0 + terms["K_delta"][i] * ds.delta
    b, a = bilinear_tf([1.0, 0.0], [A1, d, k1], ds.T)
    y_hat = lfilter(b, a, u)
    b2, a2 = bilinear_tf([terms["z_s"][i], 0.0, known.g], [A1, d, k1], ds.T)
    a_hat = lfilter(b2, a2, u) - known.U * ds.r_hat0
    return y_hat, a_hat


def fir_moments(ds: Dataset, a: np.ndarray, y_hat, a_hat, options: MassCMOptions):
    """IV moments of one dataset for a FIR prefilter ``L = A(q)`` (the AR noise model), lag instruments.

    ``options.compute == "fast"``: :func:`fir_moments_compiled`; ``"reference"``: :func:`fir_moments_numpy`.
    Both equal the general path of :func:`build_moments` to rounding (tests).
    """
    if options.compute == "fast":
        return fir_moments_compiled(ds, a, y_hat, a_hat, options)
    return fir_moments_numpy(ds, a, y_hat, a_hat, options)


def fir_moments_compiled(ds: Dataset, a: np.ndarray, y_hat, a_hat, options: MassCMOptions):
    """:func:`fir_moments_numpy` by the compiled kernels of :mod:`shipid.estimate.fir_kernels`.

    The eight distinct signals (``y_hat``, ``mu_hat`` of a_s, the iterate-independent ``mu_hat`` of r and
    the rudder difference, the three measured differences of (37) and ``y``) are filtered by one call
    (:func:`~shipid.estimate.fir_kernels.fir_filter`); the delayed-``y`` columns of (37) are the delayed
    filtered ``y``; ``Z^T Z`` and ``Z^T [Phi, y]`` come from :func:`~shipid.estimate.fir_kernels.lag_moments`
    without forming ``Z``. The compression (eigen-decomposition with the rank rule) is the same function.
    """
    s = first_row(options)
    n = ds.y.size
    X, nls = work_arrays(ds, options)
    X[0] = y_hat - y_hat.mean()
    da = diff2(a_hat)
    X[1] = da - da.mean()
    Fl = fir_filter(np.ascontiguousarray(a, dtype=float), X)
    T = np.empty((6, n))                     # Phi columns (37) then y, prefiltered
    T[0, 0], T[0, 1:] = 0.0, -Fl[7, :-1]      # the filter commutes with the delay
    T[1, :2], T[1, 2:] = 0.0, -Fl[7, :-2]
    T[2:] = Fl[4:]
    ZtZ, ZtP = lag_moments(Fl[:4], nls, T, s)
    return iv_compress_products(ZtZ, ZtP, n - s)


def work_arrays(ds: Dataset, options: MassCMOptions) -> tuple[np.ndarray, np.ndarray]:
    """Per-dataset work array of the compiled moments: rows 2..7 the iterate-independent signals
    (``mu_hat`` of the black-box r (44), the rudder difference, both mean-removed; the measured differences
    of (37); ``y``), rows 0, 1 overwritten per call; and the lags ``(n_y, n_as, n_r, n_delta)``."""
    nls = (options.n_y, options.n_as, options.n_r, options.n_delta)
    key = ("work", nls)
    if key not in ds.cache:
        X = np.empty((8, ds.y.size))
        X[0:2] = 0.0
        X[2], X[3] = input_differences(ds)
        X[4:7] = ds.Phi[:, 2:].T
        X[7] = ds.y
        ds.cache[key] = (X, np.array(nls, dtype=np.int64))
    return ds.cache[key]


def input_differences(ds: Dataset) -> tuple[np.ndarray, np.ndarray]:
    """The iterate-independent instrument signals of dataset ``ds``: ``mu_hat`` of the black-box r (44) and the
    rudder difference, both mean-removed (kept in ``ds.cache``; the other iterate-independent signals of the
    numpy paths are read from ``ds.Phi`` and ``ds.y``, not copied)."""
    c = ds.cache
    if "dr0" not in c:
        dr0, dd = diff2(ds.r_hat0), diff2(ds.delta)
        c["dr0"], c["dd"] = dr0 - dr0.mean(), dd - dd.mean()
    return c["dr0"], c["dd"]


def fir_moments_numpy(ds: Dataset, a: np.ndarray, y_hat, a_hat, options: MassCMOptions):
    """IV moments of one dataset for a FIR prefilter ``L = A(q)``, lag instruments, in numpy (reference).

    The same quantities as the general path of :func:`build_moments` (``instruments`` + prefilter +
    :func:`iv_compress`), arranged for speed: the iterate-independent signals are read from the dataset
    (:func:`input_differences`, ``Phi``, ``y``), each of the ten signals is filtered once by ``np.convolve``
    (what ``lfilter`` does for a FIR filter), and the products come from the lag structure block by block
    (:func:`lag_products`).
    """
    s = first_row(options)
    n = ds.y.size
    da = diff2(a_hat)
    sig = [y_hat - y_hat.mean(), da - da.mean(), *input_differences(ds), None, None, *ds.Phi[:, 2:].T, ds.y]
    filt = np.empty((len(sig), n))
    for k, x in enumerate(sig):
        if x is not None:
            filt[k] = np.convolve(a, x)[:n]
    # Phi columns 0, 1 are -y delayed by 1, 2 samples (37): the filter commutes with the delay
    filt[4, 0], filt[4, 1:] = 0.0, -filt[9, :-1]
    filt[5, :2], filt[5, 2:] = 0.0, -filt[9, :-2]
    nls = (options.n_y, options.n_as, options.n_r, options.n_delta)
    ZtZ, ZtP = lag_products(filt, nls, filt[4:, s:], s)      # P: Phi columns then y, prefiltered
    return iv_compress_products(ZtZ, ZtP, n - s)


#: Instruments per block of :func:`lag_products` (a multiple of the 4 x 8 tile of the BLAS product kernel, so
#: that each block's product computes every entry as the whole-matrix product does).
LAG_BLOCK = 8


def lag_products(F: np.ndarray, nls, P: np.ndarray, s: int) -> tuple[np.ndarray, np.ndarray]:
    """``Z^T Z`` and ``Z^T P^T`` of the lag instruments (45) of the rows of ``F``, rows ``t = s .. n-1``.

    Instrument ``(k, i)`` (signal after signal, lags ``i < nls[k]``) is ``F[k, t - i]``; ``P`` (n_P, n - s) the
    prefiltered regressors and output on the same rows. The products are those of the explicit ``Z^T``
    (``n_z x (n - s)``, the reference :func:`instruments`), formed :data:`LAG_BLOCK` instruments at a time:
    the same dot products by the same BLAS calls on row blocks aligned as the whole matrix's, without
    holding ``Z`` (at one hour of 50 Hz data ``Z^T`` is 72 MB, a block 12 MB). ``Z^T Z`` from the lag-0
    products by :func:`shipid.estimate.iv.lag_gram_from`.
    """
    n = F.shape[1]
    m = n - s
    idx = [(k, i) for k, nl in enumerate(nls) for i in range(nl)]
    used = tuple(nl for nl in nls if nl)
    nz = len(idx)
    A = np.ascontiguousarray(F[[k for k, nl in enumerate(nls) if nl], s:])     # the lag-0 rows of Z^T
    F0 = np.empty((A.shape[0], nz))
    ZtP = np.empty((nz, P.shape[0]))
    W = np.empty((min(LAG_BLOCK, nz), m))
    for g0 in range(0, nz, LAG_BLOCK):
        rows = idx[g0:g0 + LAG_BLOCK]
        Wb = W[:len(rows)]
        for r, (k, i) in enumerate(rows):
            Wb[r] = F[k, s - i:n - i]
        ZtP[g0:g0 + len(rows)] = Wb @ P.T
        F0[:, g0:g0 + len(rows)] = A @ Wb.T
    h = np.array([F[k, s - 1 - i] for k, i in idx])
    e = np.array([F[k, n - 1 - i] for k, i in idx])
    return lag_gram_from(F0, h, e, used), ZtP


def filtered_lag_moments(ds: Dataset, L, y_hat, a_hat, options: MassCMOptions):
    """IV moments of one dataset for any prefilter ``L`` (or none), lag instruments, without forming ``Z``.

    The same quantities as the explicit path (:func:`instruments`, prefilter, transient drop
    :func:`transient_length`, :func:`iv_compress`; tests compare them): the eight distinct signals are
    prefiltered once, from rest, by :func:`shipid.numerics.iir_kernels.lfilter_into` (the numbers of
    ``scipy.signal.lfilter``), the four instrument signals into one array and the three measured differences
    of (37) and ``y`` into the array of the regressors; the two delayed-``y`` columns of (37) are the delayed
    filtered ``y`` (the filter commutes with the delay), and ``Z^T Z``, ``Z^T [Phi, y]`` come from the lag
    structure by the compiled :func:`shipid.estimate.fir_kernels.lag_moments` in either ``compute`` mode (the
    products of the numpy blocks of :func:`lag_products` up to the order of the summation, at a third of their
    cost; this function's reference is the explicit path, ``explicit_moments=True``). Cost O(n n_z) per
    dataset and no n × n_z matrix (the largest arrays are these 4 + 6 filtered rows), which is what keeps
    long records linear in time and bounded in memory.
    """
    s = first_row(options)
    n = ds.y.size
    da = diff2(a_hat)
    F = np.empty((4, n))                    # the instrument signals (rows 0-3 of work_arrays), prefiltered
    T = np.empty((6, n))                    # Phi columns (37) then y, prefiltered
    rows = ((F[0], y_hat - y_hat.mean()), (F[1], da - da.mean()), *zip(F[2:], input_differences(ds)),
            *zip(T[2:5], ds.Phi[:, 2:].T), (T[5], ds.y))
    for out, x in rows:                     # row by row: no 8 x n copy of the inputs
        if L is not None:
            lfilter_into(L.a, L.c, x, out)  # = scipy.signal.lfilter(L.a, L.c, x) (shipid.numerics.iir_kernels)
        else:
            out[:] = x
    T[0, 0], T[0, 1:] = 0.0, -T[5, :-1]     # the delayed-y columns: the filter commutes with the delay
    T[1, :2], T[1, 2:] = 0.0, -T[5, :-2]
    s2 = s + transient_length(L, n - s, options)
    nls = np.array((options.n_y, options.n_as, options.n_r, options.n_delta), dtype=np.int64)
    ZtZ, ZtP = lag_moments(F, nls, T, s2)
    return iv_compress_products(ZtZ, ZtP, n - s2)


def build_moments(prep: list[Dataset], L: list, y_hats, a_hats, options: MassCMOptions):
    s = first_row(options)
    mom = []
    for ds, Li, yh, ah in zip(prep, L, y_hats, a_hats):
        if Li is not None and Li.c.size == 1 and Li.c[0] == 1.0 and options.instruments == "lags":
            mom.append(fir_moments(ds, Li.a, yh, ah, options))
            continue
        if options.instruments == "lags" and options.explicit_moments is False:
            mom.append(filtered_lag_moments(ds, Li, yh, ah, options))
            continue
        Z = instruments(ds, yh, ah, ds.r_hat0, Li, options)
        if Li is not None:
            yf = Li.prefilter(ds.y)[s:]
            Pf = Li.prefilter(ds.Phi)[s:]
        else:
            yf, Pf = ds.y[s:], ds.Phi[s:]
        k = transient_length(Li, yf.size, options)
        mom.append(iv_compress(Z[k:], yf[k:], Pf[k:]))
    return mom


def transient_length(L, n: int, options: MassCMOptions) -> int:
    """Samples to drop while the prefilter's start-up transient decays (*).

    ``lfilter`` starts from rest; the slowly decaying response to the signals' offsets (the record's
    mean roll rate, the constant of a gyro bias) is not orthogonal to the slow instruments and biases
    the estimate when the prefilter has poles near 1 (as ``1/(1 - c q^-2)`` and wave-noise models do).
    We drop the samples until the slowest pole has decayed to ``options.transient_tol``, at most
    ``options.transient_max`` of the record.
    """
    if L is None or L.c.size <= 1:
        return 0
    r = float(np.max(np.abs(np.roots(L.c))))
    if r <= 0:
        return 0
    k = int(np.ceil(np.log(options.transient_tol) / np.log(min(r, 1 - 1e-9))))
    return int(min(k, options.transient_max * n))


__all__ = ["instruments", "closed_loop_sim", "fir_moments", "fir_moments_compiled", "fir_moments_numpy",
           "input_differences", "LAG_BLOCK", "lag_products", "work_arrays", "filtered_lag_moments", "build_moments", "transient_length"]
