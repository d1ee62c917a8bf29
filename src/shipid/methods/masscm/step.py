"""One compiled (numba) pass of steps B(b)–(c) of Algorithm 1 (Linder et al. 2015) for one dataset.

For the default configuration (AR noise model ``L = A(q)``, lag instruments (45)) an iteration of
:func:`shipid.methods.masscm.iteration.iterate` does, per dataset, at the relaxed iterate ``theta_mid``:

1. the equation error (42) ``eps = y - Phi g_i(theta_mid)`` (:func:`equation_error`);
2. its AR(p) noise model (least squares, :func:`shipid.estimate.fir_kernels.ar_fit`) — the prefilter (43);
3. the closed-loop instrument simulation (46)–(47) (:func:`instrument_signals`, the arithmetic of
   :func:`shipid.methods.masscm.moments.closed_loop_sim`);
4. the IV moments ``Z^T Z``, ``Z^T [Phi, y]`` of the prefiltered instruments
   (:func:`shipid.estimate.fir_kernels.fir_filter`, :func:`~shipid.estimate.fir_kernels.lag_moments` and
   :func:`delayed_y_columns`, as :func:`shipid.methods.masscm.moments.fir_moments_compiled`).

:func:`dataset_step` chains them (tests compare it with the reference path). The compression of the moments
(eigen-decomposition with the rank rule) stays in :func:`shipid.estimate.iv.iv_compress_products_compiled`.

Compiled with ``cache=True``. No kernel here calls a compiled function of another module: numba keys a cached
function on its own source file only, so a kernel that compiled :mod:`shipid.estimate.fir_kernels` into itself
would keep stale code after an edit there. :func:`dataset_step` is therefore plain Python that calls the kernels
of this module and of ``fir_kernels`` in turn, each cached against its own file.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from shipid.estimate.fir_kernels import ar_fit, fir_filter, lag_moments


@njit(cache=True)
def _iir2_pair(b1, a1, b2, a2, Kyaw, r, Kd, delta, U):
    """``y = lfilter(b1, a1, u)`` and ``w = lfilter(b2, a2, u) - U r`` of ``u = Kyaw r + Kd delta``, second-order
    ``b``, ``a`` with ``a[0] = 1`` (direct form II transposed), in one pass: the two independent recursions
    interleaved, each sample's arithmetic that of one ``lfilter`` at a time."""
    n = r.size
    y = np.empty(n)
    w = np.empty(n)
    p0 = 0.0
    p1 = 0.0
    q0 = 0.0
    q1 = 0.0
    for t in range(n):
        xt = Kyaw * r[t] + Kd * delta[t]
        yt = b1[0] * xt + p0
        p0 = b1[1] * xt - a1[1] * yt + p1
        p1 = b1[2] * xt - a1[2] * yt
        y[t] = yt
        vt = b2[0] * xt + q0
        q0 = b2[1] * xt - a2[1] * vt + q1
        q1 = b2[2] * xt - a2[2] * vt
        w[t] = vt - U * r[t]
    return y, w


@njit(cache=True)
def _bilinear(p2, p1, p0, q2, q1, q0, T):
    """:func:`shipid.models.roll_reduced.bilinear_tf` of ``(p2 s^2 + p1 s + p0)/(q2 s^2 + q1 s + q0)``."""
    c = 2.0 / T
    b = np.array([p2 * c * c + p1 * c + p0, -2 * p2 * c * c + 2 * p0, p2 * c * c - p1 * c + p0])
    a = np.array([q2 * c * c + q1 * c + q0, -2 * q2 * c * c + 2 * q0, q2 * c * c - q1 * c + q0])
    return b / a[0], a / a[0]


@njit(cache=True)
def _mean(x):
    s = 0.0
    for t in range(x.size):
        s += x[t]
    return s / x.size


