"""README.md is short, its test command is the one CI runs, and every code block in it runs.

* Length: at most 150 lines (the README is for users; measured figures live in ``docs/validation/``).
* The ``<!-- test-command -->`` block is exactly ``pip install -e '.[test]' && python -m pytest`` (``.ci/run``
  reads it) and the README names ``python -m pytest -m slow``.
* Fast check of every shell block and every inline ``shipid ...`` code span: the command path exists in the
  click tree and every option given is an option of that command; ``shipid``'s own options (``--strict``,
  ``--version``) only before the command.
* Slow: the shell blocks run as written, in order, in one fresh folder (``shipid`` is ``python -m shipid`` of this
  interpreter); the blocks that read the shared data (``$SHIPID_DATA``) or the model they produce are marked
  ``realdata``. The install block (``pip install``) is not run.
* Slow: the Python block runs and the coefficient it prints lies within 2 of its printed standard deviations
  (a 95 % interval) of the simulated ship's true value, with status ``estimated``.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import click
import pytest

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
TEXT = README.read_text(encoding="utf-8")
FENCE = re.compile(r"^```(\w*)[ \t]*\n(.*?)^```[ \t]*$", re.S | re.M)
BLOCKS = [(m.group(1), m.group(2)) for m in FENCE.finditer(TEXT)]
SHELL = [b for lang, b in BLOCKS if lang == "bash" and "pip install" not in b]
PYTHON = [b for lang, b in BLOCKS if lang == "python"]
#: the options of ``shipid`` itself, given before the command
GLOBAL_OPTIONS = {"--strict", "-h", "--help", "-V", "--version"}
#: the options every command takes too
HELP_OPTIONS = {"-h", "--help"}


def _needs_data(block: str) -> bool:
    return "SHIPID_DATA" in block or "model.json" in block


def _lines(block: str) -> list[str]:
    """Logical lines (continuations joined, comments dropped)."""
    joined = re.sub(r"\\\n\s*", " ", block)
    return [ln.split("  #")[0].strip() for ln in joined.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]


def _shipid_calls(line: str) -> list[list[str]]:
    """The ``shipid`` invocations of one shell line (split at ``;``, ``&&``, ``do``), as argument lists."""
    out = []
    for seg in re.split(r";|&&|\bdo\b|\bdone\b", line):
        toks = shlex.split(seg.split(" #")[0])
        if toks and toks[0] == "shipid":
            out.append(toks[1:])
    return out


def _inline_calls() -> list[list[str]]:
    return [shlex.split(m.group(1))[1:] for m in re.finditer(r"`(shipid [^`]+)`", TEXT)]


def _resolve(args: list[str]) -> tuple[click.Command, list[str], list[str]]:
    """(command, the names of its path, the option tokens given after the command's name) for ``shipid ARGS``.

    Options before the first command name are ``shipid``'s own: they must be :data:`GLOBAL_OPTIONS`.
    """
    from shipid.cli import cli

    cmd: click.Command = cli
    path: list[str] = []
    opts: list[str] = []
    rest = list(args)
    while rest:
        tok = rest.pop(0)
        if tok.startswith("-"):
            if not path:
                assert tok.split("=")[0] in GLOBAL_OPTIONS, f"`shipid {tok}`: not an option of shipid itself"
            else:
                opts.append(tok.split("=")[0])
            continue
        if re.fullmatch(r"[A-Z][A-Z_.]*|.*\*.*|\.\.\.", tok):   # a placeholder (CMD, FILE, ...) or a pattern
            if isinstance(cmd, click.Group):
                break                                        # the command itself is left open: nothing to check
            continue                                         # an argument of the command
        if isinstance(cmd, click.Group):
            sub = cmd.get_command(click.Context(cmd), tok)
            assert sub is not None, f"README: `shipid {' '.join(path + [tok])}` is not a command"
            cmd, path = sub, path + [tok]
        else:
            opts.extend(t.split("=")[0] for t in rest if t.startswith("-"))
            break
    return cmd, path, opts


def _all_calls() -> list[list[str]]:
    calls = [c for b in SHELL for ln in _lines(b) for c in _shipid_calls(ln)]
    return calls + [c for c in _inline_calls() if c]


def test_readme_is_short():
    n = len(TEXT.splitlines())
    assert n <= 150, f"README.md has {n} lines (at most 150; measured figures go to docs/validation/)"


def test_readme_test_command_is_the_ci_command():
    m = re.search(r"<!-- test-command -->\s*```bash\n(.*?)\n```\s*<!-- /test-command -->", TEXT, re.S)
    assert m, "the <!-- test-command --> block is missing"
    assert m.group(1).strip() == "pip install -e '.[test]' && python -m pytest"
    assert "python -m pytest -m slow" in TEXT


@pytest.mark.parametrize("args", _all_calls(), ids=lambda a: " ".join(a)[:60])
def test_readme_commands_exist_with_their_options(args):
    cmd, path, opts = _resolve(args)
    names = {o for p in cmd.params for o in (*p.opts, *p.secondary_opts)}
    unknown = [o for o in opts if o not in names and o not in HELP_OPTIONS]
    assert not unknown, f"README: `shipid {' '.join(path)}` has no option {unknown}"


def _run_blocks(blocks: list[str], workdir: Path, env: dict) -> None:
    prelude = f'shipid() {{ "{sys.executable}" -m shipid "$@"; }}\nset -euo pipefail\n'
    for block in blocks:
        proc = subprocess.run(["bash", "-c", prelude + block], cwd=workdir, env=env, capture_output=True,
                              text=True, timeout=1500)
        assert proc.returncode == 0, f"README block failed ({proc.returncode}):\n{block}\n{proc.stderr[-3000:]}"


def _env() -> dict:
    env = dict(os.environ, SHIPID_NO_PROGRESS="1")
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    return env


@pytest.mark.slow
def test_readme_shell_blocks_run(tmp_path):
    _run_blocks([b for b in SHELL if not _needs_data(b)], tmp_path, _env())


@pytest.mark.slow
@pytest.mark.realdata
def test_readme_real_data_blocks_run(tmp_path, data_root):
    env = _env()
    env["SHIPID_DATA"] = str(data_root)
    _run_blocks([b for b in SHELL if _needs_data(b)], tmp_path, env)


@pytest.mark.slow
def test_readme_python_block_is_right(tmp_path, monkeypatch):
    assert len(PYTHON) == 1
    monkeypatch.chdir(tmp_path)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(PYTHON[0], "README.md", "exec"), {"__name__": "__readme__"})
    m = re.search(r"= (\S+) ± (\S+) \(([^)]*)\); truth (\S+)", out.getvalue())
    assert m, out.getvalue()
    value, std, status, truth = float(m.group(1)), float(m.group(2)), m.group(3), float(m.group(4))
    assert status == "estimated", out.getvalue()
    assert abs(value - truth) <= 2.0 * std, out.getvalue()
