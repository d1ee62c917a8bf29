"""The common validate entry for MMG: shipid.validate on a Result, a MODEL.json path and the registry dispatch."""

import numpy as np
import pytest

import shipid
from shipid import registry
from shipid.data import data_root
from shipid.data.trial import Trial
from shipid.methods.mmg import validate as V
from shipid.models import mmg
from shipid.result import Result

ROOT = data_root()


def need_data():
    if ROOT is None or not (ROOT / "params").is_dir():
        pytest.skip("shared data not found (set SHIPID_DATA)")


def _run(model, seconds=80.0):
    t = np.arange(0.0, seconds, 0.1)
    U = np.zeros((t.size, 4))
    U[:, 0] = np.deg2rad(15) * np.sign(np.sin(2 * np.pi * t / 40))
    U[:, 1] = 10.0
    X = mmg.simulate_batch(model, t, np.array([[0, 0, 0, 0.4, 0, 0]]), U)[0]
    ch = {c: X[:, i] for i, c in enumerate(mmg.STATE_NAMES)}
    ch.update(delta=U[:, 0], n=U[:, 1])
    return Trial(t, ch, {}, {"source": "simulated"})


def test_every_method_with_a_model_has_the_same_validate_entry():
    have = {k for k, v in registry.methods().items() if v.has_module("validate")}
    assert {"mmg", "ebm", "dp", "mass-cm"} <= have
    for k in have:
        mod = registry.get(k).submodule("validate")
        assert callable(mod.validate_result) and mod.DEFAULT_HORIZON > 0


def test_result_and_json_path_validate_like_the_model(tmp_path):
    need_data()
    m = mmg.load_published("esso_osaka_3m")
    tr = _run(m)
    res = Result(method="mmg-ebm", estimates={}, model=m.to_dict())
    v = shipid.validate(res, tr)
    assert v.method == "mmg-ebm" and v.quantities == V.QUANTITIES
    for block in list(v.windows.values()) + [v.horizons]:
        for q in V.QUANTITIES:
            assert block[q]["max"] < 1e-9
    res.write_json(tmp_path / "m.json")
    w = shipid.validate(tmp_path / "m.json", tr)
    assert w.windows == v.windows and w.horizons == v.horizons
    other = m.with_coef({"NR_arm": 0.5 * m.coef["NR_arm"]}, name="half-rudder")
    assert shipid.validate(other, tr).windows["first_60s"]["psi"]["rms"] > 0.5
