"""The batched row integrator of the MMG studies against the one Python source (Yoshimura & Yasukawa MMG).

:func:`shipid.methods.mmg.manoeuvres.rows_rk4` steps many rows, each with its own coefficients, by the
package's one RK4 (:func:`shipid.numerics.integrate.rk4_propagate`) on a row-wise form of the model.
Each row must equal one RK4 step of :func:`shipid.models.mmg.dynamics` (``f(t, x, u, θ)``) with that
row's coefficients, to rounding (rtol 1e-12: the row form sums the coefficient products by einsum).
"""

from __future__ import annotations

import numpy as np
import pytest

from shipid.io import data_root
from shipid.methods.mmg import manoeuvres as MM
from shipid.models import mmg
from shipid.numerics.integrate import rk4_step


@pytest.fixture(scope="module")
def esso():
    root = data_root()
    if root is None or not (root / "params").is_dir():
        pytest.skip("shared data (params/) not found (set SHIPID_DATA)")
    return mmg.load_published("esso_osaka_3m")        # has wind geometry: the air terms are exercised


@pytest.mark.parametrize("wind", [False, True])
def test_rows_rk4_is_rk4_step_of_dynamics_per_row(esso, wind):
    rng = np.random.default_rng(11)
    B = 4
    names = ["N_r", "Y_v"]
    vals = np.array([[esso.coef[c] for c in names]]) * (1.0 + 0.2 * rng.standard_normal((B, 2)))
    Th = MM.theta_rows(esso, names, vals)
    x = np.column_stack([rng.normal(0, 10, B), rng.normal(0, 10, B), rng.uniform(-np.pi, np.pi, B),
                         rng.uniform(0.5, 1.2, B), rng.normal(0, 0.05, B), rng.normal(0, 0.01, B)])
    delta, n = rng.uniform(-0.6, 0.6, B), rng.uniform(5.0, 12.0, B)
    w = (rng.uniform(0.0, 2.0, B), rng.uniform(-np.pi, np.pi, B)) if wind else None
    h = np.array([[0.1], [0.2], [0.05], [0.3]])
    got = MM.rows_rk4(esso, Th, x, delta, n, h, wind=w)
    for i in range(B):
        model_i = esso.with_coef(dict(zip(names, vals[i])))
        u_i = np.array([delta[i], n[i]] + ([w[0][i], w[1][i]] if wind else [0.0, 0.0]))
        want = rk4_step(mmg.dynamics, 0.0, x[i], u_i, model_i, float(h[i, 0]))
        np.testing.assert_allclose(got[i], want, rtol=1e-12, atol=1e-12 * np.abs(want).max())
        assert not np.allclose(want, x[i])
