"""The MMG coverage task: deterministic for a given seed, the free coefficients compared with the truth."""

import numpy as np
import pytest

from shipid.data import data_root

pytestmark = pytest.mark.skipif(not (data_root() / "params").exists(), reason="shared data (Esso Osaka params) absent")


def test_run_one_deterministic_and_complete():
    from shipid.methods.mmg.coverage import run_one

    a = run_one(0, np.random.SeedSequence([7, 0]), seconds=60.0)
    b = run_one(0, np.random.SeedSequence([7, 0]), seconds=60.0)
    assert a == b
    assert a["coefficients"] and all(np.isfinite(c["true"]) for c in a["coefficients"].values())
    assert {"Y_v", "N_r"} <= set(a["coefficients"])
