"""Every real run in ../shared/data reads into SI channels with plausible ranges.

Skipped cleanly when the data folder is absent (see :func:`shipid.io.paths.data_root`).

Known defects, as observed by scanning every file (not only as the README says):

* ``esso_osaka_3m/data/zigzag/zigzag_31-Jul-2020_13_50_28.csv``: data rows 1702-2028
  (327 rows, the end of the file) are ``,,,,,,,,,,,,`` — every cell empty. Reported as
  an error by default; readable with ``trim_empty_rows=True`` (the trim is recorded).
  Interpolation cannot repair it (nothing follows the empty rows).
* "Some random runs have time gaps": no file has a gap *inside* it (every step of every
  Esso run is 0.1 s within 1e-6 s). The gap is between the parts of the run
  ``random_06-Aug-2020_16_24_25``: parts _1, _3, _4, _5, _6 exist, part _2 does not;
  _1 covers t = 0-671.6 s and _3 starts at t = 1176.1 s (504.5 s missing), while
  _3 → _4 → _5 → _6 continue each other at 0.1 s steps. Joining _1 and _3 is reported
  as a time gap; joining _3 ... _6 is clean.
* KVLCC2: no defects found (20 Hz, no gaps, no missing values).
"""

from pathlib import Path

import numpy as np
import pytest

from shipid.io import data_root, read_trial
from shipid.io.combine import concat_trials
from shipid.errors import InputError

pytestmark = pytest.mark.realdata

ROOT = data_root()
ESSO = ROOT / "esso_osaka_3m" / "data" if ROOT else None
KVLCC2 = ROOT / "kvlcc2_hsva" if ROOT else None
ESSO_DEFECTIVE = {"zigzag/zigzag_31-Jul-2020_13_50_28.csv": (1702, 2028)}   # (first, last) empty row
RANDOM_PARTS = "random/random_06-Aug-2020_16_24_25_{}.csv"


def need(folder):
    if folder is None or not folder.is_dir():
        pytest.skip("real data not found (set SHIPID_DATA or place it at ../shared/data)")


def esso_files():
    need(ESSO)
    return sorted(ESSO.glob("*/*.csv"))


def test_every_esso_run_reads_into_si_ranges():
    files = esso_files()
    assert len(files) == 41                     # data/README.md: 15 turning, 9 zig-zag, 9 random, 8 berthing
    counts = {}
    for f in files:
        rel = f.relative_to(ESSO).as_posix()
        counts[f.parent.name] = counts.get(f.parent.name, 0) + 1
        if rel in ESSO_DEFECTIVE:
            continue
        tr = read_trial(f, required=["x", "y", "psi", "u", "v", "r", "n", "delta"])
        assert tr.meta["profile"] == "esso" and tr.meta["repairs"] == []
        assert tr.meta["manoeuvre"] == f.parent.name
        assert tr.dt == pytest.approx(0.1, abs=1e-9)              # 10 Hz
        assert len(tr) > 900
        # 3 m model at pond speeds (Wakita et al. 2022): well under 1 m/s
        assert np.all(np.abs(tr["u"]) < 1.0), rel
        assert np.all(np.abs(tr["v"]) < 0.5), rel
        assert np.all(np.abs(tr["r"]) < 0.5), rel
        assert np.all(np.abs(tr["n"]) <= 25.0), rel                # propeller revolutions, rps
        assert np.all(np.abs(tr["delta"]) <= np.deg2rad(45.0)), rel
        assert np.all(np.abs(tr["psi"]) <= np.pi + 1e-9), rel      # heading wrapped to [-pi, pi]
        assert np.all(np.abs(tr["x"]) < 100) and np.all(np.abs(tr["y"]) < 100), rel
        for w in ("wind_speed", "wind_speed_rel"):
            assert np.all((tr[w] >= 0) & (tr[w] < 15.0)), rel
        for w in ("wind_dir", "wind_dir_rel"):
            assert np.all((tr[w] >= 0) & (tr[w] <= 2 * np.pi + 1e-9)), rel
        # columns mapped the right way round: surge from the track agrees with u_velo
        c, s = np.cos(tr["psi"]), np.sin(tr["psi"])
        u_track = np.gradient(tr["x"], tr.t) * c + np.gradient(tr["y"], tr.t) * s
        assert np.corrcoef(u_track, tr["u"])[0, 1] > 0.5, rel
    assert counts == {"turning": 15, "zigzag": 9, "random": 9, "berthing": 8}


