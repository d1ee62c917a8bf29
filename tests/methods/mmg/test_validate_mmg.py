"""The common validate entry for MMG: shipid.validate on a Result, a MODEL.json path and the registry dispatch."""

import pytest

import shipid
from shipid import registry
from shipid.io import data_root
from shipid.methods.mmg import validate as V
from shipid.models import mmg
from shipid.result import Result

ROOT = data_root()


def need_data():
    if ROOT is None or not (ROOT / "params").is_dir():
        pytest.skip("shared data not found (set SHIPID_DATA)")


def test_every_method_with_a_model_has_the_same_validate_entry():
    have = {k for k, v in registry.methods().items() if v.has_module("validate")}
    assert {"mmg", "ebm", "dp", "mass-cm"} <= have
    for k in have:
        mod = registry.get(k).submodule("validate")
        assert callable(mod.validate_result) and mod.DEFAULT_HORIZON > 0


def test_result_and_json_path_validate_like_the_model(tmp_path, own_run):
    need_data()
    m = mmg.load_published("esso_osaka_3m")
    tr = own_run(m)
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
