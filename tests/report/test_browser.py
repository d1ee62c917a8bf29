"""The report renders in a real headless Chromium: no console errors, every image loads, no text
runs out of its box or past the page's right edge.

A full-page screenshot of each report, and one of its first screen (``*-first.png``, 1100 × 900 px),
are kept under ``test-artifacts/`` (git-ignored) as test artefacts: ``report-<method>.png`` (examples),
``report-run-<name>.png`` (real method runs), ``report-stored-<name>.png`` (stored results of every
method, tests/report/results) and ``report-run-esso-mmg.png`` (``shipid identify mmg`` on real Esso
Osaka runs). The first screen must show the verdict's headline and never scroll sideways.
Skips cleanly when the ``chromium`` executable is absent (see conftest.py).
"""

import re
from pathlib import Path

import pytest

STORED = sorted((Path(__file__).parent / "results").glob("*.json"))


def first_screen_ok(info: dict) -> None:
    """The verdict's headline is on the first screen (900 px) and nothing there runs past the right edge."""
    fs = info["first_screen"]
    assert fs["headline"] is not None and 0 <= fs["headline"]["top"] < 900, fs
    assert fs["scroll_x"] <= 0 and fs["sideways"] == [], fs
    assert Path(info["first_screenshot"]).stat().st_size > 5_000


@pytest.mark.parametrize("method", ["mass-cm", "dp", "ebm"])
def test_report_renders_in_chromium(browser, example_reports, artifacts, method):
    result, html, path = example_reports[method]
    info = browser.check(path, artifacts / f"report-{method}.png")
    assert info["errors"] == []
    n_img = html.count("<img")
    assert n_img > 0 and len(info["images"]) == n_img
    for im in info["images"]:
        assert im["complete"] and im["w"] > 0 and im["h"] > 0, im
        assert im["src"].startswith("data:image/png")
    assert info["external"] == []
    assert info["width"] <= info["viewport"], "the page must not scroll sideways"
    assert info["overflow"] == []
    assert info["tables"] == len(re.findall(r"<table", html))
    assert info["title"].startswith(f"shipid report — {method}")
    first_screen_ok(info)
    png = (artifacts / f"report-{method}.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000


#: Figures each real method report must show at least (tests/report/test_method_figures.py names them).
MIN_FIGURES = {"mass-cm": 8, "mass-cm-spread": 1, "dp": 9, "ebm": 11}


@pytest.mark.parametrize("name", list(MIN_FIGURES))
def test_method_report_renders_in_chromium(browser, method_reports, artifacts, name):
    """The reports of real method runs (with the paper figures of issue 8) load cleanly in Chromium."""
    result, html, path = method_reports[name]
    info = browser.check(path, artifacts / f"report-run-{name}.png")
    assert info["errors"] == []
    n_img = html.count("<img")
    assert n_img >= MIN_FIGURES[name] and len(info["images"]) == n_img
    for im in info["images"]:
        assert im["complete"] and im["w"] > 0 and im["h"] > 0, im
    assert info["external"] == []
    assert info["width"] <= info["viewport"], "the page must not scroll sideways"
    assert info["overflow"] == []
    assert (artifacts / f"report-run-{name}.png").stat().st_size > 10_000
    first_screen_ok(info)


@pytest.mark.parametrize("path", STORED, ids=lambda p: p.stem)
def test_stored_result_reports_render_in_chromium(browser, artifacts, tmp_path, path):
    """Reports of every method's stored result (mass-cm, dp, ebm, mmg, the KVLCC2 real-data model)."""
    from shipid.report import build_report
    from shipid.result import Result

    page = tmp_path / f"report-{path.stem}.html"
    page.write_text(build_report(Result.from_json(path.read_text(encoding="utf-8"))), encoding="utf-8")
    info = browser.check(page, artifacts / f"report-stored-{path.stem}.png")
    assert info["errors"] == [] and info["external"] == [] and info["overflow"] == []
    assert info["width"] <= info["viewport"]
    first_screen_ok(info)


@pytest.mark.slow
def test_esso_mmg_report_renders_in_chromium(browser, esso_mmg_report, artifacts):
    """The report of a real-data ``shipid identify mmg`` run (Esso Osaka zig-zags)."""
    _, html, path, _ = esso_mmg_report
    info = browser.check(path, artifacts / "report-run-esso-mmg.png")
    assert info["errors"] == [] and info["external"] == [] and info["overflow"] == []
    n_img = html.count("<img")
    assert n_img >= 9 and len(info["images"]) == n_img          # correlation, 8 overlays, inputs
    assert all(im["complete"] and im["w"] > 0 for im in info["images"])
    assert info["width"] <= info["viewport"]
    first_screen_ok(info)


def test_broken_image_would_be_detected(browser, tmp_path):
    """The check itself can fail: a page with a broken image and a console error is caught."""
    page = tmp_path / "broken.html"
    page.write_text('<!DOCTYPE html><html><head><title>t</title></head><body>'
                    '<img src="data:image/png;base64,AAAA"><img src="missing.png">'
                    '<script>console.error("boom")</script></body></html>', encoding="utf-8")
    info = browser.check(page, tmp_path / "broken.png")
    assert any("boom" in e for e in info["errors"])
    wide = tmp_path / "wide.html"
    wide.write_text('<!DOCTYPE html><html><head><title>t</title></head><body><main style="width:300px">'
                    '<table><tr><td style="white-space:nowrap">' + "x" * 400 + "</td></tr></table>"
                    "</main></body></html>", encoding="utf-8")
    wide_info = browser.check(wide, tmp_path / "wide.png")
    assert wide_info["overflow"]
    with pytest.raises(AssertionError):
        first_screen_ok(wide_info)
    assert [im["w"] for im in info["images"]] == [0, 0]