def test_esso_empty_cells_are_reported_not_accepted():
    need(ESSO)
    rel = next(iter(ESSO_DEFECTIVE))
    first, last = ESSO_DEFECTIVE[rel]
    path = ESSO / rel
    with pytest.raises(InputError) as err:
        read_trial(path)
    assert f"channel 't', row {first}: missing value" in str(err.value)
    with pytest.raises(InputError, match="at the end of the record"):
        read_trial(path, interpolate_gaps=1.0)            # nothing after the gap to interpolate to
    tr = read_trial(path, trim_empty_rows=True)
    assert len(tr) == first - 1
    assert tr.meta["repairs"] == [{"kind": "trimmed_empty_rows", "first_row": first, "last_row": last,
                                   "samples": last - first + 1,
                                   "text": f"removed {last - first + 1} empty rows {first}-{last} at the end"}]
    assert np.all(np.isfinite(tr.stack(tr.names)))


def test_random_run_parts_gap_is_reported():
    need(ESSO)
    parts = {k: read_trial(ESSO / RANDOM_PARTS.format(k)) for k in (1, 3, 4, 5, 6)}
    assert not (ESSO / RANDOM_PARTS.format(2)).exists()
    assert parts[1].t[0] == 0.0 and parts[3].t[0] == pytest.approx(1176.1)

    def join(keys, **kw):
        return concat_trials([parts[k] for k in keys], **kw)

    whole = join([3, 4, 5, 6])                               # consecutive parts: one clean record
    assert whole.meta["repairs"] == [] and whole.t[-1] == pytest.approx(3917.2)
    assert len(whole) == sum(len(parts[k]) for k in (3, 4, 5, 6))
    with pytest.raises(InputError, match=r"time gap of 504\.5 s"):
        join([1, 3])
    with pytest.raises(InputError, match="longer than --interpolate-gaps 1 s"):
        join([1, 3], interpolate_gaps=1.0)


def test_every_kvlcc2_zigzag_reads_into_si_ranges():
    need(KVLCC2)
    files = sorted(KVLCC2.glob("*.dat"))
    assert len(files) == 13
    for f in files:
        tr = read_trial(f, required=["x", "y", "psi", "u", "v", "r", "delta", "n"])
        assert tr.meta["repairs"] == []
        # the facility of the HSVA CPMC runs (the test report: 6.0 m water depth, h/T 13.2)
        assert tr.meta["water_depth"] == 6.0 and "h/T 13.2" in tr.meta["water_depth_source"]
        assert tr.dt == pytest.approx(0.05, abs=1e-9)              # 20 Hz
        # approach speed U0 = 1.179 m/s and n = 10.23 rps (data/README.md)
        assert tr["u"][0] == pytest.approx(1.179, abs=0.01), f.name
        assert np.all((tr["u"] > 0.5) & (tr["u"] < 1.3)), f.name
        assert np.all(np.abs(tr["v"]) < 0.6), f.name
        np.testing.assert_allclose(tr["n"], 10.23, atol=0.01)
        # rudder amplitude is the first number of the name: ..._Z_<delta>_<psi>
        amp = float(f.stem.split("_")[4])
        assert np.max(np.abs(tr["delta"])) == pytest.approx(np.deg2rad(amp), abs=np.deg2rad(0.2)), f.name
        # yaw rate column is the heading's derivative (column order check, deg -> rad both)
        r_psi = np.gradient(tr["psi"], tr.t)
        assert np.max(np.abs(r_psi - tr["r"])) < np.deg2rad(0.5), f.name
        # observed minimum 0.995 (Z 5/1: smallest yaw rates, so sensor noise weighs most)
        assert np.corrcoef(r_psi, tr["r"])[0, 1] > 0.99, f.name
