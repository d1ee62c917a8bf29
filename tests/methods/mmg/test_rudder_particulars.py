"""Candidate particulars of the KVLCC2 rudder (shipid.methods.mmg.candidates.apply_candidate, shipid.models.mmg):
the rudder cross-flow part and the side gain."""

import numpy as np
import pytest

from shipid.io import data_root
from shipid.methods.mmg.candidates import apply_candidate
from shipid.models import mmg

ROOT = data_root()


def need(sub):
    if ROOT is None or not (ROOT / sub).is_dir():
        pytest.skip(f"shared data ({sub}/) not found (set SHIPID_DATA)")


def test_rudder_crossflow_adds_the_sin_abs_sin_part_of_the_normal_force():
    """particulars["rudder_crossflow"] = C_Dc: F_N = 0.5 rho A_R U_R^2 (f_a sin a + C_Dc sin a |sin a|);
    absent, the standard method's force exactly."""
    need("params")
    m = mmg.load_published("kvlcc2_hsva")
    m1, _ = apply_candidate(m, {k: () for k in mmg.MODES} | {"particulars": {"rudder_crossflow": 1.0}})
    u, v, r = np.full(3, 1.1), np.array([0.0, 0.05, -0.05]), np.array([0.0, 0.02, -0.03])
    delta, n = np.deg2rad([35.0, -20.0, 10.0]), np.full(3, 10.23)
    a0 = mmg.basis(m, u, v, r, delta, n, 0.0, 0.0)["aux"]
    a1 = mmg.basis(m1, u, v, r, delta, n, 0.0, 0.0)["aux"]
    np.testing.assert_array_equal(a0["alpha_R"], a1["alpha_R"])
    s = np.sin(a0["alpha_R"])
    np.testing.assert_allclose(a1["F_N"], a0["F_N"] * (1 + s * np.abs(s) / (m.particulars["f_alpha"] * s)),
                               rtol=1e-12)
    assert np.all(np.abs(a1["F_N"]) > np.abs(a0["F_N"]))


def test_rudder_side_gain_scales_the_normal_force_per_side():
    """particulars["rudder_side_gain"] = s: F_N (1 + s sign(delta))."""
    need("params")
    m = mmg.load_published("kvlcc2_hsva")
    m1, _ = apply_candidate(m, {k: () for k in mmg.MODES} | {"particulars": {"rudder_side_gain": -0.1}})
    u, v, r = np.full(3, 1.1), np.array([0.0, 0.05, -0.05]), np.array([0.0, 0.02, -0.03])
    delta, n = np.deg2rad([35.0, -20.0, 0.0]), np.full(3, 10.23)
    f0 = mmg.basis(m, u, v, r, delta, n, 0.0, 0.0)["aux"]["F_N"]
    f1 = mmg.basis(m1, u, v, r, delta, n, 0.0, 0.0)["aux"]["F_N"]
    np.testing.assert_allclose(f1, f0 * np.array([0.9, 1.1, 1.0]), rtol=1e-12)
