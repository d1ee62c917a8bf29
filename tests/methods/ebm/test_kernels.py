"""The compiled EBM path (:mod:`shipid.methods.ebm.compiled`, :mod:`~shipid.methods.ebm.kernels`,
:mod:`~shipid.methods.ebm.model_kernels`) equals its one reference.

The model equations are stated once, in :class:`~shipid.models.ebm_state.EbmModel`; the numba
kernels of ``f, F, h, H`` must equal it on random states and random parameters, and the compiled
RK4 must equal the one RK4 :func:`shipid.numerics.integrate.rk4_propagate`. The compiled filter and
smoothers must equal the pure-Python :func:`shipid.estimate.cd_ekf.cd_ekf` with the ``EbmModel``
callables and :mod:`shipid.estimate.smoothers` (seed 002 eqs. 9–10) on the same short seeded
simulated trial, to 1e-9 relative (the two differ only in the order of floating-point operations,
measured ~1e-11).

The numba compilation is cached on disk (``cache=True``): only the first run on a
machine compiles (~30 s); later runs load it in well under a second.
"""

from dataclasses import replace

import numpy as np
import pytest

from shipid.numerics import numba_linalg
from shipid.estimate.cd_ekf import cd_ekf
from shipid.numerics.linalg import NotPositiveDefiniteError
from shipid.estimate.smoothers import mbf_smoother, rts_smoother
from shipid.methods.ebm import compiled as fast
from shipid.methods.ebm import estimator as ebm
from shipid.methods.ebm import kernels, model_kernels
from shipid.methods.ebm.trials import simulate_trial
from shipid.models import abkowitz as ab
from shipid.models.ebm_state import NX, EbmModel, initial_state, measurement_noise
from shipid.numerics.integrate import rk4_propagate

RTOL = 1e-9


@pytest.fixture(scope="module")
def problem():
    tr = simulate_trial("zigzag-20", 150.0, seed=4)
    p = ab.params_from_vessel()
    tc = ab.trial_conditions()
    cfg = ebm.EbmConfig()  # rudder_q_gain > 0: Q per sample interval
    model = EbmModel.from_abkowitz(p, tc["x_D"], tc["y_D"], tc["y_S"], q_force=cfg.q_force,
                                   q_current=cfg.q_current)
    Q = ebm.process_noise(model, np.asarray(tr["delta"], dtype=float), cfg)
    R = measurement_noise(tc["sigma_xy"], tc["sigma_xy_dot"], tc["sigma_psi"], tc["sigma_u_log"])
    z = ebm.measurements(tr)
    t = tr.t - tr.t[0]
    return dict(tr=tr, p=p, model=model, Q=Q, R=R, z=z, t=t, x0=initial_state(z[0], model),
                P0=ebm.prior_cov(False))


def _reference(pb, **kw):
    m = kw.get("model", pb["model"])
    return cd_ekf(m.f, m.F, m.h, m.H, kw.get("Q", pb["Q"]), pb["R"], pb["t"], kw.get("z", pb["z"]), pb["x0"],
                  kw.get("P0", pb["P0"]), substeps=kw.get("substeps", 1))


def _compiled(pb, **kw):
    return fast.ebm_cd_ekf(kw.get("model", pb["model"]), kw.get("Q", pb["Q"]), pb["R"], pb["t"],
                           kw.get("z", pb["z"]), pb["x0"], kw.get("P0", pb["P0"]),
                           **{k: v for k, v in kw.items() if k in ("tol", "max_terms", "substeps")})


def _close(a, b, rtol=RTOL):
    """|a − b| ≤ rtol × (largest |b| of that component over the samples); NaNs must coincide."""
    a, b = np.asarray(a), np.asarray(b)
    np.testing.assert_array_equal(np.isnan(a), np.isnan(b))
    scale = np.nanmax(np.abs(b), axis=0)
    scale = np.where(scale > 0, scale, 1.0)
    err = np.nan_to_num(np.abs(a - b)) / scale
    assert err.max() <= rtol, f"max relative difference {err.max():.3g}"


def _assert_filters_equal(fa, fb):
    for name in ("x_pred", "P_pred", "x_filt", "P_filt", "Phi", "Qd", "innov", "S", "K", "H", "nis",
                 "HtSinv_nu", "HtSinv_H"):
        _close(getattr(fa, name), getattr(fb, name))
    assert fa.loglik == pytest.approx(fb.loglik, rel=RTOL)


