"""Online mass and centre-of-mass monitoring: Algorithm 1 of Linder et al. (2015) on a sliding window.

Monitoring is *online*: the ship's load changes while it sails. :class:`MassCMMonitor` is fed
chunks of the loaded-condition IMU + rudder stream and returns one :class:`MonitorUpdate` every
``every`` seconds of stream time. It is built from the pieces of Algorithm 1
(:mod:`shipid.methods.masscm.estimator`):

1. **Start-up (once).** The first ``init`` seconds of the stream, with the nominal and calibration
   datasets, go through the offline Algorithm 1 (:func:`shipid.methods.masscm.estimator.iterate`, z_f known). From
   its converged state the monitor keeps, and never recomputes, the compressed IV criteria
   ``(R_i, r_i, lam_i)`` of the nominal and calibration datasets (40)–(41): they are processed once.
2. **Block moments of the loaded stream.** Each block of ``every`` seconds is turned into its IV moment
   matrices ``Z_b^T Z_b`` and ``Z_b^T [Phi_b, y_b]``: regressors (37); instruments (45) (``n_y = n_as = n_r
   = 16``, ``n_delta = 2`` lags of the closed-loop simulation (46)–(47) of the current model, driven by the
   black-box yaw-rate model (44) fitted at start-up), both filtered by the current prefilter (43): default the
   Box-Jenkins ``D(q)/(1 - c q^-2)^k`` (:mod:`.bj_prefilter`), or AR(40) ``A(q)``; instruments mean-removed per block (a gyro bias leaves a constant in the
   equation error). Filters and simulations carry their state over block boundaries, so a block costs the
   same whatever the elapsed time. Blocks are kept for ``window`` seconds (raw samples included, for a
   rebuild after a change): the memory is bounded by the window, not by the stream length.
3. **Refined IV update.** Every block: the window's moments are summed and compressed
   (:func:`shipid.estimate.iv.iv_compress_products`), the criterion (40) over the three datasets is
   minimised from the previous estimate (damped Gauss-Newton, exact complex-step Jacobian, z_f known). The
   standard errors of ``m``, ``zm_bar`` and ``rho`` (delta method) come from the block Newey-West sandwich of
   :mod:`shipid.methods.monitor.covariance`: the gradient of (40) cut into ``every``-second blocks of the
   nominal and calibration datasets (kept from the start-up; their error is shared by every update) and of
   the window, so that a coloured equation error and a slow misfit, which the white-noise covariance
   ``(J^T J)^-1`` of Algorithm 1 does not see, widen the bands (never below ``(J^T J)^-1``), and so does the
   error a gyro bias leaves through the reference datasets' prefilter. Then step B(b)-(c) for the *next* blocks: the noise model
   (AR part; (c, k) held) is refitted to the equation error of the last ``ar_fit`` seconds (Hannan–Rissanen, i.e.
   least squares) and the instrument model is the new estimate. Blocks already in the window keep the
   prefilter and instruments they were built with: each block's instruments are a function of the rudder
   only, so the summed moments remain a valid IV criterion (only its efficiency depends on the model).
4. **Change detector** (:meth:`MassCMMonitor._detect`): a two-window Wald / GLR test on the loaded
   dataset's identifiable load quantities ``(q = m z_m, zm_bar)`` (equivalently ``rho`` and ``zm_bar``;
   ``rho = q / (m_c z_c)``) with the ship's coefficients held at the current estimate. For every split
   of the window at a block boundary with a tail of ``detect_min``..``detect_max`` seconds and a reference
   of at least ``ref_min`` seconds, ``(q, zm_bar)`` is estimated on the reference and on the tail, and
   ``T = d^T (S_ref + S_tail)^-1 d`` is formed (``chi^2`` with 2 degrees of freedom under no change, for
   one split). The alarm is raised when ``max T`` exceeds ``threshold``; ``change_at`` is the arg-max
   split. Holding the coefficients at one value for both windows removes from ``d`` the uncertainty that
   the two windows share (that of the nominal and calibration datasets), which is most of the
   uncertainty of ``rho`` and ``m``.
5. **After an alarm** the window is cut to the blocks after ``change_at``, their moments rebuilt from the
   raw samples with the tail's estimate as the instrument model, and the estimate re-converges on the
   growing window (``converged`` is False until it spans ``min_window`` seconds again). The detector
   waits until the new reference is ``ref_min`` long.

The defaults (a 300-s rectangular window, ``threshold`` 40) and what they give on simulated streams (window
trade-off, detection delay, false-alarm rate, coverage of ±2 std, speed, memory): ``docs/validation/monitor.md``.
"""

