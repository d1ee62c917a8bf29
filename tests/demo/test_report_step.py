"""The ``report`` step of ``shipid demo``: a report per result, fallbacks reported, never silent."""

import pytest

from shipid.demo import DemoContext, demo_steps
from shipid.demo import report_step as demo_step
from shipid.methods.mmg import demo as mmg_demo
from report.examples import EXAMPLES


def test_step_is_registered_last():
    steps = demo_steps()
    assert steps[-1].name == "report"


def test_reports_for_results_in_context(tmp_path, monkeypatch):
    ctx = DemoContext(out_dir=tmp_path, echo=lambda s: None)
    # results handed over as JSON files (what method steps do) ...
    for m in ("mass-cm", "dp"):
        p = tmp_path / f"{m}-sim.json"
        EXAMPLES[m]().write_json(p)
        ctx.files.append(p)
    # ... and a method with no result whose fallback fails: listed as skipped with the reason
    def broken(seed):
        raise RuntimeError("method not ready")
    monkeypatch.setitem(demo_step.FALLBACKS, "ebm", broken)
    monkeypatch.setitem(demo_step.REAL_DATA, "mmg", lambda seed: None)  # as without the shared data
    rows = demo_step.report_step(ctx)
    by = {r["result"]: r for r in rows}
    assert by["ebm"]["report"].startswith("skipped: RuntimeError: method not ready")
    for name in ("mass-cm-sim", "dp-sim"):
        html = (tmp_path / f"report-{name}.html").read_text(encoding="utf-8")
        assert html.startswith("<!DOCTYPE html>") and "<img" in html
        assert by[name]["converged"] == "yes"
    assert not (tmp_path / "report-ebm.html").exists()


def test_fallback_result_is_saved_and_reported(tmp_path, monkeypatch):
    ctx = DemoContext(out_dir=tmp_path, seed=3, echo=lambda s: None)
    ctx.results = {"given": EXAMPLES["mass-cm"](), "dp-given": EXAMPLES["dp"]()}
    monkeypatch.setitem(demo_step.FALLBACKS, "ebm", lambda seed: EXAMPLES["ebm"]())
    monkeypatch.setitem(demo_step.REAL_DATA, "mmg", lambda seed: None)
    rows = demo_step.report_step(ctx)
    assert {r["result"] for r in rows} == {"given", "dp-given", "result-ebm"}
    assert (tmp_path / "result-ebm.json").exists() and (tmp_path / "report-ebm.html").exists()
    assert (tmp_path / "report-given.html").exists()


@pytest.mark.realdata
def test_real_data_report_with_held_out_validation(tmp_path):
    from shipid.io.paths import data_root

    root = data_root()
    if root is None or not (root / "kvlcc2_hsva").is_dir():
        pytest.skip("shared real data (kvlcc2_hsva) not found: set SHIPID_DATA or provide ../shared/data")
    res = mmg_demo.real_data(0)
    assert res.method == "mmg-ebm"
    ov = res.series["overlays"]
    assert {e["kind"] for e in ov.values()} == {"validation"}
    # the held-out heading is predicted open loop to within a few degrees RMS (HSVA 20/10 zig-zag)
    import numpy as np
    psi = ov["psi_validation"]
    rms = float(np.sqrt(np.mean((np.asarray(psi["measured"]) - np.asarray(psi["model"])) ** 2)))
    assert rms < np.deg2rad(5.0), np.rad2deg(rms)
    from shipid.report import build_report
    html = build_report(res)
    assert "Validation: heading ψ" in html and "held out: validation only" in html


def test_the_demo_says_what_was_not_determined_and_every_warning(tmp_path, monkeypatch):
    """Per result: determined / not determined / warnings in the table, the names and warnings in the
    findings, and the closing line says results need reading (not only that every step ran)."""
    from shipid.demo import closing_line
    from shipid.result import Estimate, Result

    res = Result("ebm", {"Y_v": Estimate(-0.03, 0.001), "Y_vvv": Estimate(0.1, 0.5, status="not determined"),
                         "N_rrr": Estimate(0.01, 0.05)},
                 diagnostics={"converged": True, "warnings": ["EBM: 2 of 3 coefficients not determined"]})
    ctx = DemoContext(out_dir=tmp_path, echo=lambda s: None)
    ctx.results = {"ebm-run": res, "fine": EXAMPLES["dp"]()}
    monkeypatch.setattr(demo_step, "FALLBACKS", {})
    monkeypatch.setattr(demo_step, "REAL_DATA", {})
    monkeypatch.setattr(demo_step, "fallbacks", lambda: {})
    monkeypatch.setattr(demo_step, "real_data_runs", lambda: {})
    rows = {r["result"]: r for r in demo_step.report_step(ctx)}
    assert rows["ebm-run"]["converged"] == "yes" and rows["ebm-run"]["determined"] == "1 of 3"
    assert rows["ebm-run"]["not determined"] == "2" and rows["ebm-run"]["warnings"] == "1"
    assert rows["fine"]["not determined"] == "0"
    text = "\n".join(ctx.findings)
    assert ctx.findings[0].startswith("ebm-run (ebm): 1 of 3 estimated quantities determined")
    assert "not determined (2, not estimates): Y_vvv, N_rrr" in text
    assert "warning: EBM: 2 of 3 coefficients not determined" in text
    line = closing_line(ctx, 1.0, tmp_path)
    assert "1 result with undetermined quantities or warnings" in line and line.endswith("every step ran in full")
    assert "no result has" in closing_line(DemoContext(out_dir=tmp_path), 1.0, tmp_path)
