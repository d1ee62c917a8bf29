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


def test_scrambled_prior_free_coefficients_give_identical_estimates():
    """No answer in the pipeline: the prior's values of the coefficients being estimated do not enter the fit."""
    from shipid.methods.mmg import coverage as C
    from shipid.methods.mmg.pipeline import identify
    from shipid.models import mmg

    rng = np.random.default_rng(3)
    base = mmg.load_published("esso_osaka_3m")
    truth = C.draw_truth(rng, base)
    trials, _ = C.simulate_campaign(truth, rng, seconds=60.0)
    free, g = set(C.free_coefficients(base)), np.random.default_rng(9)
    scr = mmg.MmgModel(base.structure, dict(base.particulars),
                       {k: (v * g.uniform(-3, 3) if k in free else v) for k, v in base.coef.items()},
                       name="scrambled", sources=dict(base.sources))
    a = identify(trials, base, structure=C.STRUCTURE, select=False, refine="none")
    b = identify(trials, scr, structure=C.STRUCTURE, select=False, refine="none")
    for n in a.covariance_names:
        assert a.estimates[n].value == b.estimates[n].value and a.estimates[n].std == b.estimates[n].std
