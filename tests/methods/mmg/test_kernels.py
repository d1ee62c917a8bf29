"""The compiled step 1 (shipid.methods.mmg.kernels) against the reference CD-EKF + RTS."""

import numpy as np
import pytest

from shipid.io.trial import Trial
from shipid.numerics import numba_linalg
from shipid.errors import ShipidError
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import kernels
from shipid.numerics.integrate import rk4_propagate


def _trial(seed: int, n: int = 900, gaps: bool = False) -> Trial:
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 0.1
    r = 0.05 * np.sin(0.05 * t)
    psi = np.cumsum(r) * 0.1
    u = 0.5 + 0.05 * np.cos(0.03 * t)
    v = 0.02 * np.sin(0.07 * t)
    x = np.cumsum(u * np.cos(psi) - v * np.sin(psi)) * 0.1
    y = np.cumsum(u * np.sin(psi) + v * np.cos(psi)) * 0.1
    ch = {"x": x + 0.02 * rng.standard_normal(n), "y": y + 0.02 * rng.standard_normal(n),
          "psi": psi + 0.005 * rng.standard_normal(n), "u": u + 0.01 * rng.standard_normal(n),
          "v": v + 0.01 * rng.standard_normal(n), "r": r + 0.003 * rng.standard_normal(n),
          "delta": 0.1 * np.sign(np.sin(0.05 * t)), "n": np.full(n, 10.0)}
    if gaps:
        ch["x"][100:110] = np.nan
        ch["r"][300] = np.nan
    return Trial(t, ch, {}, {"source": f"synthetic-{seed}"})


@pytest.mark.parametrize("gaps", [False, True])
def test_compiled_step1_equals_reference(gaps):
    tr = _trial(3, gaps=gaps)
    a = R.smooth_run(tr, compiled=True)
    b = R.smooth_run(tr, compiled=False)
    scale = np.abs(b.s).max(axis=0) + 1e-12
    assert np.max(np.abs(a.s - b.s) / scale) < 1e-10
    assert np.max(np.abs(a.s_std - b.s_std) / b.s_std.max(axis=0)) < 1e-10
    assert a.nis_mean == pytest.approx(b.nis_mean, rel=1e-10)
    assert a.loglik == pytest.approx(b.loglik, rel=1e-10)


def test_compiled_step1_fails_loudly_on_a_broken_run():
    tr = _trial(4)
    bad = tr.with_channels(u=np.full(len(tr), np.inf))
    with pytest.raises(ShipidError, match="motion estimation failed"):
        R.smooth_run(bad, compiled=True)


def test_numba_linalg_cache_key_is_current():
    """kernels.py keys its numba disk cache on numerics/numba_linalg.py (numba does not see that dependency).

    If this fails, numba_linalg.py was edited: set ``NUMBA_LINALG_KEY`` in
    ``shipid/methods/mmg/kernels.py`` to the value printed, which also refreshes that file's cache.
    """
    key = numba_linalg.source_key(numba_linalg)
    assert key == kernels.NUMBA_LINALG_KEY, f"set NUMBA_LINALG_KEY = {key!r} in shipid/methods/mmg/kernels.py"
    assert kernels.CACHE_VALID


def test_compiled_kinematic_rk4_is_the_one_rk4():
    """kernels._kin_rk4 (inside the compiled filter) = numerics.integrate.rk4_propagate on estimator.kinematic_f."""
    rng = np.random.default_rng(5)
    for _ in range(5):
        x = np.concatenate([rng.normal(0, 50, 2), [rng.uniform(-np.pi, np.pi)], rng.normal(0, 1, 3),
                            rng.normal(0, 0.1, 3)])
        h = rng.uniform(0.01, 1.0)
        want = rk4_propagate(R.kinematic_f, 0.0, x, h, 1, (np.zeros(0), None))
        got = x.copy()
        w = [np.empty(9) for _ in range(5)]
        kernels._kin_rk4(got, h, *w)
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())
        assert not np.allclose(got, x)
