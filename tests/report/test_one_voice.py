"""A report speaks with one voice: the card, the verdict, the tables and the warnings box agree.

Each method's report (stored results of ``shipid demo`` and ``shipid identify``, and the example
results) is parsed: the number of warnings and of not-determined quantities must be the same in
every place that states it, every estimate has one verdict wherever it is shown, and a method's
own "N of M ... not determined" warning agrees with the table.
"""

from __future__ import annotations

import html as _html
import re
from pathlib import Path

import pytest

from shipid.report import build_report
from shipid.result import Estimate, Result

RESULTS = sorted((Path(__file__).parent / "results").glob("*.json"))


def _text(s: str) -> str:
    return " ".join(_html.unescape(re.sub(r"<[^>]+>", " ", s)).split())


def _section(html: str, start: str, end: str) -> str:
    i = html.index(start)
    return html[i:html.index(end, i)]


def facts(html: str) -> dict:
    """Every place the report states a count or a verdict, parsed from the HTML."""
    out = {}
    badge = dict((_text(k), int(v)) for k, v in re.findall(r'<div class="badge[^"]*">([^<]+)<b>(\d+)</b>', html))
    out["badge_warnings"] = badge["warnings"]
    out["badge_undetermined"] = badge.get("not determined", 0)
    verdict = _section(html, '<section class="verdict"', "</section>")
    head = _text(re.search(r'<p class="headline[^"]*">(.*?)</p>', verdict, re.S).group(1))
    m = re.search(r"(\d+) warnings?", head)
    out["headline_warnings"] = int(m.group(1))
    m = re.search(r"(\d+) not determined", head)
    out["headline_undetermined"] = int(m.group(1)) if m else 0
    m = re.search(r"(\d+) warnings?</b> \(listed below", verdict)
    out["verdict_warnings"] = int(m.group(1)) if m else (0 if "No warnings." in verdict else -1)
    m = re.search(r"<b>Not determined \((\d+)\)</b>", verdict)
    out["found_undetermined"] = int(m.group(1)) if m else 0
    box = re.search(r'<section class="warnings" id="warnings"><h2>Warnings \((\d+)\)</h2><ul>(.*?)</ul>', html, re.S)
    out["box_warnings"] = int(box.group(1)) if box else 0
    out["box_items"] = len(re.findall(r"<li>", box.group(2))) if box else 0
    table = _section(html, 'id="estimates"', "</table>")
    rows = re.findall(r"<tr[^>]*><td><b>([^<]+)</b></td>.*?<span class='grade [^']*'>([^<]+)</span>", table)
    out["table_grades"] = dict(rows)
    out["table_undetermined"] = sum(1 for _, g in rows if g == "not determined")
    found = _section(html, "<table class='found'>", "</table>")
    out["found_grades"] = dict(re.findall(r"<td><b>([^<]+)</b></td>.*?<span class='grade [^']*'>([^<]+)</span>",
                                          found))
    lists = re.findall(r'<li class="[^"]*"><b>([^<]+)</b>[^:<]*(?:<i>[^<]*</i>[^:<]*)*\):(.*?)</li>', verdict, re.S)
    out["lists"] = {label: [x.split(" (")[0].strip() for x in _text(body).rstrip(".").split(", ")]
                    for label, body in lists}
    out["method_n_of_m"] = [int(n) for n in re.findall(r"(\d+) of \d+ coefficients not determined", _text(html))]
    return out


def assert_one_voice(html: str) -> dict:
    f = facts(html)
    w = {f["badge_warnings"], f["headline_warnings"], f["verdict_warnings"], f["box_warnings"], f["box_items"]}
    assert len(w) == 1, f
    u = {f["badge_undetermined"], f["headline_undetermined"], f["found_undetermined"], f["table_undetermined"]}
    assert len(u) == 1, f
    for n, g in f["found_grades"].items():           # the first screen and the table give the same verdict
        assert f["table_grades"][n] == g, (n, g, f["table_grades"][n])
    named = [n for names in f["lists"].values() for n in names if not n.startswith("and ")]
    assert len(named) == len(set(named)), f["lists"]     # each estimate in one list only
    m = re.search(r"report: (\d+) quantit(?:y|ies) the method reports as estimated", _text(html))
    relabelled = int(m.group(1)) if m else 0          # named in the warnings box, so the counts are explained
    for n in f["method_n_of_m"]:                      # the method's own count agrees with the table
        assert n + relabelled == f["table_undetermined"], (n, relabelled, f)
    return f


@pytest.mark.parametrize("path", RESULTS, ids=lambda p: p.stem)
def test_stored_method_results_speak_with_one_voice(path):
    r = Result.from_json(path.read_text(encoding="utf-8"))
    f = assert_one_voice(build_report(r))
    # the method's warnings, then any the report adds itself (a relabelled quantity, a series it could not
    # draw from a stored file)
    assert f["box_warnings"] >= len(r.warnings) and (f["box_warnings"] == len(r.warnings) or "report" in
                                                     _section(build_report(r), 'id="warnings"', "</section>"))
    assert f["table_undetermined"] == len(r.verdict.not_determined)
    assert f["table_grades"] == {n: g for n, g in r.verdict.grades.items()}


@pytest.mark.parametrize("method", ["mass-cm", "dp", "ebm"])
def test_example_reports_speak_with_one_voice(example_reports, method):
    assert_one_voice(example_reports[method][1])


def test_the_check_can_fail():
    """A flagged estimate with a small SE is in one list only; a doctored page is caught."""
    r = Result("mass-cm", {"K_r": Estimate(-1.0, 0.01, "kg", note="weakly determined: finite-sample bias"),
                           "m": Estimate(2.0, 0.01, "kg"), "Y": Estimate(0.1, 0.5, "-")},
               diagnostics={"converged": True, "warnings": ["one", "two"]})
    html = build_report(r)
    f = assert_one_voice(html)
    assert f["lists"]["Flagged by the method"] == ["K_r"] and f["lists"]["Well determined"] == ["m"]
    assert f["badge_warnings"] == 3 and f["table_undetermined"] == 1      # two of the method's, one of the report
    with pytest.raises(AssertionError):
        assert_one_voice(html.replace('">warnings<b>3</b>', '">warnings<b>2</b>'))
    with pytest.raises(AssertionError):
        assert_one_voice(html.replace("<h2>Warnings (3)</h2>", "<h2>Warnings (4)</h2>"))
    assert "report: 1 quantity the method reports as estimated has a relative SE above 100 %" in html
    with pytest.raises(AssertionError):     # an estimate in two lists, as "well" and as "flagged"
        assert_one_voice(html.replace("): m (", "): m (0.5 %), K_r (", 1))
