"""Exported open-loop predictions (``shipid validate --out``): names, units, conventions, read-back."""

import json

import numpy as np
import pytest

from shipid.cli import main
from shipid.io import data_root, read_trial, write_trial
from shipid.io.trial import Trial
from shipid.methods.mmg import export as PE
from shipid.methods.mmg import validate as V
from shipid.models import mmg

ROOT = data_root()
KV = "kvlcc2_hsva/HSVA_CPMC_KVLCC2_Z_10_05.dat"


def need(path="params"):
    if ROOT is None or not (ROOT / path).exists():
        pytest.skip("shared data not found (set SHIPID_DATA)")


def test_prediction_of_own_simulation_reads_back_in_file_names_and_units(tmp_path, own_run):
    """A run the model itself produced, stored with own column names and degrees: the exported
    prediction equals the measured channels, under '<column>_pred' in the file's unit."""
    need()
    m = mmg.load_published("esso_osaka_3m")
    own = own_run(m, rudder_deg=20.0, period=50.0, psi0=3.0)
    t, ch = own.t, dict(own.channels)
    ch["psi"] = np.angle(np.exp(1j * ch["psi"]))          # the logger wraps heading to (-180, 180]
    run = tmp_path / "run.csv"
    write_trial(Trial(t, ch, {}, {}), run, units={"psi": "deg", "delta": "deg", "r": "deg/s"})
    text = run.read_text().splitlines()[0].replace("psi [deg]", "hdg [deg]")
    run.write_text("\n".join([text] + run.read_text().splitlines()[1:]) + "\n")
    tr = read_trial(run, channel_map="psi=hdg")
    v = V.validate(m, tr)
    path, pt = PE.write_prediction(v, tr, tmp_path / "pred.csv")
    header = path.read_text().splitlines()[0].split(",")
    assert "hdg_pred [deg]" in header and "r_pred [deg/s]" in header and "delta [deg]" in header
    back = read_trial(path)
    np.testing.assert_array_equal(back.t, tr.t)
    for std, col in (("x", "x"), ("y", "y"), ("psi", "hdg"), ("u", "u"), ("v", "v"), ("r", "r")):
        np.testing.assert_allclose(back[col + "_pred"], tr[std], atol=1e-9)
    # the predicted heading is on the measured (wrapped) branch although the simulation is continuous
    assert np.abs(back["hdg_pred"]).max() <= np.pi + 1e-12
    assert np.abs(np.unwrap(v.predicted[:, 2])).max() > np.pi      # the run turns through the wrap
    assert back["pos_err"].max() < 1e-9
    np.testing.assert_allclose(back["delta"], tr["delta"], atol=1e-12)


def test_rudder_written_in_the_files_convention_and_errors_match_the_table(tmp_path, own_run):
    need()
    m = mmg.load_published("esso_osaka_3m")
    tr = own_run(m, 60.0, rudder_deg=20.0, period=50.0, psi0=3.0, source="own")
    other = m.with_coef({"NR_arm": 0.7 * m.coef["NR_arm"]}, name="other")
    v = V.validate(other, tr)
    pt = PE.prediction_trial(v, tr, rudder_sign=-1)
    np.testing.assert_array_equal(pt["delta"], -tr["delta"])
    assert pt["pos_err"].max() == pytest.approx(v.windows["whole"]["pos"]["max"], rel=1e-12)
    dpsi = np.degrees(np.angle(np.exp(1j * (pt["psi_pred"] - tr["psi"]))))
    assert np.sqrt(np.mean(dpsi ** 2)) == pytest.approx(v.windows["whole"]["psi"]["rms"], rel=1e-9)
    assert pt.meta["diverged_from_s"] is None


def test_diverged_prediction_is_flagged():
    P = np.zeros((5, 6))
    P[3:, 1] = np.nan
    assert PE.diverged_from(np.arange(5.0), P) == 3.0
    assert PE.diverged_from(np.arange(5.0), np.zeros((5, 6))) is None


@pytest.mark.realdata
def test_cli_validate_out_on_hsva_run(tmp_path, capsys):
    """The HSVA run (rudder positive to port, degrees): the exported rudder is the file's own."""
    need(KV)
    out = tmp_path / "pred.csv"
    args = ["validate", "published:kvlcc2_hsva", "--trial", str(ROOT / KV), "--rudder-sign", "-1",
            "--json", "--out", str(out)]
    assert main(args) == 0
    d = json.loads(capsys.readouterr().out)
    raw = read_trial(ROOT / KV)
    back = read_trial(out)
    np.testing.assert_array_equal(back.t, raw.t)
    np.testing.assert_allclose(back["delta"], raw["delta"], rtol=0, atol=1e-12)      # not flipped
    assert back.meta["units_in"]["psi_pred"] == "deg" and back.meta["units_in"]["n"] == "rps"
    assert back["pos_err"].max() == pytest.approx(d["windows"]["whole"]["pos"]["max"], rel=1e-9)
    # no clobbering without --force (refused before the simulation)
    before = out.read_bytes()
    assert main(args) == 2
    assert out.read_bytes() == before
