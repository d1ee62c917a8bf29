"""The tutorials in docs/ run, and print what they show.

Each ``docs/*.md`` tutorial is a script cut into Markdown: its ```` ```python ```` blocks run in order in
one namespace, in a fresh working directory. A ```` ```text ```` block that directly follows a python
block (only prose between them) is the output of that block: the test compares it with what the block
printed, line by line (trailing spaces ignored). A failing block, or a shown output the code does not
print, fails the test.

The shown outputs are written by running the code, never by hand::

    python tests/docs/test_tutorials.py docs/ebm.md      # rewrite the text blocks of one tutorial

Tutorials that read the real data sets (``needs: realdata`` in their first lines) are marked ``realdata``
(skipped when ``../shared/data`` or ``$SHIPID_DATA`` is absent, tests/conftest.py).
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import sys
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[2] / "docs"
#: Pages of docs/ that are not tutorials (the site's index, the CLI page, the API reference).
NOT_TUTORIALS = {"README.md", "index.md", "cli.md", "api.md"}
TUTORIALS = sorted(p for p in DOCS.glob("*.md") if p.name not in NOT_TUTORIALS)
FENCE = re.compile(r"^```(\w*)[ \t]*\n(.*?)^```[ \t]*$", re.S | re.M)


def blocks(text: str) -> list[tuple[str, str, int, int]]:
    """The fenced blocks of ``text``: (language, body, start, end) with the offsets of the whole fence."""
    return [(m.group(1), m.group(2), m.start(), m.end()) for m in FENCE.finditer(text)]


def pairs(text: str) -> list[tuple[str, str | None, tuple[int, int] | None]]:
    """(python code, the text block shown as its output or None, that block's body offsets) in order."""
    bs = blocks(text)
    out = []
    for i, (lang, body, _, _) in enumerate(bs):
        if lang != "python":
            continue
        shown, where = None, None
        if i + 1 < len(bs) and bs[i + 1][0] == "text":
            shown = bs[i + 1][1]
            start = bs[i + 1][2] + text[bs[i + 1][2]:].index("\n") + 1
            where = (start, start + len(shown))
        out.append((body, shown, where))
    return out


def run_tutorial(path: Path, workdir: Path) -> list[tuple[str, str | None, str, tuple[int, int] | None]]:
    """Run every python block of ``path`` in ``workdir``; returns (code, shown, printed, offsets) per block."""
    ns: dict = {"__name__": "__tutorial__"}
    results = []
    old = os.getcwd()
    os.chdir(workdir)
    try:
        for i, (code, shown, where) in enumerate(pairs(path.read_text(encoding="utf-8"))):
            buf = io.StringIO()
            with contextlib.redirect_stdout(buf):
                exec(compile(code, f"{path.name}[block {i + 1}]", "exec"), ns)
            results.append((code, shown, buf.getvalue(), where))
    finally:
        os.chdir(old)
    return results


def _norm(text: str) -> list[str]:
    return [ln.rstrip() for ln in text.rstrip().splitlines()]


def _needs_realdata(path: Path) -> bool:
    head = path.read_text(encoding="utf-8").splitlines()[:5]
    return any("needs: realdata" in ln for ln in head)


def test_there_is_a_tutorial_per_method():
    assert {p.stem for p in TUTORIALS} >= {"mass-cm", "dp", "ebm", "mmg", "monitor"}


def _param(path: Path):
    return pytest.param(path, id=path.stem, marks=[pytest.mark.realdata] if _needs_realdata(path) else [])


@pytest.mark.parametrize("path", [_param(p) for p in TUTORIALS])
def test_tutorial_runs_and_prints_what_it_shows(path, tmp_path):
    code_blocks = pairs(path.read_text(encoding="utf-8"))
    assert code_blocks, f"{path.name}: no python block"
    assert "import shipid" in code_blocks[0][0], f"{path.name}: the first block must import shipid"
    for i, (_, shown, printed, _) in enumerate(run_tutorial(path, tmp_path)):
        if shown is not None:
            assert _norm(printed) == _norm(shown), f"{path.name} block {i + 1}: printed output differs from the shown"


def update(path: Path) -> None:
    """Rewrite the text blocks of ``path`` with what its python blocks print (run in a temporary folder)."""
    import tempfile

    text = path.read_text(encoding="utf-8")
    with tempfile.TemporaryDirectory() as d:
        res = run_tutorial(path, Path(d))
    for _, shown, printed, where in reversed(res):
        if where is not None:
            text = text[:where[0]] + printed.rstrip() + "\n" + text[where[1]:]
    path.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    for arg in sys.argv[1:]:
        update(Path(arg).resolve())
        print(f"updated {arg}")
