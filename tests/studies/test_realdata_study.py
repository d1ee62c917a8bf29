"""Held-out studies on the Esso Osaka and KVLCC2 data (issue 6).

Unmarked: the zig-zag measures on constructed headings and the integrity of the
splits (fast). Marked ``slow`` and ``realdata``: the full studies, asserting the
issue's targets where they are met and the measured numbers where they are not.
"""

import numpy as np
import pytest

from shipid.data import data_root
from shipid.data.trial import Trial
from shipid.studies import realdata_study as S

ROOT = data_root()


def need(sub):
    if ROOT is None or not (ROOT / sub).is_dir():
        pytest.skip("shared data not found (set SHIPID_DATA)")


def test_overshoots_of_a_constructed_heading():
    # heading: +12 deg peak after crossing +10, then -15 deg trough after crossing -10, then back past +10
    t = np.linspace(0, 60, 601)
    psi = np.deg2rad(np.interp(t, [0, 5, 10, 20, 30, 40, 50, 60], [0, 10, 12, 0, -15, 0, 11, 0]))
    o = S.overshoots(t, psi, 0, np.deg2rad(10), side=1)
    np.testing.assert_allclose(np.degrees(o), [2.0, 5.0], atol=1e-9)
    # first to port: mirror image
    o = S.overshoots(t, -psi, 0, np.deg2rad(10), side=-1)
    np.testing.assert_allclose(np.degrees(o), [2.0, 5.0], atol=1e-9)


def test_reversal_delay_of_a_constructed_autopilot():
    t = np.arange(0, 40, 0.05)
    psi = np.deg2rad(np.interp(t, [0, 1, 10, 15, 25, 40], [0, 0, 12, 14, -12, -14]))   # psi = 0 at execute
    k_cross = np.flatnonzero(np.degrees(psi) >= 10)[0]
    delta = np.where(t < 1, 0.0, np.deg2rad(20))
    delta = np.where(t >= t[k_cross] + 0.3, np.deg2rad(-20), delta)
    tr = Trial(t, {"psi": psi, "delta": delta}, {"psi": "rad", "delta": "rad"}, {})
    d = S.reversal_delays(tr, np.deg2rad(10))
    assert d[0] == pytest.approx(0.3, abs=0.051)


def test_zigzag_angles_from_names():
    assert np.degrees(S.zigzag_angles("HSVA_CPMC_KVLCC2_Z_20_10_P.dat")) == pytest.approx((20, 10))
    assert np.degrees(S.zigzag_angles("HSVA_CPMC_KVLCC2_Z_35_05.dat")) == pytest.approx((35, 5))


def test_splits_are_disjoint_and_match_the_readme_counts():
    # README_upstream.md: Miyauchi Train-TRZ has 6 runs and 5 test runs; Wakita Train-TZRB+ 35, test 6
    for name, n_train, n_test in (("miyauchi2022", 6, 5), ("wakita2022", 35, 6)):
        sp = S.SPLITS[name]
        assert len(sp["train"]) == n_train and len(sp["test"]) == n_test
        assert not set(sp["train"]) & set(sp["test"])
    assert not set(S.KVLCC2_TRAIN) & set(S.KVLCC2_TEST) and len(S.KVLCC2_TRAIN) + len(S.KVLCC2_TEST) == 13


@pytest.mark.realdata
def test_split_files_exist():
    need("esso_osaka_3m")
    for sp in S.SPLITS.values():
        for f in sp["train"] + sp["test"]:
            assert (ROOT / "esso_osaka_3m" / "data" / f).is_file(), f


@pytest.mark.slow
@pytest.mark.realdata
def test_esso_miyauchi_split_beats_published_set():
    """Issue 6 target: lower pooled heading and position RMS over restarted 60-s horizons."""
    need("esso_osaka_3m")
    st = S.esso_heldout("miyauchi2022", folds=3)
    p = st["heldout"]["pooled"]
    assert p["identified"]["psi"]["rms"] < p["published"]["psi"]["rms"]
    assert p["identified"]["pos"]["rms"] < p["published"]["pos"]["rms"]
    assert st["result"]["provenance"]["test_runs_never_used"] == S.SPLITS["miyauchi2022"]["test"]
    trained = {r["file"].split("data/")[-1] for r in st["result"]["provenance"]["training_runs"]}
    assert not trained & set(S.SPLITS["miyauchi2022"]["test"])


@pytest.mark.slow
@pytest.mark.realdata
def test_kvlcc2_overshoots_close_to_measured():
    """Issue 6 target is 2 deg; measured when this test was written: largest error 2.19 deg
    (2nd overshoot of 35/5 and 20/10 S; every 1st overshoot within 0.9 deg). The bound is
    2.5 deg so that the test guards the result we have; the 2-deg target is not met."""
    need("kvlcc2_hsva")
    st = S.kvlcc2_zigzag(folds=5)
    errs = [e for row in st["overshoots"] for e in row["identified_error_deg"]]
    assert len(errs) == 6
    assert max(abs(e) for e in errs) < 2.5
    assert sum(abs(e) <= 2.0 for e in errs) >= 4
    p = st["heldout"]["pooled"]
    assert p["identified"]["psi"]["rms"] < p["published"]["psi"]["rms"]


def test_study_cli_bad_split_and_missing_data_are_one_line(tmp_path, monkeypatch, capsys):
    from shipid.cli import main

    assert main(["study", "esso-osaka-heldout", "--split", "bogus"]) == 2
    monkeypatch.setenv("SHIPID_DATA", str(tmp_path))          # a folder without the data sets
    assert main(["study", "kvlcc2-zigzag"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("shipid: error:") and "SHIPID_DATA" in err[-1]
