"""The blocked lag products of the numpy moments path (:func:`shipid.methods.masscm.moments.lag_products`)
against the explicit instrument matrix (45)."""

import numpy as np
import pytest

from shipid.estimate.iv import lag_gram
from shipid.methods.masscm import moments
from shipid.methods.masscm.moments import lag_products


def _explicit(F, nls, P, s):
    n = F.shape[1]
    ZT = np.array([F[k, s - i:n - i] for k, nl in enumerate(nls) for i in range(nl)])
    return ZT @ ZT.T, ZT @ P.T, ZT


@pytest.mark.parametrize("nls", [(16, 16, 16, 2), (15, 7, 0, 3), (1, 0, 9, 2)])
def test_lag_products_equal_the_explicit_products(nls):
    rng = np.random.default_rng(list(nls))
    n, s = 3001, 20
    F = rng.standard_normal((4, n)) * np.array([[1e-3], [2.0], [0.5], [1e-2]])
    P = rng.standard_normal((6, n))[:, s:]
    ZtZ, ZtP = lag_products(F, nls, P, s)
    G, R, ZT = _explicit(F, nls, P, s)
    scale = np.sqrt(np.outer(np.diag(G), np.diag(G)))
    assert np.max(np.abs(ZtZ - G) / scale) < 1e-12
    assert np.allclose(ZtP, R, rtol=1e-12, atol=1e-12 * np.abs(R).max())
    # the blocks make the same products as the whole-matrix reference (lag_gram on Z^T)
    lag = np.concatenate([np.arange(nl) for nl in nls if nl])
    h = np.array([F[k, s - 1 - i] for k, nl in enumerate(nls) for i in range(nl)])
    ref = lag_gram(ZT, h, tuple(nl for nl in nls if nl))
    assert lag.size == ZtZ.shape[0]
    assert np.max(np.abs(ZtZ - ref) / scale) < 1e-13


def test_lag_products_do_not_depend_on_the_block_size(monkeypatch):
    rng = np.random.default_rng(7)
    n, s, nls = 2001, 17, (16, 16, 16, 2)
    F = rng.standard_normal((4, n))
    P = rng.standard_normal((6, n))[:, s:]
    out = {}
    for b in (4, 8, 16, 64):
        monkeypatch.setattr(moments, "LAG_BLOCK", b)
        out[b] = lag_products(F, nls, P, s)
    for b in (4, 16, 64):
        for x, y in zip(out[b], out[8]):
            assert np.allclose(x, y, rtol=1e-13, atol=1e-13 * np.abs(y).max())


@pytest.mark.parametrize("compute", ["reference", "fast"])
def test_iir_prefiltered_moments_equal_the_explicit_path(compute):
    """:func:`~shipid.methods.masscm.moments.filtered_lag_moments` (compiled filter and lag products) against the
    explicit instrument matrix, lfilter and :func:`~shipid.estimate.iv.iv_compress` (``explicit_moments=True``),
    for a Box–Jenkins prefilter ``D(q)/(1 - c q^-2)^2`` on simulated data with sensor noise and waves."""
    from shipid.estimate.arma import ARMA
    from shipid.methods.masscm.data import prepare
    from shipid.methods.masscm.moments import build_moments
    from shipid.methods.masscm.noise_bj import ma_poly
    from shipid.methods.masscm.options import MassCMOptions
    from shipid.models.roll_sim import NoiseSpec, simulate_datasets

    d = simulate_datasets("fishing-vessel", seed=np.random.SeedSequence([23, 1]), duration=60.0,
                          noise=NoiseSpec.combined())
    rng = np.random.default_rng(11)
    opt = MassCMOptions(compute=compute)
    prep = prepare(list(d.items()), opt)
    L = [ARMA(np.concatenate([[1.0], 0.05 * rng.standard_normal(opt.ar_order)]), ma_poly(0.97, 2), 1.0)
         for _ in prep]
    y_hats = [ds.y_hat0 + 1e-3 * rng.standard_normal(ds.y.size) for ds in prep]
    a_hats = [ds.a_hat0 for ds in prep]
    new = build_moments(prep, L, y_hats, a_hats, opt)
    ref = build_moments(prep, L, y_hats, a_hats, MassCMOptions(compute=compute, explicit_moments=True))
    for a, b in zip(new, ref):
        # R is unique up to the signs of its rows: compare R^T R, R^T r and the residual part; rss0 is the
        # projected |y|^2 minus its fitted part r^T r (a difference), so it is compared on the scale of |y|^2
        assert a.n == b.n and a.rank_ok == b.rank_ok
        assert np.allclose(a.R.T @ a.R, b.R.T @ b.R, rtol=1e-10, atol=1e-12 * np.abs(b.R).max() ** 2)
        assert np.allclose(a.R.T @ a.r, b.R.T @ b.r, rtol=1e-10, atol=1e-12 * np.abs(b.R.T @ b.r).max())
        assert abs(a.rss0 - b.rss0) <= 1e-10 * (b.r @ b.r + b.rss0)
