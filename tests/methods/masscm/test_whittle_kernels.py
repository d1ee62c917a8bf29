"""Tests of the compiled band kernels (shipid.methods.masscm.whittle_kernels) against the numpy formulas."""

import numpy as np

from shipid.methods.masscm.whittle_kernels import noise_spectrum, ship_columns, transient_normal


def _rand(rng, *shape, cplx=False):
    x = rng.standard_normal(shape)
    return x + 1j * rng.standard_normal(shape) if cplx else x


def test_kernels_match_numpy_forms():
    rng = np.random.default_rng(20261202)
    nz = 37
    z = np.exp(1j * np.sort(rng.uniform(0.01, 3.0, nz)))
    Ad = 0.3 * _rand(rng, 4, 4)                       # spectral radius < 1 (well away from the unit circle)
    b0, b1, c, d0 = _rand(rng, 4), _rand(rng, 4), _rand(rng, 4), _rand(rng, 3)
    C = _rand(rng, 3, 4)
    A, CR = ship_columns(z, Ad, b0, b1, C, d0, c)
    Ra = np.linalg.inv(z[:, None, None] * np.eye(4) - Ad)
    CRr, zz = C @ Ra, z[:, None]
    CR2 = CRr @ Ra
    np.testing.assert_allclose(CR, CRr, rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(A[:, :, :3], np.broadcast_to(np.eye(3), (nz, 3, 3)), atol=0)
    np.testing.assert_allclose(A[:, :, 3], -(CRr @ b0 + zz * (CRr @ b1) + d0), rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(A[:, :, 4], -zz * (CRr @ c), rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(A[:, :, 8], -1j * zz * (CRr @ b1 - CR2 @ b0 - zz * (CR2 @ b1)), rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(A[:, :, 9], -1j * zz * (CRr @ c - zz * (CR2 @ c)), rtol=1e-12, atol=1e-13)
    assert np.all(A[:, :, 5:8] == 0)
    # noise spectrum with waves: F = [[Ad, F12], [0, Aw]], T = H (zI - F)^-1 G + J, S = T T^H + R
    F12, H4, Aw = _rand(rng, 4, 2), _rand(rng, 3, 2), 0.4 * _rand(rng, 2, 2)
    G, J, R = _rand(rng, 6), _rand(rng, 3), np.diag(rng.uniform(0.5, 1.0, 3))
    S, Gam = noise_spectrum(z, CR, F12, H4, Aw, G, J, R, True)
    F = np.block([[Ad, F12], [np.zeros((2, 4)), Aw]])
    H = np.concatenate([C, H4], axis=1)
    HR = H @ np.linalg.inv(z[:, None, None] * np.eye(6) - F)
    T = HR @ G + J
    np.testing.assert_allclose(Gam, z[:, None, None] * HR, rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(S, T[:, :, None] * np.conj(T[:, None, :]) + R, rtol=1e-11, atol=1e-12)
    S0, Gam0 = noise_spectrum(z, CR, F12, H4, Aw, G, J, R, False)
    np.testing.assert_array_equal(S0, np.broadcast_to(R, (nz, 3, 3)))
    np.testing.assert_allclose(Gam0, z[:, None, None] * CRr, rtol=1e-12, atol=1e-13)
    # the transient's normal equations
    M = _rand(rng, nz, 10, 10, cplx=True)
    M = M @ np.conj(np.swapaxes(M, 1, 2))
    Hm, b = transient_normal(A, S, Gam, M)
    WG = np.linalg.inv(S) @ Gam
    e1 = (A @ M[:, :, 4:5])[:, :, 0]
    np.testing.assert_allclose(b, np.real(np.einsum("kil,ki->l", np.conj(WG), e1)), rtol=1e-10)
    Hr = np.real(np.einsum("kil,kim->lm", np.conj(Gam) * np.real(M[:, 4, 4])[:, None, None], WG))
    np.testing.assert_allclose(Hm, Hr, rtol=1e-10, atol=1e-10 * np.max(np.abs(Hr)))