from __future__ import annotations

import math
import warnings
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from shipid.io.trial import Trial
from shipid.errors import InputError, ShipidError
from shipid.numerics.linalg import one_blas_thread
from shipid.estimate.arma import hannan_rissanen
from shipid.estimate.iv import arx_fit, iv_compress_products
from shipid.methods.masscm.estimator import DEFAULT_THETA0, MassCMOptions, iterate, prepare
from shipid.methods.monitor.bj_prefilter import bj_mode, degenerate, fit_bj, inverse_c, lfilter, transient_samples
from shipid.methods.monitor.covariance import block_projections, coeff_jacobian, reference_projections, sandwich
from shipid.methods.monitor.fit import fit_load, search
from shipid.models.roll_reduced import (CALIBRATION, LOADED, NOMINAL, KnownParams, bilinear_tf, discrete_coeffs,
                                        roll_terms)

I_Q, I_ZM, I_ZF = 7, 8, 6
_HIST = 64            # samples of history carried into each block (AR order 40 + 16 lags + 2 differences)


@dataclass(frozen=True)
class MonitorOptions:
    """Tuning of the monitor (seconds of stream time).

    Attributes
    ----------
    window : float
        Sliding window of the loaded-stream moments (s).
    every : float
        Block length and update period (s).
    init : float
        Stream seconds given to the start-up run of Algorithm 1 before the first estimate.
    min_window : float
        ``converged`` needs a window (since start or since the last change) of at least this (s).
    detect_min, detect_max : float
        Shortest and longest tail tested by the change detector (s).
    ref_min : float
        Shortest reference window of the detector (s).
    threshold : float
        Alarm when the largest Wald statistic over the splits exceeds this (chi^2, 2 dof for one split;
        ``chi2.sf(threshold, 2) = exp(-threshold / 2)``, but the maximum over overlapping splits and updates is
        over-dispersed). 40: about twice the largest no-change value seen on simulated streams (22.2); the
        measured false-alarm rate and detection delays are in ``docs/validation/monitor.md``.
    ar_fit : float
        Seconds of recent equation error to which the AR prefilter is refitted after every update.
    covariance : {"sandwich", "white"}
        Standard errors of the updates: "sandwich" the block Newey-West sandwich over the reference datasets and
        the window, with the error a gyro bias leaves through the reference datasets' prefilter
        (:mod:`shipid.methods.monitor.covariance`); "white" ``(J^T J)^-1`` of Algorithm 1, which holds
        only when the prefiltered equation error is white.
    bj_reselect : int
        Box-Jenkins noise model (``masscm.noise_model`` "auto"/"bj"): every ``bj_reselect`` updates ``(c, k)``
        is chosen again on the last ``ar_fit`` s (window rebuilt if it changes); 0: the start-up's is held.
    masscm : MassCMOptions
        Options of Algorithm 1 (prefilter order, lags, start-up run); ``noise_model`` "auto" (default) or "bj"
        the Box-Jenkins prefilter of :mod:`shipid.methods.monitor.bj_prefilter`, "ar" the AR(40) one.
    """

    window: float = 300.0
    every: float = 10.0
    init: float = 120.0
    min_window: float = 120.0
    detect_min: float = 30.0
    detect_max: float = 120.0
    ref_min: float = 60.0
    threshold: float = 40.0
    ar_fit: float = 120.0
    bj_reselect: int = 0
    covariance: str = "sandwich"
    masscm: MassCMOptions = MassCMOptions()      # noise_model "auto": the Box-Jenkins prefilter (bj_prefilter)


