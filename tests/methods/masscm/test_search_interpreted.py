"""The interpreted map (33) of the residual functions gives the compiled kernel's numbers exactly."""

import numpy as np

from shipid.methods.masscm.search import g_and_jac, g_and_jac_py


def test_interpreted_g_and_jac_is_bit_identical_to_the_compiled_kernel():
    rng = np.random.default_rng(20261202)
    code = np.array([0, 1, 2, 2, 0], dtype=np.int64)
    for _ in range(500):
        th = rng.standard_normal(9) * rng.uniform(0.01, 10.0, 9)
        kc = rng.uniform(0.01, 5.0, 7)
        Ts = rng.uniform(0.005, 0.2, code.size)
        for jac in (False, True):
            G, J = g_and_jac(th, code, Ts, kc, jac)
            Gp, Jp = g_and_jac_py(th, code, Ts, kc, jac)
            assert np.array_equal(G, Gp) and np.array_equal(J, Jp)
            assert J.shape == ((code.size, 5, 9) if jac else (0, 5, 9))
