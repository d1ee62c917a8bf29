"""docs/cli.md names commands and options that exist: every ``shipid ...`` code span resolves in the click tree
with the options it shows, and every option of the conventions table is an option of at least one command."""

from __future__ import annotations

import importlib.util
import re
import shlex
from pathlib import Path

import pytest

_SPEC = importlib.util.spec_from_file_location("_readme_checks", Path(__file__).with_name("test_readme.py"))
_README = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(_README)
HELP_OPTIONS, _resolve = _README.HELP_OPTIONS, _README._resolve

PAGE = (Path(__file__).resolve().parents[2] / "docs" / "cli.md").read_text(encoding="utf-8")
CALLS = [shlex.split(m.group(1))[1:] for m in re.finditer(r"`(shipid [^`]+)`", PAGE)]
#: The options of the conventions table (the table headed ``| option | meaning |``, first column).
_CONVENTIONS = PAGE.split("| option | meaning |", 1)[1].split("\n\n", 1)[0]
TABLE = [o for row in re.findall(r"^\| `(-[^`]+)`", _CONVENTIONS, re.M)
         for o in re.findall(r"(?<![\w-])--?[\w-]+", row)]


def _all_options() -> set[str]:
    from shipid.cli import cli, load_all_commands, walk

    load_all_commands()
    return {o for _path, cmd in walk(cli) for p in cmd.params for o in (*p.opts, *p.secondary_opts)} | \
        {o for p in cli.params for o in p.opts}


@pytest.mark.parametrize("args", CALLS, ids=lambda a: " ".join(a)[:60])
def test_cli_page_commands_exist_with_their_options(args):
    cmd, path, opts = _resolve(args)
    names = {o for p in cmd.params for o in (*p.opts, *p.secondary_opts)}
    unknown = [o for o in opts if o not in names and o not in HELP_OPTIONS]
    assert not unknown, f"docs/cli.md: `shipid {' '.join(path)}` has no option {unknown}"


def test_cli_page_conventions_are_real_options():
    assert len(TABLE) >= 10
    missing = sorted(set(TABLE) - _all_options())
    assert not missing, f"docs/cli.md names options no command has: {missing}"
