"""`shipid identify dp` and `shipid study dp-supply` (issue 4)."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from known.fossen1996 import K_EQ49

from shipid.cli import main


@pytest.fixture(scope="module")
def trial_files(tmp_path_factory):
    """Six short simulated trials (seed 3, 300 s) written as CSV, heading and azimuth in degrees."""
    from shipid.io.files import write_trial
    from shipid.methods.dp.trials import simulate_dp_trials
    from shipid.models.dp import dp_vessel
    from shipid.vessels import load_vessel

    d = tmp_path_factory.mktemp("dp")
    tr = simulate_dp_trials(dp_vessel(load_vessel("supply")), 3, duration=300.0)
    files = {}
    for kind, trs in tr.items():
        files[kind] = []
        for i, t in enumerate(trs):
            p = d / f"{kind}{i + 1}.csv"
            write_trial(t, p, units={"psi": "deg", "alpha6": "deg"})
            files[kind].append(str(p))
    return d, files


def _args(files):
    return ["identify", "dp", "--surge", *files["surge"], "--sway-yaw", *files["sway-yaw"],
            "--azimuth", *files["azimuth"]]


def test_identify_dp_json_and_plot(trial_files, capsys):
    d, files = trial_files
    png = d / "fig8.png"
    rc = main(_args(files) + ["--vessel", "supply", "--json", "--plot", str(png)])
    out = capsys.readouterr().out
    assert rc == 0
    res = json.loads(out)
    assert res["method"] == "dp"
    theta = np.asarray(res["model"]["theta"])
    assert theta.shape == (9,) and np.all(np.isfinite(theta))
    # K1 = K2 (θ6) is well determined even from 300-s trials: within 5 % of eq. 49
    assert abs(theta[5] / K_EQ49[0] - 1) < 0.05
    # inputs: one trial summary per file (issue 8, shipid.methods.dp.series)
    first = res["provenance"]["inputs"][0]
    assert first["name"].endswith("surge1.csv") and first["n_samples"] > 100 and "x" in first["channels"]
    assert {"innovation_SI1_s", "innovation_SI2_psi"} <= set(res["series"]["residuals"])
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"
    # never overwrite
    rc = main(_args(files) + ["--plot", str(png)])
    assert rc == 2 and "exists" in capsys.readouterr().err


def test_identify_dp_missing_channel_is_one_line(trial_files, tmp_path, capsys):
    _, files = trial_files
    bad = tmp_path / "bad.csv"
    bad.write_text("t [s],x [m],y [m],psi [rad]\n0,0,0,0\n1,0,0,0\n")
    rc = main(["identify", "dp", "--surge", str(bad), "--sway-yaw", *files["sway-yaw"],
               "--azimuth", *files["azimuth"]])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and len(err.splitlines()) == 1 and "bad.csv" in err and "p1" in err


def test_identify_dp_needs_all_three_kinds(trial_files, capsys):
    _, files = trial_files
    rc = main(["identify", "dp", "--surge", *files["surge"]])
    err = capsys.readouterr().err
    assert rc == 2 and "sway-yaw" in err


def test_study_dp_supply_subprocess():
    """Through the console entry point: a short study prints true vs estimated."""
    out = subprocess.run([sys.executable, "-m", "shipid", "study", "dp-supply", "--seed", "2",
                          "--duration", "240"], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert "theta9" in out.stdout and "true" in out.stdout and "A'' = M''^-1" in out.stdout


def test_identify_dp_prints_noise_and_an_unsettled_scheme(trial_files, capsys, monkeypatch):
    """Text output: the estimated noise levels; a scheme that has not settled is printed and its std marked."""
    from dataclasses import replace

    import shipid.methods.dp.estimator as estimator

    real = estimator.pem_stage        # the name the estimator calls (imported from shipid.methods.dp.pem)

    def stalls_in_si2(lik, *a, **k):
        out = real(lik, *a, **k)
        return replace(out, settled=False) if lik.kind == "momentum" and len(a[1]) == 6 else out

    monkeypatch.setattr(estimator, "pem_stage", stalls_in_si2)
    _, files = trial_files
    assert main(_args(files)) == 0
    cap = capsys.readouterr()
    assert "SI2: NOT SETTLED" in cap.out and "SI1: NOT SETTLED" not in cap.out
    assert "SI1 noise (estimated): q_h = " in cap.out and "sigma_psi" in cap.out
    assert "SI2: parameter estimate has not settled" in cap.err
    assert main(_args(files) + ["--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    status = {k: v["status"] for k, v in res["estimates"].items()}
    assert status["theta1"] == status["theta6"] == "estimated"
    assert all(status[f"theta{i}"] == "std unreliable" for i in (2, 3, 4, 5, 7, 8, 9))
    assert any("SI2" in w and "unreliable" in w for w in res["diagnostics"]["warnings"])


def test_study_dp_coverage_json(tmp_path, capsys):
    """One short realisation through the campaign engine: per-θ coverage table and the stored run."""
    store = tmp_path / "cov.sqlite"
    rc = main(["study", "dp-coverage", "--runs", "1", "--duration", "240", "--seed", "3", "--workers", "1",
               "--store", str(store), "--json"])
    assert rc == 0
    d = json.loads(capsys.readouterr().out)
    s = d["summary"]
    assert s["ok"] == 1 and set(s["parameters"]) == {f"theta{i}" for i in range(1, 10)}
    run = d["runs"][0]
    assert run["s_m"] in (0.5, 1.0, 2.0) and run["s_p"] in (0.5, 1.0, 2.0)
    assert set(run["noise_scale_estimates"]) == {"SI1", "SI2", "SI3"}
    assert store.exists()
