"""``shipid demo`` names every part it skipped and why (issue 13); its help states a measured time."""

import re

import pytest

import shipid.demo as D
from shipid.cli import main
from shipid.demo import report_step as RS
from report.examples import example


@pytest.fixture
def only_steps(monkeypatch):
    """Run the demo with the given steps only (the real ones are tested in test_simulate_cli.py)."""
    def use(*steps):
        monkeypatch.setattr(D, "_STEPS", {s.name: s for s in steps})
        monkeypatch.setattr(D, "discover", lambda: None)
    return use


def test_demo_lists_each_skipped_part_with_its_reason(tmp_path, capsys, only_steps):
    def step(ctx):
        ctx.skip("part A", "real data not found\n(set SHIPID_DATA)")
        return [{"thing": "done"}]

    only_steps(D.DemoStep("fake", step, 1, "a step that skips a part"))
    assert main(["demo", "--out-dir", str(tmp_path / "d")]) == 0
    out = capsys.readouterr().out
    assert "[skipped] part A: real data not found (set SHIPID_DATA)" in out
    assert out.strip().splitlines()[-1].endswith("1 part skipped (listed above)")


def test_demo_says_when_nothing_was_skipped(tmp_path, capsys, only_steps):
    only_steps(D.DemoStep("fake", lambda ctx: [], 1, "nothing to skip"))
    assert main(["demo", "--out-dir", str(tmp_path / "d")]) == 0
    out = capsys.readouterr().out
    assert "[skipped]" not in out and out.strip().endswith("every step ran in full")


def test_report_step_without_real_data_names_the_skipped_real_data_step(tmp_path, monkeypatch):
    """The report step's real-data part (KVLCC2 zig-zags) used to vanish silently without the data."""
    monkeypatch.setenv("SHIPID_DATA", str(tmp_path / "no-such-folder"))
    ctx = D.DemoContext(out_dir=tmp_path)
    for m in ("mass-cm", "dp", "ebm"):           # results already there: no fallback runs
        p = tmp_path / f"result-{m}.json"
        example(m).write_json(p)
        ctx.files.append(p)
    RS.report_step(ctx)
    assert [w for w, _ in ctx.skipped] == ["real-data MMG identification (KVLCC2 HSVA zig-zags) and its report"]
    assert "real data not found" in ctx.skipped[0][1]


def test_demo_help_points_to_a_measured_time(capsys):
    """The help names where the demo's measured run time is (help texts carry no measurements); that page
    states one."""
    from pathlib import Path

    assert main(["demo", "--help"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "well under a minute" not in out
    assert "docs/validation/index.md" in out
    page = (Path(__file__).resolve().parents[2] / "docs" / "validation" / "index.md").read_text(encoding="utf-8")
    assert re.search(r"2-core .* \d+ s without the real data", " ".join(page.split()))