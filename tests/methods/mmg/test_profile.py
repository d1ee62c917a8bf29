"""Data profiles: a run is read as its file says, whatever the model was trained on (methods/mmg/profile.py)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import shipid
from shipid.cli import main
from shipid.io import data_root
from shipid.io.files import write_trial
from shipid.methods.mmg import profile as PF


def _hsva():
    root = data_root()
    if root is None or not (root / "kvlcc2_hsva").is_dir():
        pytest.skip("shared data (kvlcc2_hsva/) not found (set SHIPID_DATA)")
    return root / "kvlcc2_hsva"


@pytest.fixture(scope="module")
def dat_model(tmp_path_factory):
    """A model trained on two HSVA .dat files read with the format named (MODEL.json records 'kvlcc2')."""
    d = _hsva()
    files = [str(d / f"HSVA_CPMC_KVLCC2_Z_{n}.dat") for n in ("10_10_P", "20_05")]
    res = shipid.identify("mmg", files, fmt="kvlcc2", structure="linear-hull+rudder", refine="none", simex="off")
    assert res.model["validate"]["format"] == "kvlcc2" and res.model["validate"]["rudder_sign"] == -1
    path = tmp_path_factory.mktemp("model") / "MODEL.json"
    path.write_text(res.to_json(), encoding="utf-8")
    return path


def _keys(v):
    d = v.to_dict()
    return d["windows"], d["horizons"]


@pytest.mark.realdata
def test_a_csv_is_validated_against_a_model_trained_on_dat_files(dat_model, tmp_path, capsys):
    """The model's format (kvlcc2) is not forced on a CSV: the CSV is read as a CSV, its rudder with the sign
    of its own profile (none: MMG's), and the conflict is one warning line. The CSV holds the first 80 s
    of a .dat run in MMG's convention, so it validates as that run read from the .dat file does."""
    dat = _hsva() / "HSVA_CPMC_KVLCC2_Z_20_10_S.dat"
    raw = PF.read_run(dat)
    raw = raw.slice_time(None, float(raw.t[0]) + 80.0)
    tr = PF.flip(raw, -1)
    keep = ("x", "y", "psi", "u", "v", "r", "delta", "n")
    csv = write_trial(shipid.Trial(tr.t, {c: tr[c] for c in keep}, {c: tr.units[c] for c in keep}, {}),
                      tmp_path / "run.csv")
    v_csv = shipid.validate(str(dat_model), str(csv))
    v_dat = shipid.validate(str(dat_model), raw)          # the .dat run's own profile and sign
    lines = v_csv.settings["warnings"]
    conflict = [w for w in lines if "read as the file says" in w]
    assert len(conflict) == 1 and "format csv, not the model's kvlcc2" in conflict[0]
    assert "rudder sign +1" in conflict[0]
    assert v_csv.settings["rudder_sign"] == 1 and v_csv.settings["format"] is None
    assert v_dat.settings["rudder_sign"] == -1 and not any("read as the file says" in w for w in
                                                           v_dat.settings["warnings"])
    for q in ("psi", "pos", "r"):
        assert v_csv.horizons[q]["rms"] == pytest.approx(v_dat.horizons[q]["rms"], rel=1e-6)
    # the command line reads it the same way and says the same lines
    assert main(["validate", str(dat_model), "--trial", str(csv), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    py = json.loads(json.dumps(v_csv.to_dict(), default=float))
    assert d["horizons"] == py["horizons"] and d["windows"] == py["windows"]
    assert d["warnings"] == lines


@pytest.mark.realdata
def test_the_model_s_settings_apply_to_a_file_of_its_kind(dat_model):
    """A .dat run takes the model's format and rudder sign; a given rudder sign that differs is one line."""
    raw = PF.read_run(_hsva() / "HSVA_CPMC_KVLCC2_Z_20_10_S.dat")
    v = shipid.validate(str(dat_model), raw.slice_time(None, float(raw.t[0]) + 80.0), rudder_sign=1)
    assert v.settings["rudder_sign"] == 1 and v.settings["profile"] == "kvlcc2"
    assert sum("differs from the rudder sign of the model's training runs" in w for w in v.settings["warnings"]) == 1
    assert np.isfinite(v.horizons["psi"]["rms"])


def _esso():
    root = data_root()
    if root is None or not (root / "esso_osaka_3m").is_dir():
        pytest.skip("shared data (esso_osaka_3m/) not found (set SHIPID_DATA)")
    return root / "esso_osaka_3m" / "data" / "random"


@pytest.mark.realdata
def test_esso_runs_are_retimed_by_identify_and_by_validate(tmp_path, capsys):
    """Esso CSV runs: identify estimates the channel offsets on the training runs, records them in MODEL.json
    and says so in one line; validate re-times a run it reads by them (one line), --no-retime refuses both."""
    d = _esso()
    train = [str(d / f) for f in ("random_06-Aug-2020_16_24_25_4.csv", "random_31-Jul-2020_14_52_18.csv")]
    kw = dict(structure="hull+rudder+thrust", refine="none", simex="off")
    res = shipid.identify("mmg", train, **kw)
    rt = res.model["retime"]
    assert rt["runs"] == 2 and 0.0 < rt["psi"] < 2.0 and res.model["validate"]["retime"]
    assert sum("re-timed onto the position clock" in w for w in res.warnings) == 1
    model = tmp_path / "MODEL.json"
    model.write_text(res.to_json(), encoding="utf-8")
    test = str(d / "random_06-Aug-2020_16_24_25_1.csv")
    v = shipid.validate(str(model), test)
    assert v.settings["retimed"] and sum("re-timed" in w for w in v.settings["warnings"]) == 1
    raw = shipid.validate(str(model), test, retime=False)
    assert not raw.settings["retimed"] and any("--no-retime" in w for w in raw.settings["warnings"])
    assert v.horizons["psi"]["rms"] != raw.horizons["psi"]["rms"]
    # the command line: the same model, and --no-retime refuses
    out = tmp_path / "cli.json"
    assert main(["identify", "mmg", *[a for f in train for a in ("--trial", f)], "--structure", "hull+rudder+thrust",
                 "--refine", "none", "--simex", "off", "-o", str(out)]) == 0
    cli = json.loads(out.read_text(encoding="utf-8"))
    assert cli["model"]["retime"] == json.loads(res.to_json())["model"]["retime"]
    assert cli["estimates"] == json.loads(res.to_json())["estimates"]
    out2 = tmp_path / "cli_raw.json"
    assert main(["identify", "mmg", *[a for f in train for a in ("--trial", f)], "--structure", "hull+rudder+thrust",
                 "--refine", "none", "--simex", "off", "--no-retime", "-o", str(out2)]) == 0
    assert json.loads(out2.read_text(encoding="utf-8"))["model"]["retime"] is None
    capsys.readouterr()
    assert main(["validate", str(model), "--trial", test, "--no-retime", "--json"]) == 0
    d2 = json.loads(capsys.readouterr().out)
    assert d2["settings"]["retimed"] is False and d2["horizons"] == json.loads(json.dumps(raw.to_dict()))["horizons"]
