"""``shipid export ...``: the commands parse, print readable tables, write JSON, and fail in one line."""

from __future__ import annotations

import json

import numpy as np

from shipid.cli import main


def test_state_space_prints_the_table(capsys):
    assert main(["export", "state-space", "supply"]) == 0
    out = capsys.readouterr().out
    assert "eqs. 50-52" in out and "du/dt" in out and "u6 [-]" in out
    assert len(out.splitlines()) <= 40


def test_state_space_json_and_out(tmp_path, capsys):
    f = tmp_path / "ss.json"
    assert main(["export", "state-space", "esso-osaka", "--kinematics", "--json", "-o", str(f)]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["states"] == ["u", "v", "r", "psi", "y"] and d["inputs"] == ["delta", "n"]
    assert np.array(d["A"]).shape == (5, 5) and json.loads(f.read_text())["B"] == d["B"]
    assert main(["export", "state-space", "esso-osaka", "-o", str(f)]) == 2     # exists, no --force


def test_nomoto_prints_values_and_std(capsys):
    assert main(["export", "nomoto", "esso-osaka", "--speed", "5.144"]) == 0
    out = capsys.readouterr().out
    assert "T1" in out and "K'" in out and "std: none" in out
    assert main(["export", "nomoto", "esso-osaka", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["units"]["T"] == "s" and d["values"]["T2"] > 0


def test_nomoto_from_a_zigzag(capsys):
    """--from zigzag-10 gives the first-order K, T of the zig-zag: a tenth of the straight-run T for this
    nearly course-unstable tanker (the numbers are tested in test_nomoto.py)."""
    assert main(["export", "nomoto", "esso-osaka", "--from", "zigzag-10", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["about"] == "zigzag-10" and 0 < d["values"]["T"] < 2000 and d["fit"]["K_std"] > 0
    assert main(["export", "nomoto", "esso-osaka", "--from", "turning-35"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("shipid: error:") and "zigzag-10" in err and len(err.strip().splitlines()) == 1


def test_params_to_stdout(capsys):
    assert main(["export", "params", "supply"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("# shipid parameter file") and "[coefficients]" in out and "theta9 = {" in out


def test_bad_model_is_one_line(tmp_path, capsys):
    assert main(["export", "state-space", str(tmp_path / "none.json")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("shipid: error:") and len(err.strip().splitlines()) == 1
    assert main(["export", "nomoto", "supply"]) == 2
    assert "manoeuvring" in capsys.readouterr().err
    assert main(["export", "shipmmg", "esso-osaka"]) == 2
