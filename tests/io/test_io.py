"""Readers and writers: CSV `name [unit]`, Parquet, channel maps, profiles, safe writing."""

import json
import math
import os
from pathlib import Path

import numpy as np
import pytest

from shipid.cli import main
from shipid.io import Trial, parse_channel_map, read_trial, write_trial
from shipid.errors import InputError, OutputExistsError, ShipidError

GOOD = Path(__file__).parent / "good"


def assert_same(a: Trial, b: Trial, rtol=0.0):
    assert a.names == b.names
    assert dict(a.units) == dict(b.units)
    np.testing.assert_allclose(b.t, a.t, rtol=rtol, atol=0)
    for k in a.names:
        np.testing.assert_allclose(b[k], a[k], rtol=rtol, atol=1e-300)


def test_simple_csv_is_converted_to_si():
    tr = read_trial(GOOD / "simple.csv")
    assert len(tr) == 8 and tr.dt == pytest.approx(0.1)
    assert tr.units["psi"] == "rad" and tr.units["u"] == "m/s" and tr.units["n"] == "1/s"
    np.testing.assert_allclose(tr["psi"], np.deg2rad(2.0 * 0.1 * np.arange(8)), rtol=1e-12)
    np.testing.assert_allclose(tr["u"], 1852.0 / 3600.0)          # 1 knot
    np.testing.assert_allclose(tr["r"], math.pi / 90.0)           # 2 deg/s
    np.testing.assert_allclose(tr["delta"], -math.pi / 36.0)      # -5 deg
    np.testing.assert_allclose(tr["n"], 10.0)                     # 600 rpm
    assert tr.meta["units_in"]["n"] == "rpm"
    assert tr.meta["source"] == str(GOOD / "simple.csv")
    assert tr.meta["repairs"] == []


def test_bom_and_crlf_are_accepted():
    raw = (GOOD / "crlf_bom.csv").read_bytes()
    assert raw.startswith(b"\xef\xbb\xbf") and b"\r\n" in raw
    assert_same(read_trial(GOOD / "simple.csv"), read_trial(GOOD / "crlf_bom.csv"))


@pytest.mark.parametrize("ext", [".csv", ".parquet"])
def test_round_trip_exact_in_si(tmp_path, ext):
    tr = read_trial(GOOD / "simple.csv", vessel="test-vessel", manoeuvre="zigzag")
    out = write_trial(tr, tmp_path / f"trial{ext}")
    back = read_trial(out)
    assert_same(tr, back)                     # written with repr / float64: bit-exact
    if ext == ".parquet":
        assert back.meta["vessel"] == "test-vessel" and back.meta["manoeuvre"] == "zigzag"


@pytest.mark.parametrize("ext", [".csv", ".parquet"])
def test_round_trip_in_user_units(tmp_path, ext):
    tr = read_trial(GOOD / "simple.csv")
    out = write_trial(tr, tmp_path / f"trial{ext}", units={"psi": "deg", "n": "rpm", "u": "knot", "t": "min"})
    if ext == ".csv":
        header = out.read_text().splitlines()[0]
        assert header.startswith("t [min],x [m],y [m],psi [deg],u [knot]") and "n [rpm]" in header
    back = read_trial(out)
    assert_same(tr, back, rtol=1e-14)
    assert back.meta["units_in"]["psi"] == "deg"


def test_csv_to_parquet_to_csv(tmp_path):
    tr = read_trial(GOOD / "esso_like.csv")
    p = write_trial(tr, tmp_path / "a.parquet")
    c = write_trial(read_trial(p), tmp_path / "b.csv")
    assert_same(tr, read_trial(c))


def test_writer_never_overwrites_without_force(tmp_path):
    tr = read_trial(GOOD / "simple.csv")
    dest = tmp_path / "t.csv"
    write_trial(tr, dest)
    before = dest.read_bytes()
    with pytest.raises(OutputExistsError):
        write_trial(tr.with_channels(x=tr["x"] + 1.0), dest)
    assert dest.read_bytes() == before
    write_trial(tr.with_channels(x=tr["x"] + 1.0), dest, force=True)
    assert read_trial(dest)["x"][0] == pytest.approx(1.0)
    assert sorted(os.listdir(tmp_path)) == ["t.csv"]          # no temporary files left behind


def test_writer_rejects_unknown_format_and_units(tmp_path):
    tr = read_trial(GOOD / "simple.csv")
    with pytest.raises(ShipidError, match="cannot write format"):
        write_trial(tr, tmp_path / "t.xlsx")
    with pytest.raises(InputError, match="cannot express"):
        write_trial(tr, tmp_path / "t.csv", units={"psi": "m/s"})
    with pytest.raises(InputError, match="no such channel"):
        write_trial(tr, tmp_path / "t.csv", units={"zz": "m"})
    assert not (tmp_path / "t.csv").exists()


def test_esso_profile_is_detected_and_maps_names():
    tr = read_trial(GOOD / "esso_like.csv")
    assert tr.meta["profile"] == "esso"
    assert {"x", "y", "psi", "u", "v", "r", "n", "delta", "wind_speed", "wind_dir",
            "wind_speed_rel", "wind_dir_rel"} == set(tr.names)
    assert tr.meta["columns"]["psi"] == "psi_hat" and tr.meta["columns"]["v"] == "vm_velo"
    assert "manoeuvre" not in tr.meta        # only the data set's own folders (zigzag, ...) name one
    np.testing.assert_allclose(tr["n"], 12.0)


def test_profile_on_wrong_file_is_error():
    with pytest.raises(InputError, match="not in the esso format: column 'x_position_mid' missing"):
        read_trial(GOOD / "simple.csv", fmt="esso")


