"""What an export starts from: identified results (DP, EBM, MMG), published sets, packaged vessels."""

from __future__ import annotations

import json

import numpy as np
import pytest

from known.fossen1996 import THETA_EQ46_49
from shipid.errors import InputError
from shipid.export import load, nomoto, state_space
from shipid.io.paths import data_root
from shipid.models import dp, mmg
from shipid.result import Estimate, Result
from shipid.vessels import load_vessel


def _dp_result(theta, std):
    est = {k: Estimate(float(v), float(s), "-", "estimated") for k, v, s in zip(dp.THETA_NAMES, theta, std)}
    return Result(method="dp", estimates=est, model={"vessel": "supply"}, covariance=np.diag(np.square(std)),
                  covariance_names=list(dp.THETA_NAMES))


def test_dp_result_exports_its_own_theta(tmp_path):
    """A DP result's theta, not the packaged one, goes into A'' and B'' (eq. 50); a MODEL.json reads the same."""
    theta = THETA_EQ46_49 * 1.1
    res = _dp_result(theta, 0.01 * np.abs(theta))
    ss = state_space(res)
    v = dp.dp_vessel(load_vessel("supply")).with_theta(theta)
    np.testing.assert_allclose(ss.A, np.linalg.solve(v.M, v.A_h @ v.M), rtol=1e-14)
    f = tmp_path / "MODEL.json"
    res.write_json(f)
    src = load(str(f))
    assert src.family == "dp" and src.method == "dp" and src.cov_names == dp.THETA_NAMES
    np.testing.assert_array_equal(state_space(str(f)).B, ss.B)


def test_mmg_result_with_covariance_gives_nomoto_std():
    """An MMG MODEL.json (family mmg, covariance over its estimated coefficients) gives Nomoto with a delta-method
    std; the fixed coefficients carry none."""
    root = data_root()
    if root is None or not (root / "params" / "kvlcc2_L7_mmg_shipmmg.yml").is_file():
        pytest.skip("KVLCC2 parameters not found (set SHIPID_DATA)")
    model = mmg.load_published("kvlcc2_L7")
    free = ["Y_v", "Y_r", "N_v", "N_r", "YR_gain", "NR_arm"]
    sd = {k: 0.03 * abs(model.coef[k]) for k in free}
    est = {k: Estimate(float(v), sd.get(k, float("nan")), "-", "estimated" if k in sd else "fixed")
           for k, v in model.coef.items()}
    d = model.to_dict()
    d["training_conditions"] = {"rps_ahead": 10.23, "rudder_rate": float(np.deg2rad(15.8))}
    res = Result(method="mmg-ebm", estimates=est, model=d, covariance=np.diag([sd[k] ** 2 for k in free]),
                 covariance_names=free)
    src = load(json.loads(res.to_json()))
    assert src.family == "mmg" and src.cov_names == tuple(free) and src.conditions["rps_ahead"] == 10.23
    nm = nomoto(src)
    assert nm.method == "delta" and all(np.isfinite(nm.std[k]) and nm.std[k] > 0 for k in ("K", "T1", "T3"))
    assert nm.rps == pytest.approx(10.23, rel=1e-9)          # the speed the training rate holds
    # a model of step 2's differential form: the integral form's difference counts as model-form error
    res.diagnostics["form_check"] = {"integral": {k: 0.9 * model.coef[k] for k in free}}
    with_form = load(json.loads(res.to_json()))
    assert "model-form" in with_form.cov_note
    np.testing.assert_allclose(np.diag(with_form.cov) - np.diag(src.cov),
                               [(0.1 * model.coef[k]) ** 2 for k in free], rtol=1e-12)
    assert with_form.std["Y_v"] == pytest.approx(np.hypot(sd["Y_v"], 0.1 * model.coef["Y_v"]), rel=1e-12)
    assert load(json.loads(res.to_json()), form_term=False).cov_note == src.cov_note


def test_unknown_model_is_refused():
    with pytest.raises(InputError, match="no exportable model"):
        load("not-a-vessel")
    with pytest.raises(InputError, match="no exportable model|method"):
        load(Result(method="mass-cm", estimates={}))