def _assert_smoothers_equal(sa, sb, fr):
    _close(sa.x, sb.x)
    # P(k|N) = P(k|k) − … cancels strongly for the well-determined states (the current's
    # variance falls by ~1e6 from the prior), so rounding in either path is ~eps·|P(k|k)|,
    # not ~eps·|P(k|N)|: compare relative to the *filtered* standard deviations.
    sd = np.sqrt(np.einsum("kii->ki", fr.P_filt))
    err = np.abs(sa.P - sb.P) / (sd[:, :, None] * sd[:, None, :])
    assert err.max() <= RTOL, f"max difference of smoothed P / (σ_i σ_j filtered) {err.max():.3g}"


@pytest.mark.parametrize("absolute", [False, True])
def test_kernels_equal_model_methods(problem, absolute):
    m = problem["model"]
    if absolute:
        m = replace(m, absolute=True)
    p = m.kernel_params()
    rng = np.random.default_rng(5)
    for _ in range(5):
        x = problem["x0"] + rng.normal(size=17) * np.array([1, 1, 1e-2, 10, 10, 1, 1e6, 1e4, 1e2, 1e6, 1e4, 1e2,
                                                                1e8, 1e6, 1e4, 0.5, 0.5])
        tk = float(rng.uniform(0, 100))
        for kern, meth in ((model_kernels.ebm_f, m.f), (model_kernels.ebm_F, m.F), (model_kernels.ebm_h, m.h),
                           (model_kernels.ebm_H, m.H)):
            np.testing.assert_allclose(kern(p, tk, x), meth(tk, x), rtol=1e-14, atol=1e-300)


def _random_model(rng, absolute):
    """An EbmModel with random mass, centre of gravity, inverse mass matrix and sensor lever arms."""
    Minv = rng.normal(size=(3, 3)) * np.array([1e-6, 1e-6, 1e-9])[:, None]
    return EbmModel(m=float(rng.uniform(1e3, 1e7)), x_G=float(rng.normal(0, 5)), Minv=Minv,
                    x_D=float(rng.normal(0, 20)), y_D=float(rng.normal(0, 5)), y_S=float(rng.normal(0, 5)),
                    absolute=absolute)


def _random_state(rng):
    scale = np.array([5, 1, 0.05, 1e3, 1e3, np.pi, 1e6, 1e4, 1e2, 1e6, 1e4, 1e2, 1e8, 1e6, 1e4, 1, 1])
    return rng.normal(size=NX) * scale


@pytest.mark.parametrize("absolute", [False, True])
def test_model_kernels_equal_the_model_on_random_parameters_and_states(absolute):
    """The one statement of eqs. 6 and 8 is EbmModel; the numba kernels must compute the same values."""
    rng = np.random.default_rng(11)
    for _ in range(20):
        m = _random_model(rng, absolute)
        p = m.kernel_params()
        x, tk = _random_state(rng), float(rng.uniform(0, 3600))
        for kern, meth in ((model_kernels.ebm_f, m.f), (model_kernels.ebm_F, m.F), (model_kernels.ebm_h, m.h),
                           (model_kernels.ebm_H, m.H)):
            want = meth(tk, x)
            # the kernels evaluate the same expressions; only libm's cos/sin may round differently
            np.testing.assert_allclose(kern(p, tk, x), want, rtol=1e-13, atol=1e-13 * np.abs(want).max())


@pytest.mark.parametrize("substeps", [1, 3])
def test_compiled_rk4_equals_the_one_rk4(substeps):
    """kernels.rk4_into (inside the compiled filter) is numerics.integrate.rk4_propagate on EbmModel.f."""
    rng = np.random.default_rng(12)
    for _ in range(10):
        m = _random_model(rng, bool(rng.integers(2)))
        x, tk, h = _random_state(rng), float(rng.uniform(0, 100)), float(rng.uniform(0.05, 2.0))
        out, work = np.empty(NX), [np.empty(NX) for _ in range(5)]
        kernels.rk4_into(m.kernel_params(), tk, x, h, substeps, out, *work)
        want = rk4_propagate(m.f, tk, x, h, substeps)
        np.testing.assert_allclose(out, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())


def test_model_kernels_cache_key_is_current():
    """kernels.py keys its numba disk cache on model_kernels.py and numerics/numba_linalg.py
    (numba does not see those dependencies).

    If this fails, one of them was edited: set the key named in ``shipid/methods/ebm/kernels.py``
    to the value printed, which also refreshes that file's cache.
    """
    key = kernels.source_key(model_kernels)
    assert key == kernels.MODEL_KERNELS_KEY, f"set MODEL_KERNELS_KEY = {key!r} in shipid/methods/ebm/kernels.py"
    key = kernels.source_key(numba_linalg)
    assert key == kernels.NUMBA_LINALG_KEY, f"set NUMBA_LINALG_KEY = {key!r} in shipid/methods/ebm/kernels.py"
    assert kernels.CACHE_VALID


