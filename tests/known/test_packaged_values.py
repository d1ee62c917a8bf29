"""The published values shipid ships (vessel files, paper columns of its studies) equal the papers'.

The estimators never read these (they are compared with, not used); a typo in a vessel file or a
study's "paper" column would make every comparison with the paper wrong, so each is checked against
the values typed from the paper in :mod:`known`.
"""

from __future__ import annotations

import numpy as np
import pytest
from known import fossen1996, linder2015, yoon_rhee2003

from shipid.methods.ebm.design import PAPER_FIG7
from shipid.methods.ebm.study import PAPER_TABLE4
from shipid.methods.masscm.study import table3
from shipid.models import dp
from shipid.models.roll_reduced import KnownParams
from shipid.vessels import load_vessel


def test_linder2015_table3_true_mean_std():
    t = table3()
    for i, name in enumerate(linder2015.NAMES):
        assert t[name]["true"] == pytest.approx(linder2015.TABLE3_TRUE[i], rel=1e-12)
        assert t[name]["paper_mean"] == pytest.approx(linder2015.TABLE3_MEAN[i], rel=1e-12)
        assert t[name]["paper_std"] == pytest.approx(linder2015.TABLE3_STD[i], rel=1e-12)


def test_linder2015_table2_known_quantities():
    kn = KnownParams.from_vessel("fishing-vessel")
    for name, value in linder2015.TABLE2_KNOWN.items():
        assert getattr(kn, name) == pytest.approx(value, rel=1e-12)
    gen = load_vessel("fishing-vessel").values("general")
    for name, value in linder2015.TABLE2_LOAD.items():
        assert gen[name] == pytest.approx(value, rel=1e-12)


def test_fossen1996_supply_vessel():
    v = dp.dp_vessel(load_vessel("supply"))
    np.testing.assert_allclose(v.theta, fossen1996.THETA_EQ46_49, rtol=1e-12)
    np.testing.assert_allclose(v.A_h, fossen1996.A_H_EQ48, rtol=1e-12)
    np.testing.assert_allclose(v.K, fossen1996.K_EQ49, rtol=1e-12)
    np.testing.assert_allclose(v.T(np.pi / 2), fossen1996.T_EQ29, rtol=1e-12, atol=1e-12)


def test_yoon_rhee2003_table4_and_fig7():
    for mode, row in yoon_rhee2003.TABLE4.items():
        assert PAPER_TABLE4[mode] == pytest.approx(row, rel=1e-12)
    assert PAPER_FIG7 == yoon_rhee2003.FIG7_OPTIMUM
    c = load_vessel("esso-osaka").values("abkowitz")
    for name, value in yoon_rhee2003.TABLE3_TRUE.items():
        assert c[name] == pytest.approx(value, rel=1e-12)
