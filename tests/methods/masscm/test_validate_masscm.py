"""Open-loop validation of the identified roll model (Linder et al. 2015, (23)–(26), (33)) on held-out runs.

Training: nominal, calibration and loaded datasets of 120 s (seed 21) with gyro noise 0.002 rad/s
and accelerometer noise 0.02 m/s², z_f known; held out: new 60-s datasets (seed 77, another PRBS
rudder) with the same noise. The bounds are the measured errors with a margin (numbers in each test).
"""

import json

import numpy as np
import pytest

import shipid
from shipid.cli import main
from shipid.io.files import write_trial
from shipid.methods.masscm import validate as MV
from shipid.methods.masscm.crlb import true_theta
from shipid.methods.masscm.estimator import estimate_mass_cm
from shipid.models.roll_reduced import KnownParams
from shipid.models.roll_sim import NoiseSpec, simulate_datasets

NOISE = NoiseSpec(gyro_std=0.002, acc_std=0.02)
ZF_TRUE = -0.028        # Table 2


@pytest.fixture(scope="module")
def identified():
    kn = KnownParams.from_vessel("fishing-vessel")
    return estimate_mass_cm(list(simulate_datasets(seed=21, duration=120.0, noise=NOISE).items()), kn, z_f=ZF_TRUE)


@pytest.fixture(scope="module")
def held_out():
    return simulate_datasets(seed=77, duration=60.0, noise=NOISE)


def test_identified_roll_model_predicts_held_out_loaded_run(identified, held_out):
    v = shipid.validate(identified, held_out["loaded"])
    assert v.method == "mass-cm" and v.quantities == ("p", "phi") and v.settings["condition"] == "loaded"
    theta, known = MV.model_from_result(identified)
    wrong = theta.copy()
    wrong[7:9] *= 1.3                                        # the load m and its height zm_bar 30 % off
    w = MV.validate(wrong, known, held_out["loaded"])
    # measured: roll rate rms 0.144 deg/s (the gyro noise alone is 0.115) vs 6.9 deg/s; roll angle
    # 0.071 vs 1.6 deg
    assert v.windows["whole"]["p"]["rms"] < 0.05 * w.windows["whole"]["p"]["rms"]
    assert v.windows["whole"]["phi"]["rms"] < 0.1 * w.windows["whole"]["phi"]["rms"]
    assert v.horizons["p"]["rms"] < w.horizons["p"]["rms"]
    assert v.windows["whole"]["p"]["rms"] < 0.25 and v.windows["whole"]["phi"]["rms"] < 0.15
    assert v.horizons["length_s"] == MV.DEFAULT_HORIZON and v.horizons["count"] == 6


def test_condition_comes_from_the_run(identified, held_out):
    """The calibration run is predicted with the calibration load (known), not the estimated one."""
    v = shipid.validate(identified, held_out["calibration"])      # measured: 0.151 vs 3.72 deg/s rms
    as_loaded = shipid.validate(identified, held_out["calibration"], condition="loaded")
    assert v.settings["condition"] == "calibration"
    assert v.windows["whole"]["p"]["rms"] < 0.25
    assert v.windows["whole"]["p"]["rms"] < as_loaded.windows["whole"]["p"]["rms"]


def test_cli_table_json_and_unknown_method(identified, held_out, tmp_path, capsys):
    model = tmp_path / "mcm.json"
    identified.write_json(model)
    run = tmp_path / "loaded.csv"
    write_trial(held_out["loaded"], run)
    rc = main(["validate", str(model), "--trial", str(run), "--out", str(tmp_path / "pred.csv")])
    out = capsys.readouterr().out
    assert rc == 0 and "p [deg/s]" in out and "phi [deg]" in out and "10-s horizons (n=6)" in out
    assert out.startswith("shipid validate: ") and max(map(len, out.splitlines())) <= 100     # the summary()
    assert out.startswith(shipid.validate(str(model), str(run)).summary() + "\n")          # the library's
    assert (tmp_path / "pred.csv").read_text().splitlines()[0] == ("t [s],p [rad/s],p_pred [rad/s],phi [rad],"
                                                                        "phi_pred [rad]")
    rc = main(["validate", str(model), "--trial", str(run), "--json"])
    d = json.loads(capsys.readouterr().out)
    assert rc == 0 and d["method"] == "mass-cm" and d["windows"]["whole"]["p"]["rms"] < 0.25
    other = tmp_path / "kalman.json"
    other.write_text(json.dumps({"method": "kalman", "estimates": {}}))
    assert main(["validate", str(other), "--trial", str(run)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "'kalman' result cannot be validated" in err[0]


def test_noise_free_true_model_error_is_the_discretisation_only():
    """The validator itself: the true parameters on a noise-free loaded run (simulated with the exact
    zero-order hold at 50 Hz); what remains is the bilinear transform (33) of the continuous model."""
    tr = simulate_datasets(seed=5, duration=60.0)["loaded"]
    v = MV.validate(true_theta("fishing-vessel"), KnownParams.from_vessel("fishing-vessel"), tr)
    peak = float(np.degrees(np.max(np.abs(tr["p"]))))
    # measured: 0.10 deg/s at most on a roll rate of 21 deg/s peak; roll angle 0.013 deg at most
    assert v.windows["whole"]["p"]["max"] < 0.01 * peak
    assert v.windows["whole"]["phi"]["max"] < 0.05
