"""Open-loop validation (issue 6): metrics on constructed cases, CLI on one short real run."""

import json
import subprocess
import sys

import numpy as np
import pytest

import shipid
from shipid.cli import main
from shipid.io import data_root
from shipid.methods.mmg import validate as V
from shipid.models import mmg

ROOT = data_root()
ZIGZAG = "esso_osaka_3m/data/zigzag/zigzag_31-Jul-2020_13_57_45.csv"   # shortest zig-zag (113 s)


def need_data():
    if ROOT is None or not (ROOT / "params").is_dir() or not (ROOT / ZIGZAG).is_file():
        pytest.skip("shared data not found (set SHIPID_DATA)")


def test_model_validated_on_its_own_simulation_has_zero_error(own_run):
    need_data()
    m = mmg.load_published("esso_osaka_3m")
    tr = own_run(m, 100.0, units=True)
    v = V.validate(m, tr)
    for block in list(v.windows.values()) + [v.horizons]:
        for q in V.QUANTITIES:
            assert block[q]["max"] < 1e-9
    assert v.horizons["count"] == 2      # starts at 0 s and 60 s (the second is 40 s long, >= half of 60 s)


def test_wrong_model_has_error_and_heading_is_wrapped(own_run):
    need_data()
    m = mmg.load_published("esso_osaka_3m")
    tr = own_run(m, 70.0, units=True)
    other = m.with_coef({"NR_arm": 0.5 * m.coef["NR_arm"]}, name="half-rudder")
    v = V.validate(other, tr)
    assert v.windows["first_60s"]["psi"]["rms"] > 0.5
    assert v.windows["whole"]["psi"]["max"] <= 180.0


def test_horizon_starts():
    np.testing.assert_array_equal(V.horizon_starts(1300, 600, 600, 300), [0, 600, 1200][:2])
    np.testing.assert_array_equal(V.horizon_starts(1600, 600, 600, 300), [0, 600, 1200])


@pytest.mark.realdata
def test_cli_validate_published_on_real_zigzag(tmp_path, capsys):
    need_data()
    png = tmp_path / "v.png"
    rc = main(["validate", "published:esso_osaka_3m", "--trial", str(ROOT / ZIGZAG), "--json",
               "--plot", str(png)])
    out = capsys.readouterr().out
    assert rc == 0
    d = json.loads(out)
    h = d["horizons"]
    assert h["count"] == 2
    # a real model on a real run: finite, non-zero errors of sensible size (heading within 180 deg)
    assert 0 < h["psi"]["rms"] < 180 and 0 < h["pos"]["rms"] < 50
    assert png.stat().st_size > 1000
    # without --json: the library's summary(), at most 100 columns
    assert main(["validate", "published:esso_osaka_3m", "--trial", str(ROOT / ZIGZAG)]) == 0
    out = capsys.readouterr().out
    assert out == shipid.validate("published:esso_osaka_3m", str(ROOT / ZIGZAG)).summary() + "\n"
    assert max(map(len, out.splitlines())) <= 100 and "psi [deg]" in out and "pos [m]" in out
    # no clobbering of the plot without --force
    assert main(["validate", "published:esso_osaka_3m", "--trial", str(ROOT / ZIGZAG), "--plot", str(png)]) == 2


def test_cli_validate_bad_model_is_one_line(tmp_path):
    bad = tmp_path / "m.json"
    bad.write_text(json.dumps({"method": "mmg-ebm", "model": {"family": "dp"}, "estimates": {}}))
    run = tmp_path / "r.csv"
    run.write_text("t [s],x [m]\n0,0\n")
    p = subprocess.run([sys.executable, "-m", "shipid", "validate", str(bad), "--trial", str(run)],
                       capture_output=True, text=True)
    assert p.returncode == 2
    assert p.stderr.count("\n") == 1 and "not hold an MMG model" in p.stderr
    # a method without an open-loop model: one line naming those that have one
    bad.write_text(json.dumps({"method": "kalman", "model": {}, "estimates": {}}))
    p = subprocess.run([sys.executable, "-m", "shipid", "validate", str(bad), "--trial", str(run)],
                       capture_output=True, text=True)
    assert p.returncode == 2
    assert p.stderr.count("\n") == 1 and "'kalman' result cannot be validated" in p.stderr
