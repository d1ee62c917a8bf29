"""CLI of the EBM method: identify ebm, study ebm-esso-osaka, design prbs."""

import json
import subprocess
import sys

import numpy as np
import pytest

from shipid.cli import main
from shipid.io.files import write_trial
from shipid.methods.ebm.trials import simulate_trial


@pytest.fixture(scope="module")
def trial_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("ebm")
    paths = []
    for i, (m, dur) in enumerate([("turning-35", 300.0), ("zigzag-20", 400.0)]):
        p = d / f"t{i}.parquet"  # Parquet keeps the trial metadata (the DGPS antenna and log positions)
        write_trial(simulate_trial(m, dur, seed=i), p)
        paths.append(str(p))
    return paths


def test_identify_ebm_json(trial_files, capsys, monkeypatch):
    monkeypatch.setenv("SHIPID_NO_PROGRESS", "1")
    argv = ["identify", "ebm", "--vessel", "esso-osaka", "--json"]
    for p in trial_files:
        argv += ["--trial", p]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["method"] == "ebm"
    for k in ("Y_v", "N_r", "eta_CR", "current_speed", "current_direction"):
        assert k in out["estimates"] and np.isfinite(out["estimates"][k]["std"])
    assert set(out["diagnostics"]["modes"]) == {"surge", "sway", "yaw"}
    for m in out["diagnostics"]["modes"].values():
        assert {"kappa", "R2", "Cp"} <= set(m)
    # current of §5.1: 2 kn = 1.029 m/s towards 45°
    assert out["estimates"]["current_speed"]["value"] == pytest.approx(1.029, abs=0.02)
    assert np.rad2deg(out["estimates"]["current_direction"]["value"]) == pytest.approx(45.0, abs=2.0)


def test_identify_ebm_missing_channel_is_one_line_exit_2(tmp_path, capsys):
    p = tmp_path / "bad.csv"
    p.write_text("t [s],x [m],y [m]\n0,0,0\n1,1,1\n2,2,2\n")
    assert main(["identify", "ebm", "--trial", str(p)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "x_dot" in err


def test_identify_ebm_wrong_vessel(trial_files, capsys):
    assert main(["identify", "ebm", "--trial", trial_files[0], "--vessel", "supply"]) == 2


def test_design_prbs_subprocess():
    r = subprocess.run([sys.executable, "-m", "shipid", "design", "prbs", "--amplitudes", "10,35",
                        "--periods", "105", "--duration", "400", "--seeds", "1", "--json"],
                       capture_output=True, text=True, timeout=300, env={**__import__("os").environ,
                                                                         "SHIPID_NO_PROGRESS": "1"})
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)  # a shipid Result (method "ebm-design") since --out/--json write one
    assert out["estimates"]["amplitude"]["value"] == 35.0  # larger rudder, better conditioned (Fig. 7)
    assert len(out["series"]["contours"]["d_optimal"]["z"]) == 2


def test_design_prbs_bad_grid(capsys):
    assert main(["design", "prbs", "--amplitudes", "50"]) == 2


def test_study_cli_quick(capsys, monkeypatch):
    monkeypatch.setenv("SHIPID_NO_PROGRESS", "1")
    assert main(["study", "ebm-esso-osaka", "--input", "standard", "--seed", "3", "--scale", "0.3"]) == 0
    out = capsys.readouterr().out
    assert "Table 2 analogue" in out and "eq. 21 combined coefficients" in out and "Y_delta" in out


def test_identify_ebm_text_prints_verdicts_converged_and_warnings(tmp_path, capsys, monkeypatch):
    """Issue 16: verdicts, converged and the warnings in the text output; a coefficient that is
    not determined is printed without a value. A short zig-zag alone leaves the cubic terms open."""
    monkeypatch.setenv("SHIPID_NO_PROGRESS", "1")
    p = tmp_path / "z.parquet"
    write_trial(simulate_trial("zigzag-20", 400.0, seed=5), p)
    assert main(["identify", "ebm", "--trial", str(p)]) == 0
    cap = capsys.readouterr()
    out = cap.out
    assert "converged: " in out
    lines = [ln for ln in out.splitlines() if "not determined (" in ln]
    assert lines, out
    for ln in lines:  # no number in the estimate and std columns
        name, est, std = ln.split()[:3]
        assert est == "-" and std == "-"
    # the warnings are the common one-line form on stderr (shipid.cli._common.loud)
    assert any(ln.startswith("shipid: warning: EBM:") and "not determined" in ln for ln in cap.err.splitlines())


def test_identify_ebm_constant_rudder_is_refused_with_one_line(tmp_path, capsys):
    p = tmp_path / "s.parquet"
    write_trial(simulate_trial("straight", 200.0, seed=0), p)
    assert main(["identify", "ebm", "--trial", str(p)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "rudder barely varies" in err
