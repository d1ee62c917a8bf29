"""The command line answers --help and --version, and unknown commands with exit 2."""

import subprocess
import sys

import shipid
from shipid.cli import main


def test_version(capsys):
    assert main(["--version"]) == 0
    assert shipid.__version__ in capsys.readouterr().out


def test_help_lists_groups(capsys):
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    for group in ("identify", "study", "analyse", "design"):
        assert group in out


def test_unknown_command_is_one_line_exit_2():
    proc = subprocess.run([sys.executable, "-m", "shipid", "no-such-command"], capture_output=True, text=True)
    assert proc.returncode == 2
    assert len(proc.stderr.strip().splitlines()) == 1
    assert "Traceback" not in proc.stderr


def test_bare_shipid_and_bare_group_print_their_help(capsys):
    from shipid.cli import main

    assert main([]) == 0
    out = capsys.readouterr().out
    assert out.startswith("Usage: shipid") and "Commands:" in out and "shipid: error" not in out
    assert main(["study"]) == 0
    out = capsys.readouterr().out
    # summaries whole: click cut them at 45 characters and at "Fig." (issue 14)
    line = next(ln for ln in out.splitlines() if ln.strip().startswith("mass-cm-contour"))
    assert "Fig. 4: cost" in line and "..." not in out.split("Commands:")[1]


def test_format_is_a_choice_everywhere(capsys):
    from shipid.cli import main

    for argv in (["identify", "mmg", "--trial", "x.csv", "--format", "foo"],
                 ["validate", "m.json", "--trial", "x.csv", "--format", "foo"],
                 ["check", "x.csv", "--format", "foo"]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "'foo' is not one of" in err and "kvlcc2" in err, argv
