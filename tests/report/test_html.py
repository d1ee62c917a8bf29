"""The HTML report of any Result: self-contained, tables and images for the three methods."""

import base64
import io
import re

import numpy as np
import pytest
from PIL import Image

from shipid.report import Claim, build_report, register_section
from shipid.report.convention import overlay
from shipid.result import Estimate, Result

IMG = re.compile(r'<img src="data:image/png;base64,([A-Za-z0-9+/=]+)"')


def _roundtrip(r: Result) -> Result:
    return Result.from_json(r.to_json())


def _images(html: str) -> list[Image.Image]:
    out = []
    for b64 in IMG.findall(html):
        im = Image.open(io.BytesIO(base64.b64decode(b64)))
        im.load()
        out.append(im)
    return out


def _assert_self_contained(html: str) -> None:
    assert html.startswith("<!DOCTYPE html>")
    assert "<script" not in html.lower()
    assert not re.search(r'(src|href)="(https?:)?//', html), "external resource referenced"
    assert "<link" not in html.lower()
    assert html.count("<img") == len(IMG.findall(html)), "every image must be an inline PNG"


@pytest.mark.parametrize("method, captions, n_images", [
    ("mass-cm", ["(Linder et al. 2015, Fig. 4)", "(Linder et al. 2015, Table 3)"], 4),  # corr., Fig. 4, spread, overlay
    ("dp", ["(Fossen, Sagatun &amp; Sørensen 1996, Fig. 8)", "Innovation check"], 5),  # Fig. 8, 3 innovations, overlay
    ("ebm", ["Rhee 2003, Figs 4, 9)", "Rhee 2003, Tables 1–2)", "Rhee 2003, Table 4)", "Rhee 2003, Fig. 7)",
             "Rhee 2003, Figs 6, 10)"], 6),
])
def test_report_has_tables_images_and_paper_figures(method, captions, n_images, example_reports):
    r, html, _ = example_reports[method]
    _assert_self_contained(html)
    imgs = _images(html)
    assert len(imgs) == n_images
    for im in imgs:
        assert im.format == "PNG" and im.size[0] > 300 and im.size[1] > 150
        # not blank: a drawn figure has many distinct colours
        assert len(im.convert("RGB").getcolors(maxcolors=1 << 20)) > 50
    for cap in captions:
        assert cap in html, cap
    # estimates table: every estimate, with its unit, and the 95 % CI header
    assert "95 % confidence interval" in html
    for name, e in r.estimates.items():
        assert f"<b>{name}</b>" in html
    assert "Data used" in html and "samples" in html and "Hz" in html
    assert "Residual checks" in html and "Ljung–Box p" in html
    assert "Report written by shipid" in html
    assert "Could not draw" not in html


def test_estimate_row_rounding_and_units_in_table(example_reports):
    r, html, _ = example_reports["mass-cm"]
    m = r.estimates["m"]
    # the row of m: value to the tens (SE 420 has 2 significant digits) and the unit
    table = html[html.index('id="estimates"'):]
    row = re.search(r"<td><b>m</b></td>(.*?)</tr>", table).group(1)
    assert f"{round(m.value, -1):.0f}" in row and ">420<" in row and "<td>kg</td>" in row
    assert "not identifiable" in html              # I_xx has std = inf
    assert "fixed" in html                         # z_f is a known input


def test_warnings_are_prominent(example_reports):
    html = example_reports["ebm"][1]
    assert 'class="warnings"' in html and "ridge parameter chosen at the edge" in html
    r = Result("dp", {"a": Estimate(1.0, 0.5, "kg")}, diagnostics={"converged": False, "iterations": 50})
    html = build_report(r)
    assert "DID NOT converge" in html and "Did not converge" in html and '<div class="badge bad">converged<b>NO</b>' in html


def test_minimal_result_and_unknown_method():
    r = Result("some-new-method", {"k": Estimate(2.0, 0.1, "N/m")})
    html = build_report(_roundtrip(r))
    _assert_self_contained(html)
    assert "some-new-method" in html and "does not record its inputs" in html
    assert "<img" not in html


def test_broken_series_entry_is_reported_not_fatal():
    r = Result("dp", {"a": Estimate(1.0, 0.5, "kg")}, series={
        "overlays": {"bad": {"t": [0, 1, 2], "measured": [1, 2]}},  # no "model"
        "matrices": {"flat": {"values": [1, 2, 3], "rows": ["a"]}},  # not 2-D
        "mystery": {"x": 1}})
    html = build_report(_roundtrip(r))
    assert html.count("Could not draw") == 2
    assert "series[&#x27;overlays&#x27;][&#x27;bad&#x27;]" in html
    assert "not part of the report convention): mystery" in html
    assert "report: series" in html  # listed among the warnings too


