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
