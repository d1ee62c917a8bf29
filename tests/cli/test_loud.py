"""The one mechanism of loud failures (shipid.cli._common): stderr lines, JSON warnings, --strict exit 3.

A throw-away command registered on the real ``shipid`` group for the duration of a
test runs the same path every identify/study/validate command runs: a Python
warning raised inside the "method", a Result that did not converge, a coefficient
the data do not determine, a data repair.
"""

import json
import subprocess
import sys
import warnings

import click
import pytest

from shipid.cli import _common, cli, main
from shipid.io.trial import Trial
from shipid.result import Estimate, Result


@pytest.fixture
def fake_command():
    """``shipid fake-id [--json] [--converged/--not-converged] [--undetermined] [--repair] [--pywarn]``."""

    @cli.command("fake-id")
    @click.option("--json", "as_json", is_flag=True)
    @click.option("--not-converged", is_flag=True)
    @click.option("--undetermined", is_flag=True)
    @click.option("--repair", is_flag=True)
    @click.option("--pywarn", is_flag=True)
    def fake(as_json, not_converged, undetermined, repair, pywarn):
        if pywarn:  # as a method deep inside would: numpy, a ridge k iteration ...
            warnings.warn("mode N: Hoerl-Kennard iteration for k did not converge\nafter 50 steps", RuntimeWarning)
        est = {"a": Estimate(1.0, 0.1, "-", "estimated")}
        if undetermined:
            est["b"] = Estimate(0.0, float("inf"), "-", "not determined", "regressor identically zero")
        res = Result("fake", est, diagnostics={"converged": not not_converged, "iterations": 3, "warnings": []})
        tr = Trial([0.0, 1.0, 2.0], {"x": [0.0, 1.0, 2.0]}, {"x": "m"},
                   {"source": "run.csv", "repairs": [{"text": "rows 5-7: 3 empty cells interpolated"}] if repair else []})
        _common.loud(res, trials=[tr])
        click.echo(res.to_json() if as_json else "table")

    yield
    cli.commands.pop("fake-id", None)


def _lines(err):
    return [ln for ln in err.splitlines() if ln.strip()]


def test_clean_result_prints_nothing_and_exits_0_even_strict(fake_command, capsys):
    assert main(["--strict", "fake-id"]) == 0
    assert capsys.readouterr().err == ""


def test_python_warning_is_one_line_without_source_path_and_in_json(fake_command, capsys):
    assert main(["fake-id", "--pywarn", "--json"]) == 0
    cap = capsys.readouterr()
    assert _lines(cap.err) == ["shipid: warning: mode N: Hoerl-Kennard iteration for k did not converge after 50 steps"]
    assert ".py:" not in cap.err and "RuntimeWarning" not in cap.err
    d = json.loads(cap.out)
    assert d["diagnostics"]["warnings"] == ["mode N: Hoerl-Kennard iteration for k did not converge after 50 steps"]


def test_not_converged_undetermined_and_repair_are_one_line_each(fake_command, capsys):
    assert main(["fake-id", "--not-converged", "--undetermined", "--repair", "--json"]) == 0
    cap = capsys.readouterr()
    err = _lines(cap.err)
    assert len(err) == 3 and all(ln.startswith("shipid: warning: ") for ln in err)
    assert any("did not converge" in ln for ln in err)
    assert any(ln.startswith("shipid: warning: b: not determined (regressor identically zero)") for ln in err)
    assert any("data repaired in run.csv: rows 5-7" in ln for ln in err)
    assert len(json.loads(cap.out)["diagnostics"]["warnings"]) == 3


@pytest.mark.parametrize("argv", [["--strict", "fake-id", "--not-converged"], ["--strict", "fake-id", "--pywarn"],
                                  ["--strict", "fake-id", "--undetermined"], ["--strict", "fake-id", "--repair"]])
def test_strict_exits_3_after_the_output(fake_command, capsys, argv):
    assert main(argv) == 3
    cap = capsys.readouterr()
    assert cap.out.strip() == "table"             # the output is still written
    assert cap.err.strip().splitlines()[-1].startswith("shipid: error: 1 warning and --strict")


def test_without_strict_warnings_exit_0(fake_command, capsys):
    assert main(["fake-id", "--not-converged", "--pywarn"]) == 0
    assert len(_lines(capsys.readouterr().err)) == 2


def test_strict_does_not_leak_into_the_next_invocation(fake_command, capsys):
    assert main(["--strict", "fake-id", "--repair"]) == 3
    assert main(["fake-id", "--repair"]) == 0
    capsys.readouterr()


def test_warning_outside_a_result_is_still_one_line(capsys):
    """A warning no command claims with loud() is printed by main at the end, one line, and counts for --strict."""
    @cli.command("fake-warn")
    def fake_warn():
        warnings.warn("something odd\n  in two lines", UserWarning)

    try:
        assert main(["fake-warn"]) == 0
        assert main(["--strict", "fake-warn"]) == 3
    finally:
        cli.commands.pop("fake-warn", None)
    err = capsys.readouterr().err
    assert "shipid: warning: something odd in two lines" in err and "UserWarning" not in err


def test_the_fixture_catches_raw_warning_text_of_a_subprocess():
    """tests/conftest.py's no_raw_warnings (active here): Python's own warning format on stderr fails a test."""
    code = "import warnings; warnings.warn('raw one')"
    with pytest.raises(pytest.fail.Exception, match="raw Python warning text"):
        subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)


def test_the_fixture_catches_raw_warning_text_read_through_capsys(capsys):
    sys.stderr.write("/x/shipid/methods/mmg/estimator.py:497: RuntimeWarning: mode N: k did not converge\n")
    with pytest.raises(pytest.fail.Exception, match="raw Python warning text"):
        capsys.readouterr()