@njit(cache=True, fastmath={"reassoc", "contract"})
def delayed_y_columns(F, nls, yf, Sy, s, ZtP):
    """Columns 0, 1 of ``Z^T Phi`` (37): ``-sum_t F[k, t-i] yf[t-d]``, ``d = 1, 2``, ``t = s .. n-1``.

    Moving the window back by ``d`` samples turns them into the y column ``Sy[(k, i-d)]`` plus edge terms:
    ``sum_t f[t-i] y[t-1] = Sy[i-1] + f[s-i] y[s-1] - f[n-i] y[n-1]`` (i >= 1) and
    ``sum_t f[t-i] y[t-2] = Sy[i-2] + f[s-i+1] y[s-1] + f[s-i] y[s-2] - f[n-i+1] y[n-1] - f[n-i] y[n-2]``
    (i >= 2); the lags that would need a negative shift (i < d) are direct dot products.
    """
    n = yf.size
    m = n - s
    r = 0
    for k in range(nls.size):
        fk = F[k]
        d10 = 0.0
        for i in range(nls[k]):
            if i == 0:
                acc1 = 0.0
                acc2 = 0.0
                f0 = fk[s:]
                y1 = yf[s - 1:n - 1]
                y2 = yf[s - 2:n - 2]
                for t in range(m):
                    acc1 += f0[t] * y1[t]
                    acc2 += f0[t] * y2[t]
                d10 = acc1
                D1, D2 = acc1, acc2
            else:
                D1 = Sy[r - 1] + fk[s - i] * yf[s - 1] - fk[n - i] * yf[n - 1]
                if i == 1:                                   # sum_t f[t-1] y[t-2] from the i = 0 sum
                    D2 = d10 + fk[s - 1] * yf[s - 2] - fk[n - 1] * yf[n - 2]
                else:
                    D2 = (Sy[r - 2] + fk[s - i + 1] * yf[s - 1] + fk[s - i] * yf[s - 2]
                          - fk[n - i + 1] * yf[n - 1] - fk[n - i] * yf[n - 2])
            ZtP[r, 0] = -D1
            ZtP[r, 1] = -D2
            r += 1


@njit(cache=True)
def equation_error(y, PhiT, g_mid, s):
    """Equation error (42) ``y_t - Phi_t^T g_mid`` for ``t = s .. n-1``, mean removed and scaled by its std
    (the normalisation of :func:`shipid.estimate.arma.fit_ar`); returns ``(e, scale)``.

    Regressor by regressor over the samples (each sample's terms subtracted in the order ``j = 0 .. 4``,
    contiguous rows: a vectorised loop with each sample's arithmetic unchanged)."""
    n = y.size
    m = n - s
    e = np.empty(m)
    for t in range(m):
        e[t] = y[s + t]
    for j in range(5):
        gj = g_mid[j]
        pj = PhiT[j, s:]
        for t in range(m):
            e[t] -= pj[t] * gj
    mu = _mean(e)
    var = 0.0
    for t in range(e.size):
        e[t] -= mu
        var += e[t] * e[t]
    scale = np.sqrt(var / e.size)
    if np.isfinite(scale) and scale > 0.0:
        for t in range(e.size):
            e[t] /= scale
    return e, scale


@njit(cache=True)
def instrument_signals(sim, r_hat0, delta, y_hat, a_hat, X):
    """Closed-loop instruments (46)–(47) and rows 0, 1 of the work array ``X``; returns ``(stable, y_hat, a_hat)``.

    ``sim = [A1, d, k1, Kyaw, K_delta, z_s, g, U, T]``: with ``v'`` neglected in (20),
    ``(A1 s^2 + d s + k1) phi = Kyaw r + K_delta delta`` and ``a_s = z_s p' + g phi - U r``, discretised by the
    bilinear transform; ``r`` is the black-box yaw rate (44). An unstable model keeps the given ``y_hat``,
    ``a_hat``. ``X[0]`` is ``y_hat``, ``X[1]`` the difference ``a_hat_t - a_hat_{t-2}``, both mean removed.
    """
    n = r_hat0.size
    A1, d, k1, Kyaw, Kd, zs, g, U, T = sim[0], sim[1], sim[2], sim[3], sim[4], sim[5], sim[6], sim[7], sim[8]
    stable = A1 > 0 and d > 0 and k1 > 0
    if stable:
        b1, a1 = _bilinear(0.0, 1.0, 0.0, A1, d, k1, T)
        b2, a2 = _bilinear(zs, 0.0, g, A1, d, k1, T)
        y_hat, a_hat = _iir2_pair(b1, a1, b2, a2, Kyaw, r_hat0, Kd, delta, U)
    my = _mean(y_hat)
    for t in range(n):
        X[0, t] = y_hat[t] - my
    X[1, 0] = 0.0
    X[1, 1] = 0.0
    for t in range(2, n):
        X[1, t] = a_hat[t] - a_hat[t - 2]
    md = _mean(X[1])
    for t in range(n):
        X[1, t] -= md
    return stable, y_hat, a_hat