def test_kvlcc2_layout_derives_body_velocities():
    tr = read_trial(GOOD / "small_hsva.dat")
    assert tr.meta["profile"] == "kvlcc2" and tr.meta["manoeuvre"] == "Z10°/10° made up"
    assert tr.dt == pytest.approx(0.05)
    np.testing.assert_allclose(tr["u"], 1.18)    # psi = 0: u = dx0/dt, v = dy0/dt
    np.testing.assert_allclose(tr["v"], 0.0, atol=1e-15)
    assert tr.units["n"] == "1/s" and tr.units["torque"] == "N*m"


def test_channel_map_with_units_for_bare_headers():
    with pytest.raises(InputError, match="no unit in header cell 'heading'"):
        read_trial(GOOD / "custom_names.csv")
    tr = read_trial(GOOD / "custom_names.csv", channel_map="t=time, psi=heading[deg], u=surge",
                    required=["psi", "u"])
    assert tr.names == ["psi", "u"]
    np.testing.assert_allclose(tr["psi"], np.deg2rad(10.0 * tr.t), rtol=1e-12)
    assert tr.meta["columns"] == {"t": "time", "psi": "heading", "u": "surge"}


def test_channel_map_errors():
    with pytest.raises(InputError, match="not NAME=COLUMN"):
        parse_channel_map("x=a,y")
    with pytest.raises(InputError, match="names 'x' twice"):
        parse_channel_map("x=a,x=b")
    with pytest.raises(InputError, match="no column 'nope'"):
        read_trial(GOOD / "simple.csv", channel_map={"x": "nope"})
    with pytest.raises(InputError, match="header says 'm'"):
        read_trial(GOOD / "simple.csv", channel_map={"x": "x [deg]"})
    assert parse_channel_map(" x = a , u=b [knot] ") == {"x": "a", "u": "b [knot]"}


def test_channel_map_renaming_over_a_profile():
    tr = read_trial(GOOD / "esso_like.csv", channel_map={"U": "u_velo"})
    assert "U" in tr.names and "u" not in tr.names


def test_repairs_only_on_request():
    with pytest.raises(InputError, match="row 5: missing value"):
        read_trial(GOOD / "short_gap.csv")
    tr = read_trial(GOOD / "short_gap.csv", interpolate_gaps=0.25)
    assert len(tr) == 10                                    # the lost sample is back on the grid
    np.testing.assert_allclose(tr["u"], 1.0)
    np.testing.assert_allclose(tr["x"], tr.t, atol=1e-12)
    kinds = [r["kind"] for r in tr.meta["repairs"]]
    assert kinds == ["interpolated", "filled_time_gap"]
    with pytest.raises(InputError, match="non-uniform"):
        read_trial(GOOD / "jittered.csv")
    tr = read_trial(GOOD / "jittered.csv", resample=0.1)
    np.testing.assert_allclose(np.diff(tr.t), 0.1, rtol=1e-9)


def test_parquet_with_units_in_column_names(tmp_path):
    tr = read_trial(GOOD / "simple.csv")
    df = tr.to_frame().reset_index()                      # columns 't [s]', 'x [m]', ...
    df.to_parquet(tmp_path / "f.parquet")
    assert_same(tr, read_trial(tmp_path / "f.parquet"))


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        read_trial(tmp_path / "none.csv")
    with pytest.raises(InputError, match="is a directory"):
        read_trial(tmp_path)


def test_cli_check_and_convert(tmp_path, capsys):
    assert main(["check", str(GOOD / "simple.csv")]) == 0
    out = capsys.readouterr().out
    assert "8 samples, dt 0.1 s" in out and "from psi [deg]" in out
    assert main(["check", str(GOOD / "short_gap.csv"), "--interpolate-gaps", "0.25", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["samples"] == 10 and len(summary["repairs"]) == 2
    dest = tmp_path / "c.parquet"
    assert main(["convert", str(GOOD / "simple.csv"), str(dest), "--units", "psi=deg"]) == 0
    assert read_trial(dest).meta["units_in"]["psi"] == "deg"
    capsys.readouterr()
    assert main(["convert", str(GOOD / "simple.csv"), str(dest)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "output file exists (use --force to overwrite)" in err[0]
    assert main(["convert", str(GOOD / "simple.csv"), str(dest), "--force"]) == 0


def test_compiled_csv_path_gives_the_doubles_float_gives(tmp_path):
    """Rows with the header's field count go through numpy's reader: the same doubles as ``float()`` of
    each cell (decimal strings of 17 and of 6 significant digits, signs, exponents)."""
    rng = np.random.default_rng(7)
    X = rng.standard_normal((2000, 3)) * np.array([1e-9, 1.0, 1e7])
    X[:, 0] = np.arange(2000) * 0.02
    rows = [[repr(float(v)) for v in r] for r in X[:1000]] + [[f"{v:+.6g}" for v in r] for r in X[1000:]]
    p = tmp_path / "a.csv"
    p.write_text("t [s],x [m],y [m]\n" + "\n".join(",".join(r) for r in rows) + "\n")
    tr = read_trial(p)
    want = np.array([[float(c) for c in r] for r in rows])
    assert np.array_equal(tr.t, want[:, 0])
    for j, ch in ((1, "x"), (2, "y")):
        assert np.array_equal(tr[ch], want[:, j])


def test_a_bad_cell_still_names_channel_and_row(tmp_path):
    p = tmp_path / "b.csv"
    p.write_text("t [s],x [m]\n0,1\n0.1,2\n0.2,x7\n")
    with pytest.raises(InputError, match="row 3") as e:
        read_trial(p)
    assert "x" in str(e.value) and "x7" in str(e.value)
