"""The ``report`` step of ``shipid demo``: a report per result, fallbacks reported, never silent."""

import pytest

from shipid.demo import DemoContext, demo_steps
from shipid.report import demo_step
from shipid.methods.mmg import demo as mmg_demo
from shipid.report.examples import EXAMPLES


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