@dataclass(frozen=True)
class MonitorUpdate:
    """One output line of the monitor. Estimates are None before the start-up run has finished."""

    t: float
    m: float | None
    m_std: float | None
    zm_bar: float | None
    zm_bar_std: float | None
    rho: float | None
    rho_std: float | None
    converged: bool
    alarm: bool
    change_at: float | None
    window_s: float = 0.0
    statistic: float | None = None
    warnings: tuple = ()

    def to_json(self) -> dict:
        def f(v):
            return None if v is None or not math.isfinite(v) else float(v)
        return {"t": round(float(self.t), 6), "m": f(self.m), "m_std": f(self.m_std), "zm_bar": f(self.zm_bar),
                "zm_bar_std": f(self.zm_bar_std), "rho": f(self.rho), "rho_std": f(self.rho_std),
                "converged": bool(self.converged), "alarm": bool(self.alarm), "change_at": f(self.change_at),
                "window_s": float(self.window_s), "statistic": f(self.statistic),
                "warnings": list(self.warnings)}


@dataclass
class _Block:
    t0: float
    t1: float
    raw: np.ndarray                 # (4, n): p, a_s, r, delta (rudder offset removed)
    ZtZ: np.ndarray = field(repr=False, default=None)
    ZtP: np.ndarray = field(repr=False, default=None)
    n: int = 0


@dataclass
class _Sim:
    """Streaming state of the instrument simulations (46)-(47) and the black-box r model (44)."""

    zr: np.ndarray
    zy: np.ndarray | None = None
    za: np.ndarray | None = None
    coef: tuple | None = None
    hist: np.ndarray = None         # (3, _HIST): y_hat, a_hat, r_hat0
    raw_hist: np.ndarray = None     # (4, _HIST)
    skip_left: int = 0              # samples still to drop (start-up transient of the filters)
    zc: np.ndarray | None = None    # state of the prefilter's 1/C(q) (Box-Jenkins prefilter only)
    ghist: np.ndarray | None = None  # (10, _HIST): the 1/C-filtered signals' history


def _d2(x: np.ndarray) -> np.ndarray:
    """``x_t - x_{t-2}`` along the last axis; the first two entries are left as they are (history)."""
    d = np.zeros_like(x)
    d[..., 2:] = x[..., 2:] - x[..., :-2]
    return d


