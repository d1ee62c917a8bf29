"""Run i's randomness depends on (campaign seed, i) only."""

import numpy as np
import pytest

from shipid.errors import ShipidError
from shipid.campaign.seeding import check_seed, run_entropy, run_rng, run_seed_sequence


def test_run_stream_is_seedsequence_of_seed_and_index():
    a = run_rng(7, 3).standard_normal(5)
    b = np.random.default_rng(np.random.SeedSequence([7, 3])).standard_normal(5)
    np.testing.assert_array_equal(a, b)
    assert run_entropy(7, 3) == [7, 3]
    assert run_seed_sequence(7, 3).entropy == [7, 3]


def test_streams_differ_between_runs_and_seeds():
    draws = {tuple(run_rng(s, i).integers(0, 2**62, 4)) for s in (0, 1) for i in range(50)}
    assert len(draws) == 100


@pytest.mark.parametrize("bad", [-1, 1.5, "3", True, None])
def test_bad_seed_is_refused(bad):
    with pytest.raises(ShipidError):
        check_seed(bad)


def test_numpy_integer_seed_accepted():
    assert check_seed(np.int64(5)) == 5
