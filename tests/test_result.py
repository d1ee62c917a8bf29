"""The typed result: Diagnostics as a mapping and as fields, Covariance, the JSON round trip."""

import json

import numpy as np
import pytest

from shipid.result import Covariance, Diagnostics, Estimate, Result


def _result(**kw):
    return Result("dp", {"a": Estimate(1.0, 0.1, "m"), "b": Estimate(2.0, 0.2, "s")},
                  covariance=np.array([[0.01, 0.006], [0.006, 0.04]]), covariance_names=["a", "b"], **kw)


def test_a_dict_given_as_diagnostics_becomes_typed_and_reads_both_ways():
    r = _result(diagnostics={"converged": False, "iterations": 7, "ridge_k": 0.01})
    assert isinstance(r.diagnostics, Diagnostics)
    assert r.diagnostics.converged is False and r.diagnostics["converged"] is False and r.converged is False
    assert r.diagnostics["iterations"] == 7 and r.diagnostics.extra == {"ridge_k": 0.01}
    r.diagnostics.setdefault("warnings", []).append("stage SI2 did not settle")
    assert r.warnings == ["stage SI2 did not settle"]
    assert r.diagnostics == {"converged": False, "iterations": 7, "warnings": ["stage SI2 did not settle"],
                             "ridge_k": 0.01}


def test_an_unset_field_is_absent_as_in_the_json():
    d = Diagnostics.coerce({"loglik": -3.0})
    assert "converged" not in d and d.get("converged", "none") == "none"
    with pytest.raises(KeyError):
        d["iterations"]
    assert list(d) == ["warnings", "loglik"]


def test_reassigning_diagnostics_keeps_the_type():
    r = _result()
    r.diagnostics = {"converged": True}
    assert isinstance(r.diagnostics, Diagnostics) and r.converged is True


def test_json_round_trip_keeps_estimates_covariance_and_diagnostics():
    r = _result(diagnostics={"converged": True, "warnings": ["w"], "noise": {"R": [1.0, 2.0]}})
    back = Result.from_json(r.to_json())
    assert back.estimates == r.estimates and back.diagnostics == r.diagnostics
    assert np.array_equal(back.covariance, r.covariance)
    assert json.loads(back.to_json())["diagnostics"] == json.loads(r.to_json())["diagnostics"]


def test_covariance_names_std_correlation_and_blocks():
    c = _result().cov
    assert isinstance(c, Covariance) and c.names == ("a", "b")
    assert c.std() == pytest.approx({"a": 0.1, "b": 0.2})
    assert c.correlation()[0, 1] == pytest.approx(0.006 / (0.1 * 0.2))
    assert c.sub(["b"]).matrix.tolist() == [[0.04]]
    assert Result("x", {}).cov is None


def test_with_series_of_a_method_without_a_series_hook_is_the_result_itself():
    r = Result("not-a-method", {})
    assert r.with_series() is r