class MassCMMonitor:
    """Online estimate of the load mass ``m`` and centre ``zm_bar`` with change detection.

    Parameters
    ----------
    nominal, calibration : Trial
        The reference datasets (channels ``p, a_s, r, delta``), recorded once.
    known : KnownParams
        ``U, M, zg_bar, m_c, zc_bar, zs_bar, g`` (§4.3).
    z_f : float
        Known centre of rotation (m); without it ``m`` is not identifiable (ERRATA).
    options : MonitorOptions

    Use :meth:`feed` with chunks of samples (any length); it returns the updates completed by them.
    """

    def __init__(self, nominal: Trial, calibration: Trial, known: KnownParams, z_f: float,
                 options: MonitorOptions = MonitorOptions()):
        if z_f is None or not math.isfinite(float(z_f)):
            raise InputError("the monitor needs a known z_f (known.toml: z_f); without it m is not identifiable")
        self.known, self.z_f, self.opt = known, float(z_f), options
        self._refs = (nominal, calibration)
        self.T = float(np.mean(np.diff(np.asarray(nominal.t, dtype=float))))
        self.nb = max(1, int(round(options.every / self.T)))
        self._pending: list[np.ndarray] = []       # chunks (5, k): t, p, a_s, r, delta
        self._npending = 0
        self._t_next: float | None = None          # expected time of the next sample
        self._t_first: float | None = None
        self.blocks: deque[_Block] = deque()
        self._init_blocks: list[_Block] = []
        self.started = False
        self.theta_q: np.ndarray | None = None
        self.change_at: float | None = None
        self._since: float | None = None           # start of the current condition's window
        self.updates: list[MonitorUpdate] = []
        self.keep_updates = True
        self.bj = bj_mode(options.masscm)
        self.prefilter_c = np.ones(1)              # C(q) of the Box-Jenkins prefilter D/C (1 for the AR one)
        self._n_upd = 0

    # ------------------------------------------------------------------ input
    def feed(self, t, p, a_s, r, delta) -> list[MonitorUpdate]:
        """Append samples (1-D arrays of equal length; ``t`` uniformly spaced at the nominal dataset's
        sample period) and return the updates they complete."""
        X = np.vstack([np.atleast_1d(np.asarray(v, dtype=float)) for v in (t, p, a_s, r, delta)])
        if X.shape[1] == 0:
            return []
        bad = np.flatnonzero(~np.all(np.isfinite(X), axis=0))
        if bad.size:
            raise InputError(f"non-finite value in the stream at sample {self._count() + int(bad[0])}")
        t_expected = (self._t_next if self._t_next is not None else X[0, 0]) + self.T * np.arange(X.shape[1])
        off = np.flatnonzero(np.abs(X[0] - t_expected) > 0.25 * self.T)
        if off.size:
            k = int(off[0])
            raise InputError(f"stream not uniformly sampled at {self.T:g} s (the nominal dataset's period): "
                             f"sample {self._count() + k} has t = {X[0, k]:.6g}, expected {t_expected[k]:.6g}")
        if self._t_first is None:
            self._t_first = float(X[0, 0])
        self._t_next = float(t_expected[-1] + self.T)
        self._pending.append(X)
        self._npending += X.shape[1]
        with one_blas_thread():            # small matrices; and thread-count-free results (as in masscm)
            return self._drain()

    def _drain(self) -> list[MonitorUpdate]:
        out = []
        if self._npending < self.nb:
            return out
        allp = np.hstack(self._pending)
        a = 0
        while allp.shape[1] - a >= self.nb:
            u = self._block(allp[:, a:a + self.nb])
            a += self.nb
            if u is not None:
                out.append(u)
                if self.keep_updates:
                    self.updates.append(u)
        rest = allp[:, a:]
        self._pending = [rest.copy()] if rest.shape[1] else []
        self._npending = rest.shape[1]
        return out

    def feed_trial(self, trial: Trial, chunk: int | None = None) -> list[MonitorUpdate]:
        """Feed a whole :class:`Trial` (in chunks of ``chunk`` samples) and return all updates."""
        n = len(trial.t)
        chunk = chunk or n
        out = []
        for a in range(0, n, chunk):
            s = slice(a, a + chunk)
            out += self.feed(trial.t[s], trial["p"][s], trial["a_s"][s], trial["r"][s], trial["delta"][s])
        return out

    def _count(self) -> int:
        if self._t_first is None or self._t_next is None:
            return 0
        return int(round((self._t_next - self._t_first) / self.T))

    # ------------------------------------------------------------------ blocks
    def _block(self, X: np.ndarray) -> MonitorUpdate | None:
        t0, t1 = float(X[0, 0]), float(X[0, -1] + self.T)
        if not self.started:
            self._init_blocks.append(_Block(t0, t1, X[1:].copy()))
            if t1 - self._t_first < self.opt.init - 0.5 * self.T:
                return MonitorUpdate(t1, None, None, None, None, None, None, False, False, None,
                                     window_s=t1 - self._t_first)
            return self._start()
        b = _Block(t0, t1, X[1:].copy())
        b.raw[3] -= self.delta0
        self._moments(b)
        self.blocks.append(b)
        while self.blocks and self.blocks[-1].t1 - self.blocks[0].t0 > self.opt.window + 0.5 * self.T:
            self.blocks.popleft()
        return self._update()

    def _start(self) -> MonitorUpdate:
        """Start-up: Algorithm 1 on nominal + calibration + the first ``init`` seconds (processed once)."""
        raw = np.hstack([b.raw for b in self._init_blocks])
        t = self._t_first + self.T * np.arange(raw.shape[1])
        loaded = Trial(t - t[0], {"p": raw[0], "a_s": raw[1], "r": raw[2], "delta": raw[3]},
                       meta={"source": "stream (start-up window)"})
        opts = self.opt.masscm
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            prep = prepare([(NOMINAL, self._refs[0]), (CALIBRATION, self._refs[1]), (LOADED, loaded)], opts)
            core = iterate(prep, self.known, DEFAULT_THETA0, z_f=self.z_f, init="linear", options=opts)
        st = core["state"]
        if not np.all(np.isfinite(core["theta_q"])):
            raise ShipidError("the start-up run of Algorithm 1 on the first "
                              f"{self.opt.init:g} s of the stream gave a non-finite estimate; cannot monitor")
        self.ref_moments = [st.moments[0], st.moments[1]]
        self.ref_lam = np.array(st.lam[:2], dtype=float)
        self.ref_proj = reference_projections(prep, st.L, np.asarray(core["theta_q"], dtype=float), self.known,
                                              [NOMINAL, CALIBRATION], opts, self.nb)
        self.Ts = np.array([ds.T for ds in prep])
        self.theta_q = np.asarray(core["theta_q"], dtype=float).copy()
        self.start_warnings = tuple(core["warnings"]) + (() if core["converged"] else (
            f"start-up run of Algorithm 1 not converged after {core['iterations']} iterations",))
        self.delta0 = float(np.mean(raw[3]))
        self.arx_r = arx_fit(raw[2] - raw[2].mean(), raw[3] - self.delta0, opts.arx_na, opts.arx_nb)
        L = st.L[2]
        if self.bj and L is not None:
            self.prefilter, self.prefilter_c = np.asarray(L.a, dtype=float), np.asarray(L.c, dtype=float)
        elif self.bj:
            self.prefilter, _, self.prefilter_c = self._fit_prefilter(raw, reselect=True)
        else:
            self.prefilter = np.asarray(L.a, dtype=float) if L is not None and L.c.size == 1 else \
                self._fit_prefilter(raw)[0]
        self.lam_loaded = float(st.lam[2])
        self.started = True
        self._since = float(self._t_first)
        for b in self._init_blocks:
            b.raw[3] -= self.delta0
        self._rebuild(self._init_blocks)
        self.blocks = deque(self._init_blocks)
        self._init_blocks = []
        return self._update(extra_warnings=self.start_warnings)

    def _model_coef(self, theta_q: np.ndarray):
        """Closed-loop simulation filters (46)-(47) of the loaded condition at ``theta_q``, or None."""
        tm = roll_terms(theta_q, self.known, [LOADED], moment=True)
        A1, d, k1 = float(tm["A1"][0]), float(tm["d"][0]), float(tm["k1"][0])
        if not (A1 > 0 and d > 0 and k1 > 0):
            return None
        b1, a1 = bilinear_tf([1.0, 0.0], [A1, d, k1], self.T)
        b2, a2 = bilinear_tf([float(tm["z_s"][0]), 0.0, self.known.g], [A1, d, k1], self.T)
        return (b1, a1, b2, a2, float(tm["Kyaw"][0]), float(tm["K_delta"][0]))

    def _rebuild(self, blocks, warm=()) -> None:
        """Moments of ``blocks`` from their raw samples with the current model, from rest (and again after a gap,
        a block with ``after_gap``). ``warm``: blocks just before ``blocks`` run through the filters first (their
        moments discarded), so that the start-up transient of the filters falls on them."""
        for i, b in enumerate(list(warm) + list(blocks)):
            self._sim = None if i == 0 or getattr(b, "after_gap", False) else self._sim
            self._moments(b)

    def _moments(self, b: _Block) -> None:
        """IV moment matrices of one block (regressors (37), instruments (45), prefilter (43))."""
        o = self.opt.masscm
        n = b.raw.shape[1]
        br, ar = self.arx_r
        coef = self._model_coef(self.theta_q)
        skip = 0
        if self._sim is None:
            # from rest; the first _HIST rows depend on the (repeated first sample) history and are dropped
            self._sim = _Sim(zr=np.zeros(max(len(ar), len(br)) - 1), hist=np.zeros((3, _HIST)),
                             raw_hist=np.repeat(b.raw[:, :1], _HIST, axis=1))
            if self.prefilter_c.size > 1:
                self._sim.skip_left = _HIST + transient_samples(self.prefilter_c, o, int(self.opt.window / self.T))
            else:
                skip = min(_HIST, n - 1)
        sm = self._sim
        if sm.skip_left:
            skip = min(sm.skip_left, n)
            sm.skip_left -= skip
        if coef is not None:
            sm.coef = coef
        if sm.coef is None:
            raise ShipidError("the start-up estimate of the loaded condition is an unstable roll model, so no "
                              "instruments can be simulated: Algorithm 1 failed on the start-up window (with narrow-"
                              "band wave roll and low-noise sensors the AR(40) prefilter is known to fail, "
                              "shipid.methods.masscm.estimator 'Known limitations'); try a longer --init")
        b1, a1, b2, a2, Kyaw, Kd = sm.coef
        delta = b.raw[3]
        r_hat, sm.zr = lfilter(br, ar, delta, zi=sm.zr)
        u = Kyaw * r_hat + Kd * delta
        if sm.zy is None:
            sm.zy, sm.za = np.zeros(2), np.zeros(2)
        y_hat, sm.zy = lfilter(b1, a1, u, zi=sm.zy)
        a_hat, sm.za = lfilter(b2, a2, u, zi=sm.za)
        a_hat = a_hat - self.known.U * r_hat
        sims = np.hstack([sm.hist, np.vstack([y_hat, a_hat, r_hat])])        # (3, H + n)
        raw = np.hstack([sm.raw_hist, b.raw])                                 # (4, H + n)
        sm.hist, sm.raw_hist = sims[:, -_HIST:].copy(), raw[:, -_HIST:].copy()
        y = raw[0]
        # signals to prefilter: instrument bases (45) and the regressors (37) with y
        S = np.empty((10, raw.shape[1]))
        S[0] = sims[0]
        S[1] = _d2(sims[1])
        S[2] = _d2(sims[2])
        S[3] = _d2(raw[3])
        S[4, 1:] = -y[:-1]; S[4, 0] = -y[0]
        S[5, 2:] = -y[:-2]; S[5, :2] = -y[0]
        S[6] = _d2(raw[1])
        S[7] = _d2(raw[2])
        S[8] = _d2(raw[3])
        S[9] = y
        if self.prefilter_c.size > 1:    # Box-Jenkins prefilter D/C: 1/C with its state carried over blocks
            S = inverse_c(S, sm, self.prefilter_c, _HIST)
        if skip >= n:                    # the whole block falls in the filters' start-up transient
            nz = o.n_y + o.n_as + o.n_r + o.n_delta
            b.ZtZ, b.ZtP, b.n = np.zeros((nz, nz)), np.zeros((nz, 6)), 0
            return
        F = lfilter(self.prefilter, [1.0], S, axis=1)[:, _HIST:]        # rows of this block only are valid
        full = lfilter(self.prefilter, [1.0], S[:4], axis=1)
        cols = []
        for k, nl in enumerate((o.n_y, o.n_as, o.n_r, o.n_delta)):
            for j in range(nl):
                cols.append(full[k, _HIST - j:_HIST - j + n])
        Z = np.array(cols).T[skip:]                                      # (n, n_z)
        Z = Z - Z.mean(axis=0)
        P = F[4:, skip:].T                                               # (n, 6): Phi then y
        b.ZtZ, b.ZtP, b.n = Z.T @ Z, Z.T @ P, n - skip

    def _fit_prefilter(self, raw: np.ndarray, theta_q: np.ndarray | None = None, reselect: bool = False):
        """AR(ar_order) noise model (42)-(43) of the loaded equation error of ``raw`` at ``theta_q``: ``(A, lam)``;
        with the Box-Jenkins prefilter ``(D, lam, C)`` (``C`` held unless ``reselect``)."""
        th = self.theta_q if theta_q is None else theta_q
        g = discrete_coeffs(th, self.known, [LOADED], self.T, moment=True)[0]
        y = raw[0]
        Phi = np.column_stack([-np.r_[y[0], y[:-1]], -np.r_[y[:2], y[:-2]], _d2(raw[1]), _d2(raw[2]), _d2(raw[3])])
        eps = (y - Phi @ g)[3:]
        if self.bj:
            return fit_bj(eps, self.opt.masscm, None if reselect else self.prefilter_c)
        L = hannan_rissanen(eps, self.opt.masscm.ar_order, 0, n_long=self.opt.masscm.ar_order)
        return np.asarray(L.a, dtype=float), float(L.lam)

    # ------------------------------------------------------------------ estimation
    def _sum(self, blocks) -> tuple[np.ndarray, np.ndarray, int]:
        ZtZ = sum(b.ZtZ for b in blocks)
        ZtP = sum(b.ZtP for b in blocks)
        return ZtZ, ZtP, int(sum(b.n for b in blocks))

    def _load_summary(self, theta_q: np.ndarray, cov_qz: np.ndarray) -> dict:
        """``m, zm_bar, rho`` and their standard errors from ``(q, zm_bar)`` and its 2x2 covariance."""
        q, zm = float(theta_q[I_Q]), float(theta_q[I_ZM])
        zmf = zm + self.z_f
        kn = self.known
        crho = 1.0 / (kn.m_c * (kn.zc_bar + self.z_f))
        gm = np.array([1.0 / zmf, -q / zmf ** 2])

        def sd(v):
            return float(math.sqrt(v)) if np.isfinite(v) and v >= 0 else float("inf")
        return {"m": q / zmf, "m_std": sd(gm @ cov_qz @ gm), "zm_bar": zm, "zm_bar_std": sd(cov_qz[1, 1]),
                "rho": q * crho, "rho_std": sd(cov_qz[0, 0]) * abs(crho)}

    def _update(self, extra_warnings=()) -> MonitorUpdate:
        blocks = list(self.blocks)
        t1 = blocks[-1].t1
        warn = list(extra_warnings)
        ZtZ, ZtP, n = self._sum(blocks)
        mom = iv_compress_products(ZtZ, ZtP, n)
        free = np.ones(9, dtype=bool)
        free[I_ZF] = False
        th, ok, J = search(self.ref_moments + [mom], [*self.ref_lam, self.lam_loaded], self.known,
                           [NOMINAL, CALIBRATION, LOADED], self.T, self.theta_q, free, self.opt.masscm.zm_bound)
        if not (ok and np.all(np.isfinite(th))):
            warn.append(f"t = {t1:g} s: window search not converged; estimate kept from the last update")
            th = self.theta_q
        elif self.bj and degenerate(th, self.theta_q, self.known, self.opt.masscm.zm_bound):
            ok, th = False, self.theta_q   # the degenerate minimum of (40) (masscm.iteration): last physical kept
            warn.append(f"t = {t1:g} s: window search left the physical region; estimate kept from the last update")
        if self.bj and th is self.theta_q:     # the kept estimate's covariance: the Jacobian at that point
            J = search(self.ref_moments + [mom], [*self.ref_lam, self.lam_loaded], self.known,
                       [NOMINAL, CALIBRATION, LOADED], self.T, th, free, self.opt.masscm.zm_bound, max_iter=0)[2]
        self.theta_q = th
        try:
            cov = self._covariance(th, J, free, ZtZ, ZtP, blocks) if self.opt.covariance == "sandwich" else \
                np.linalg.inv(J.T @ J)
            cov = 0.5 * (cov + cov.T)
        except np.linalg.LinAlgError:
            cov = np.full((8, 8), np.inf)
        summ = self._load_summary(th, cov[6:, 6:])
        # steps (b)-(c) for the next blocks: noise model refitted to the recent equation error
        k = max(1, int(round(self.opt.ar_fit / self.opt.every)))
        raw = np.hstack([b.raw for b in blocks[-k:]])
        new_c, self._n_upd = None, self._n_upd + 1
        if raw.shape[1] > 4 * self.opt.masscm.ar_order:
            if self.bj:
                resel = self.opt.bj_reselect > 0 and self._n_upd % self.opt.bj_reselect == 0
                self.prefilter, self.lam_loaded, c_fit = self._fit_prefilter(raw, reselect=resel)
                if not np.array_equal(c_fit, self.prefilter_c):
                    new_c = c_fit
            else:
                self.prefilter, self.lam_loaded = self._fit_prefilter(raw)
        stat, tau, th_tail = self._detect()
        alarm = stat is not None and stat > self.opt.threshold
        if alarm:
            _, tau2, th2 = self._detect(locate=True)
            self._reset(tau2 if tau2 is not None else tau, th2 if th2 is not None else th_tail)
        elif new_c is not None:          # a new MA structure: 1/C's state is invalid, the window is rebuilt
            self.prefilter_c = new_c
            self._rebuild(self.blocks)
        converged = bool(ok and not alarm and t1 - self._since >= self.opt.min_window - 0.5 * self.T)
        return MonitorUpdate(t1, summ["m"], summ["m_std"], summ["zm_bar"], summ["zm_bar_std"], summ["rho"],
                             summ["rho_std"], converged, bool(alarm), self.change_at,
                             window_s=t1 - blocks[0].t0, statistic=stat, warnings=tuple(warn))

    def _covariance(self, th, J, free, ZtZ, ZtP, blocks) -> np.ndarray:
        """Covariance of the free parameters: the block sandwich of :mod:`shipid.methods.monitor.covariance`
        over the reference datasets' blocks (kept from the start-up) and the window's blocks."""
        conds = [NOMINAL, CALIBRATION, LOADED]
        G = discrete_coeffs(th, self.known, conds, np.full(3, self.T), moment=True)
        dg = coeff_jacobian(th, self.known, conds, self.T, free)
        proj = list(getattr(self, "ref_proj", (None, None))) + [block_projections(ZtZ, ZtP, [b.ZtP for b in blocks])]
        return sandwich(J, dg, G, [*self.ref_lam, self.lam_loaded], proj)

    def _fit_load(self, blocks, theta_q: np.ndarray):
        """:func:`shipid.methods.monitor.fit.fit_load` on the summed moments of ``blocks``."""
        mom = iv_compress_products(*self._sum(blocks))
        return fit_load(mom, self.lam_loaded, self.known, self.T, theta_q, self.opt.masscm.zm_bound)

    def _detect(self, locate: bool = False):
        """Largest two-window Wald statistic over the admissible splits: ``(T, change_at, theta_tail)``.

        ``locate``: after an alarm, the change time is the arg-max over the splits with tails from one block
        to ``detect_max`` (the alarm itself needs a tail of ``detect_min``)."""
        o = self.opt
        blocks = list(self.blocks)
        t_end = blocks[-1].t1
        best = (None, None, None)
        tmin = o.every if locate else o.detect_min
        for j in range(1, len(blocks)):
            tail = t_end - blocks[j].t0
            ref = blocks[j].t0 - blocks[0].t0
            if not (tmin - 0.5 * self.T <= tail <= o.detect_max + 0.5 * self.T
                    and ref >= o.ref_min - 0.5 * self.T):
                continue
            th_r, S_r = self._fit_load(blocks[:j], self.theta_q)
            th_t, S_t = self._fit_load(blocks[j:], th_r)
            if S_r is None or S_t is None:
                continue
            d = th_t[[I_Q, I_ZM]] - th_r[[I_Q, I_ZM]]
            try:
                T = float(d @ np.linalg.solve(S_r + S_t, d))
            except np.linalg.LinAlgError:
                continue
            if best[0] is None or T > best[0]:
                best = (T, blocks[j].t0, th_t)
        return best

    def _reset(self, tau: float, th_tail: np.ndarray) -> None:
        """After an alarm: keep the blocks from ``tau`` on and rebuild them with the tail's load estimate."""
        self.change_at = float(tau)
        self._since = float(tau)
        kept = [b for b in self.blocks if b.t0 >= tau - 0.5 * self.T]
        th = self.theta_q.copy()
        th[[I_Q, I_ZM]] = th_tail[[I_Q, I_ZM]]
        self.theta_q = th if self._model_coef(th) is not None else self.theta_q   # an unstable tail load: kept
        raw = np.hstack([b.raw for b in kept])
        warm = ()
        if self.bj:
            if raw.shape[1] > 4 * self.opt.masscm.ar_order:
                self.prefilter, self.lam_loaded, self.prefilter_c = self._fit_prefilter(raw)
            before = [b for b in self.blocks if b.t0 < tau - 0.5 * self.T]
            need = _HIST + transient_samples(self.prefilter_c, self.opt.masscm, int(self.opt.window / self.T))
            warm = before[-int(math.ceil(need / self.nb)):] if before else ()
        elif raw.shape[1] > 4 * self.opt.masscm.ar_order:
            self.prefilter, self.lam_loaded = self._fit_prefilter(raw)
        self._rebuild(kept, warm)
        self.blocks = deque(kept)


def run_monitor(nominal: Trial, calibration: Trial, stream: Trial, known: KnownParams, z_f: float,
                options: MonitorOptions = MonitorOptions(), chunk: int | None = None) -> list[MonitorUpdate]:
    """Feed a recorded stream through :class:`MassCMMonitor` and return every update."""
    mon = MassCMMonitor(nominal, calibration, known, z_f, options)
    return mon.feed_trial(stream, chunk)


__all__ = ["MonitorOptions", "MonitorUpdate", "MassCMMonitor", "run_monitor"]