def test_registered_section_runs_and_claims():
    from shipid.report.figures import new_figure

    calls = []

    def extra(result):
        """Extra figures for the test"""
        calls.append(result.method)
        fig = new_figure(height=2.0)
        ax = fig.add_subplot()
        ax.plot([0, 1], [0, 1])
        ax.set_xlabel("t [s]")
        return ["<p id='extra-marker'>hello</p>", (fig, "my caption"), Claim("overlays", "x")]

    register_section("dp-test", extra)
    t = np.arange(50.0)
    r = Result("dp-test", {"a": Estimate(1.0, 0.5, "kg")},
               series={"overlays": {"x": overlay(t, t, t + 1, "m", label="north position x")}})
    html = build_report(r)
    assert calls == ["dp-test"]
    assert "id='extra-marker'" in html and "my caption" in html and "Extra figures for the test" in html
    assert "north position x: measured and model" not in html  # claimed, so not drawn again


def test_histories_without_std_and_huge_values_draw():
    t = np.arange(100.0)
    r = Result("dp", {"m": Estimate(1e9, 1e7, "kg")},
               series={"histories": {"m": {"t": t.tolist(), "value": (1e9 + t).tolist(), "unit": "kg"}}})
    html = build_report(r)
    assert len(_images(html)) == 1 and "Could not draw" not in html


def test_series_outside_convention_are_drawn_against_t_with_guessed_units():
    t = np.arange(0.0, 20.0, 0.5)
    r = Result("ebm", {"a": Estimate(1.0, 0.5, "-", note="same"), "b": Estimate(2.0, 0.5, "-", note="same"),
                       "c": Estimate(3.0, 0.5, "-", note="same")},
               series={"t": t.tolist(), "u_r": np.cos(t).tolist(), "N": (1e8 * np.sin(t)).tolist(),
                       "other": [1, 2]})
    html = build_report(r)
    assert len(_images(html)) == 1
    assert "u_r, N versus t" in html
    assert "not part of the report convention): other" in html
    # a note shared by three rows is printed once under the table
    assert html.count("same") == 1 and "<sup>(a)</sup>" in html


def test_ebm_tables_fall_back_to_diagnostics():
    corr = np.array([[1.0, 0.9], [0.9, 1.0]])
    r = Result("ebm", {"Y_v": Estimate(-0.03, 0.001, "-"), "Y_r": Estimate(0.001, 0.0002, "-")},
               diagnostics={"correlation": {"sway": corr.tolist()},
                            "modes": {"sway": {"kappa": 812.0, "R2": 0.99, "Cp": 7.0}}})
    html = build_report(r)
    assert "Correlation of the sway regressors" in html and "Rhee 2003, Tables 1–2)" in html
    assert len(_images(html)) == 1
    row = re.search(r"<td>sway</td>(.*?)</tr>", html).group(1)
    assert ">812<" in row and ">0.99<" in row and ">7<" in row
    assert "Collinearity diagnostics per mode" in html


def test_degenerate_series_do_not_break_the_report():
    import warnings

    from shipid.report.convention import contour, history, matrix, signal, table, xy

    nan = float("nan")
    z = np.ones((3, 4))
    z[1, 1] = nan
    r = Result("mass-cm", {"m": Estimate(nan, nan, "kg"), "x": Estimate(0.0, 0.0, "m"),
                           "y": Estimate(1.0, float("inf"), "-")},
               covariance=np.array([[1.0, 0.0], [0.0, 0.0]]), covariance_names=["m", "x"],
               series={"contours": {"cost": contour([0, 1, 2, 3], [0, 1, 2], z, x_label="m", x_unit="kg",
                                                    y_label="z", y_unit="m", log=True)},
                       "overlays": {"a": overlay([0, 1], [nan, nan], [nan, nan], "m"),
                                    "b": overlay([], [], [], "m"), "c": overlay([0], [1], [1], "m")},
                       "histories": {"h": history([0, 1, 2], [nan, 1, 2], [nan, nan, nan], "kg")},
                       "signals": {"s": signal([0, 1], {}, "m")},
                       "matrices": {"m": matrix([[nan]], ["a"])},
                       "tables": {"t": table([], [])},
                       "xy": {"q": xy([], {}, x_label="a", x_unit="-", y_label="b", y_unit="-")}})
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no RuntimeWarning (all-NaN slices ...) escapes either
        html = build_report(_roundtrip(r))
    _assert_self_contained(html)
    assert "Could not draw" not in html
    assert html.count("<img") == 9   # correlation + contour + 3 overlays + history + signal + matrix + xy


def test_inputs_under_other_names_and_per_mode_diagnostics_as_tables():
    r = Result("mmg-ebm", {"N_r": Estimate(-0.054, 0.0015, "-")},
               model={"inputs": ["delta", "n"]},  # the model's input signals, not trial files
               diagnostics={"ridge": {"X": {"k": 2.7e-5, "kappa": 7529.0}, "N": {"k": 1.8e-5, "kappa": 218.0}}},
               provenance={"training_runs": [{"file": "runs/zz_10_10.dat", "sha256_16": "abc"}]})
    html = build_report(r)
    assert "<code>runs/zz_10_10.dat</code>" in html and "<code>delta</code>" not in html
    assert '<table class="rec">' in html and ">7529<" in html
    assert "Collinearity diagnostics per mode" in html   # EBM default section, from diagnostics
