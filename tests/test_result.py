"""The typed result: Diagnostics as a mapping and as fields, Covariance, the JSON round trip."""

import json

import numpy as np
import pytest

from dataclasses import asdict

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


# -- the faces of statistical packages: summary, repr, frame, intervals ------------------------------------

import math
from pathlib import Path

import pandas as pd

from shipid import summary as S

FIXTURES = Path(__file__).parent / "report" / "results"
#: Result JSON of each method as ``shipid demo`` / ``shipid identify`` wrote it (series stripped to keep it small).
METHOD_FILES = sorted(FIXTURES.glob("*.json"))


def _load(path) -> Result:
    return Result.from_json(path.read_text(encoding="utf-8"))


@pytest.fixture(params=METHOD_FILES, ids=lambda p: p.stem)
def method_result(request):
    return _load(request.param)


def test_fixtures_cover_every_method():
    assert {_load(p).method for p in METHOD_FILES} >= {"mass-cm", "dp", "ebm", "mmg-ebm"}


def test_summary_fits_100_columns_and_40_lines_and_names_everything(method_result):
    r = method_result
    s = r.summary()
    lines = s.splitlines()
    assert len(lines) <= 40 and max(map(len, lines)) <= 100, (len(lines), max(map(len, lines)))
    v = r.verdict
    table = "\n".join(lines[5:])
    for n in v.tabled:                       # each determined estimate has its own row with its value
        row = next(x for x in lines if x.startswith(n[:13]))
        assert S.num(r.estimates[n].value) in row and r.estimates[n].unit[:10] in row
    und = v.not_determined
    if und:
        block = " ".join(x for x in lines if x.startswith(("Not determined", "  ")))
        assert f"Not determined ({len(und)}" in table
        for n in und:
            assert n in block
            assert not any(x.startswith(n + " ") for x in lines)    # never a row with a value
    assert (f"Warnings ({len(r.warnings)})" if r.warnings else "No warnings.") in s
    assert f"{len(r.warnings)} warning" in lines[1] and f"{len(v.determined)} estimated" in lines[1]


def test_print_is_short_and_the_notebook_display_is_a_table(method_result):
    r = method_result
    text = str(r)
    assert len(text) <= 2000 and text == repr(r)
    assert text.startswith(f"<shipid Result {r.method}")
    h = r._repr_html_()
    assert h.count("<tr") == len(r.estimates) + 1 and all(n in h for n in r.estimates)


def _same(a: Estimate, b: Estimate) -> bool:
    return all((x == y) or (isinstance(x, float) and math.isnan(x) and math.isnan(y))
               for x, y in zip(asdict(a).values(), asdict(b).values()))


def test_to_frame_round_trips_the_estimates(method_result):
    r = method_result
    df = r.to_frame()
    assert isinstance(df, pd.DataFrame) and list(df.index) == list(r.estimates)
    back = Result.estimates_from_frame(df)
    assert list(back) == list(r.estimates)
    assert all(_same(back[k], r.estimates[k]) for k in r.estimates)
    assert list(df["verdict"]) == [r.verdict.grades[k] for k in r.estimates]


def test_conf_int_params_and_std_series(method_result):
    r = method_result
    ci, ci90 = r.conf_int(), r.conf_int(0.10)
    und = set(r.verdict.not_determined)
    for k, e in r.estimates.items():
        if k in und:
            assert math.isnan(r.params[k]) and ci.loc[k].isna().all() and math.isnan(r.bse[k])
        else:
            assert r.params[k] == e.value
            if math.isfinite(e.std):
                assert ci.loc[k, "lower"] == pytest.approx(e.value - 1.959963984540054 * e.std)
                assert ci.loc[k, "upper"] == pytest.approx(e.value + 1.959963984540054 * e.std)
                assert ci90.loc[k, "upper"] - ci90.loc[k, "lower"] < ci.loc[k, "upper"] - ci.loc[k, "lower"] \
                    or e.std == 0
        assert r.std(k) == e.std or (math.isnan(r.std(k)) and math.isnan(e.std))   # by name: as before
    assert isinstance(r.std(), pd.Series) and r.std().equals(r.bse)