@pytest.mark.parametrize("absolute, substeps", [(False, 1), (True, 2)])
def test_compiled_filter_and_smoothers_equal_reference(problem, absolute, substeps):
    kw = dict(model=replace(problem["model"], absolute=absolute), substeps=substeps)
    fb = _reference(problem, **kw)
    fa = _compiled(problem, **kw)
    _assert_filters_equal(fa, fb)
    _assert_smoothers_equal(fast.mbf_smoother_fast(fa), mbf_smoother(fb), fb)
    _assert_smoothers_equal(fast.rts_smoother_fast(fa), rts_smoother(fb), fb)


def test_constant_q_and_missing_measurements(problem):
    z = problem["z"].copy()
    z[7] = np.nan          # a whole sample missing
    z[12, [0, 1]] = np.nan  # DGPS position dropped
    z[20, 4] = np.nan      # gyro dropped
    Q = problem["model"].Q()
    fb = _reference(problem, z=z, Q=Q)
    fa = _compiled(problem, z=z, Q=Q)
    _assert_filters_equal(fa, fb)
    np.testing.assert_array_equal(fa.x_filt[7], fa.x_pred[7])
    assert np.isnan(fa.nis[7]) and np.all(fa.H[12, :2] == 0) and np.isnan(fa.innov[20, 4])
    _assert_smoothers_equal(fast.mbf_smoother_fast(fa), mbf_smoother(fb), fb)


def test_unconverged_taylor_series_falls_back_to_reference(problem):
    """With max_terms too small the compiled loop stops; the reference path (Van Loan) runs instead."""
    fa = _compiled(problem, max_terms=3)
    fb = _reference(problem)
    for name in ("x_filt", "P_filt", "Phi"):
        np.testing.assert_array_equal(getattr(fa, name), getattr(fb, name))


def test_not_positive_definite_is_reported_with_sample_index(problem):
    # an indefinite prior on a state no sensor sees directly (Ẍ): the filtered P at sample 0
    P0 = problem["P0"].copy()
    P0[8, 8] = -1.0
    with pytest.raises(NotPositiveDefiniteError, match=r"filter covariance at sample 0 \(t = 0 s\)"):
        _compiled(problem, P0=P0)
    with pytest.raises(NotPositiveDefiniteError, match=r"filter covariance at sample 0 \(t = 0 s\)"):
        _reference(problem, P0=P0)
    # an innovation covariance that is not positive definite
    R = problem["R"].copy()
    R[4, 4] = -1.0  # a negative gyro variance
    pb = dict(problem, R=R)
    for run in (_compiled, _reference):
        with pytest.raises(NotPositiveDefiniteError, match=r"innovation covariance at sample 0"):
            run(pb)


def test_generic_smoothers_equal_reference_on_linear_model():
    """The compiled smoothers read any FilterResult (here the reference filter on a linear model)."""
    F = np.array([[0.0, 1.0, 0.0], [-0.2, -0.1, 1.0], [0.0, 0.0, -0.05]])
    H = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    rng = np.random.default_rng(2)
    t = np.arange(200) * 0.5
    Z = rng.normal(size=(200, 2))
    Z[50] = np.nan
    fr = cd_ekf(lambda t, x, u, th: F @ x, lambda t, x, u, th: F, lambda t, x: H @ x, lambda t, x: H,
                np.diag([0.0, 0.02, 0.01]), np.diag([0.04, 0.25]), t, Z, np.zeros(3), np.eye(3))
    _assert_smoothers_equal(fast.mbf_smoother_fast(fr), mbf_smoother(fr), fr)
    _assert_smoothers_equal(fast.rts_smoother_fast(fr), rts_smoother(fr), fr)


def test_ebm_step1_routes_to_compiled_path_with_same_result(problem):
    tr, p = problem["tr"], problem["p"]
    a = ebm.estimate_states(tr, p)
    b = ebm.estimate_states(tr, p, config=ebm.EbmConfig(compiled=False))
    _close(a.smooth.x, b.smooth.x)
    _close(a.filt.x_filt, b.filt.x_filt)
    np.testing.assert_allclose(a.current, b.current, rtol=RTOL, atol=1e-12)