@njit(cache=True)
def instrument_products(Fl, nls, ZtT, s):
    """``Z^T Phi`` (37) from ``Z^T [Phi_2.., y]`` (``ZtT``, by :func:`~shipid.estimate.fir_kernels.lag_moments`
    of the measured columns and y, rows 4..7 of the filtered ``Fl``): the two delayed-y columns by
    :func:`delayed_y_columns`, the others copied."""
    ZtP = np.empty((ZtT.shape[0], 6))
    delayed_y_columns(Fl, nls, Fl[7], ZtT[:, 3], s, ZtP)
    for c in range(4):
        for r in range(ZtT.shape[0]):
            ZtP[r, 2 + c] = ZtT[r, c]
    return ZtP


def dataset_step(y, PhiT, g_mid, s, p, X, nls, r_hat0, delta, sim, y_hat, a_hat):
    """Steps B(b)–(c) for one dataset; see the module docstring.

    Parameters
    ----------
    y : (n,) output (roll rate); PhiT : (5, n) regressors (37) transposed; g_mid : (5,) ``g_i(theta_mid)``.
    s : first instrument row (:func:`shipid.methods.masscm.data.first_row`); p : AR order.
    X : (8, n) work array whose rows 2..7 hold the iterate-independent signals of
        :func:`shipid.methods.masscm.moments.work_arrays` (rows 0, 1 are overwritten).
    nls : (4,) lags (n_y, n_as, n_r, n_delta).
    r_hat0, delta : black-box yaw rate (44) and the (mean-removed) rudder.
    sim : ``[A1, d, k1, Kyaw, K_delta, z_s, g, U, T]`` of dataset i (``roll_terms`` at theta_mid).
    y_hat, a_hat : the previous instrument signals (kept when the model is unstable).

    Returns
    -------
    status : 0 ok; 1 the AR normal equations are not positive definite or the residual is constant
        (the caller redoes this dataset on the reference path).
    stable : whether the closed-loop simulation was done (else ``y_hat``, ``a_hat`` are the inputs).
    a, lam : AR polynomial and innovation variance; y_hat, a_hat; ZtZ, ZtP : the IV moments.
    """
    e, scale = equation_error(y, PhiT, g_mid, s)
    empty = np.zeros((0, 0))
    if not (np.isfinite(scale) and scale > 0.0) or e.size <= 2 * p:
        return 1, False, np.zeros(p + 1), 0.0, y_hat, a_hat, empty, empty
    ok, a, s2 = ar_fit(e, p)
    if not ok:
        return 1, False, a, 0.0, y_hat, a_hat, empty, empty
    lam = s2 * scale * scale
    stable, y_hat, a_hat = instrument_signals(sim, r_hat0, delta, y_hat, a_hat, X)
    Fl = fir_filter(a, X)
    ZtZ, ZtT = lag_moments(Fl[:4], nls, Fl[4:8], s)
    return 0, stable, a, lam, y_hat, a_hat, ZtZ, instrument_products(Fl, nls, ZtT, s)


__all__ = ["dataset_step", "equation_error", "instrument_signals", "instrument_products", "delayed_y_columns"]
