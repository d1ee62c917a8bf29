"""Shared fixtures of the MMG force-model tests: the KVLCC2 L7 set (read at run time from ``data_root()/params``,
never copied; skipped when absent), random manoeuvring states, and a model with particulars overridden."""

from dataclasses import replace

import numpy as np
import pytest

from shipid.io import data_root
from shipid.models import mmg


@pytest.fixture
def kvlcc2_l7():
    root = data_root()
    if root is None or not (root / "params").is_dir():
        pytest.skip("shared data (params/) not found (set SHIPID_DATA)")
    return mmg.load_published("kvlcc2_L7")


@pytest.fixture
def mmg_states():
    """``mmg_states(seed) -> (u, v, r, delta, n)``: 200 states around the L7 model's approach (1.179 m/s,
    10.23 rps), |delta| <= 35 deg, drawn from ``default_rng(seed)``."""
    def states(seed: int, k: int = 200):
        rng = np.random.default_rng(seed)
        u = 1.179 * (1 + 0.1 * rng.standard_normal(k))
        v = 0.1 * rng.standard_normal(k)
        r = 0.05 * rng.standard_normal(k)
        delta = np.deg2rad(rng.uniform(-35, 35, k))
        return u, v, r, delta, np.full(k, 10.23)
    return states


@pytest.fixture
def with_part():
    """``with_part(model, **particulars)``: the model with those particulars set."""
    return lambda m, **kw: replace(m, particulars=dict(m.particulars, **kw))