def test_a_large_result_is_folded_with_counts():
    est = {f"coef_{i:03d}": Estimate(1.0 + i, 0.01 * (1 + i), "-") for i in range(120)}
    est.update({f"bad_{i:02d}": Estimate(0.01, 1.0, "-") for i in range(60)})
    warns = [f"warning number {i}: " + "a long explanation " * 12 for i in range(30)]
    r = Result("ebm", est, diagnostics={"converged": True, "warnings": warns})
    s = r.summary()
    lines = s.splitlines()
    assert len(lines) <= 40 and max(map(len, lines)) <= 100
    assert "more estimates (res.to_frame() lists all)" in s and "Not determined (60" in s and "… and" in s
    assert "Warnings (30)" in s and "more (res.warnings)" in s
    shown = sum(1 for x in lines if x.startswith("coef_"))
    m = int(next(x for x in lines if "more estimates" in x).split("and ")[1].split()[0])
    assert shown + m == 120
    assert len(str(r)) <= 2000
    assert len(r.to_frame()) == 180


def test_one_grade_per_estimate():
    flagged = Estimate(1.0, 0.01, "-", note="weakly determined: bias beyond its std")
    assert S.grade(flagged) == "flagged"                              # not also "well"
    assert S.grade(Estimate(1.0, 0.01)) == "well" and S.grade(Estimate(1.0, 0.3)) == "loose"
    assert S.grade(Estimate(1.0, 0.7)) == "poor" and S.grade(Estimate(1.0, 1.5)) == S.NOT_DETERMINED
    assert S.grade(Estimate(1.0, float("inf"))) == S.NOT_DETERMINED
    assert S.grade(Estimate(1.0, 0.01, status="not determined")) == S.NOT_DETERMINED
    assert S.grade(Estimate(1.0, status="fixed")) == "fixed" and S.grade(Estimate(1.0)) == "no SE"


# -- validate's result ------------------------------------------------------------------------------------

def _validation():
    from shipid.analysis.openloop import Validation

    t = np.arange(0.0, 100.0, 0.5)
    meas = np.column_stack([np.sin(t / 10), 5 * t])
    pred = meas + np.column_stack([0.01 * t / 100, 0.2 * np.ones_like(t)])
    w = {"rms": 0.5, "max": 1.0, "unit": "deg"}
    windows = {"first_30s": {"psi": w, "pos": {"rms": 0.1, "max": 0.2, "unit": "m"}},
               "whole": {"psi": {"rms": 2.0, "max": 4.0, "unit": "deg"}, "pos": {"rms": 3.0, "max": 9.0, "unit": "m"}}}
    hz = {"length_s": 60.0, "stride_s": 60.0, "count": 2, "psi": {"rms": 1.0, "max": 2.0, "unit": "deg"},
          "pos": {"rms": 1.5, "max": 2.5, "unit": "m"}}
    return Validation(windows, hz, t, meas, pred, "ebm (esso-osaka)", "/somewhere/run.csv", ("psi", "pos"),
                      {"psi": "deg", "pos": "m"}, "ebm", ("psi", "x"))


def test_validation_summary_frame_plot_and_repr():
    v = _validation()
    s = v.summary()
    lines = s.splitlines()
    assert max(map(len, lines)) <= 100 and len(lines) <= 40
    assert "psi [deg]" in s and "pos [m]" in s and "60-s horizons (n=2)" in s and "2 / 4" in s
    df = v.to_frame()
    assert df.loc[("whole", "pos"), "rms"] == 3.0 and df.loc[("first_30s", "psi"), "unit"] == "deg"
    assert len(df) == 6
    r = repr(v)
    assert "<pre>" in v._repr_html_() and "psi [deg]" in v._repr_html_()
    assert len(r) < 500 and "run.csv" in r and "/somewhere" not in r and "array(" not in r and "psi 2 deg" in r
    fig = v.plot()
    assert len(fig.axes) == 2 and fig.axes[0].get_ylabel() == "psi [deg]"
    assert np.allclose(fig.axes[0].lines[0].get_ydata(), np.degrees(v.measured[:, 0]))
