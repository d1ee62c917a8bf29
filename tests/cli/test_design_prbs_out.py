"""``shipid design prbs --json / --out RESULT.json [--force]`` (Yoon & Rhee 2003 Fig. 7)."""

import json

import numpy as np

from shipid.cli import main

FAST = ["design", "prbs", "--amplitudes", "10,35", "--periods", "30,105", "--duration", "200", "--seeds", "1",
        "--dt", "2"]


def test_out_writes_a_result_and_refuses_to_overwrite(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("SHIPID_NO_PROGRESS", "1")
    out = tmp_path / "design.json"
    assert main(FAST + ["--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "optimum: amplitude" in text and str(out) in text
    d = json.loads(out.read_text())
    assert d["method"] == "ebm-design"
    z = np.asarray(d["series"]["contours"]["d_optimal"]["z"])
    assert z.shape == (2, 2)
    i, j = np.unravel_index(np.argmax(z), z.shape)
    assert d["estimates"]["amplitude"]["value"] == [10.0, 35.0][i]
    assert d["estimates"]["period"]["value"] == [30.0, 105.0][j]
    assert d["provenance"]["command"].startswith("shipid design prbs")
    before = out.read_text()
    assert main(FAST + ["--out", str(out)]) == 2           # no clobbering without --force
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "exists" in err
    assert out.read_text() == before
    assert main(FAST + ["--out", str(out), "--force"]) == 0


def test_json_prints_a_result(capsys, monkeypatch):
    monkeypatch.setenv("SHIPID_NO_PROGRESS", "1")
    assert main(FAST + ["--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["method"] == "ebm-design" and "d_optimal" in d["series"]["contours"]
