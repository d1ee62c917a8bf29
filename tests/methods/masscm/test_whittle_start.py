"""Tests of shipid.methods.masscm.whittle_start (the Whittle refinement's sway / yaw row start)."""

import numpy as np

from shipid.methods.masscm import pem, whittle, whittle_start
from shipid.methods.masscm.coverage import REGIMES
from shipid.methods.masscm.crlb_kf import true_free_theta
from shipid.models.roll_reduced import KnownParams
from shipid.models.roll_sim import simulate_datasets
from shipid.vessels import load_vessel

VESSEL = "fishing-vessel"


def test_initial_rows_equal_pem_initial_rows():
    """The one-signal-at-a-time band-pass gives exactly pem's start (same numbers, not just close), at a start
    theta away from the truth."""
    known = KnownParams.from_vessel(VESSEL)
    z_f = float(load_vessel(VESSEL).value("general", "z_f"))
    d = simulate_datasets(VESSEL, seed=np.random.SeedSequence([4253, 0]), duration=120.0, noise=REGIMES["both"])
    th = true_free_theta(VESSEL) * 1.1
    for c, t in d.items():
        s = whittle._FSet(c, t, known, z_f)
        a, b = pem.initial_rows(s, th, known), whittle_start.initial_rows(s, th, known)
        assert a.shape == (12,) and np.all(np.isfinite(a))
        assert np.array_equal(a, b)
