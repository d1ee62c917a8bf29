"""Suite-wide fixtures and checks.

With ``CI`` set to a true value (``.ci/run`` sets ``CI=true``), a missing real-data folder
(``../shared/data`` or ``$SHIPID_DATA``, see :func:`shipid.io.paths.data_root`) stops the run
at once instead of letting the real-data tests skip: a CI run that skipped them would stay green
while checking less than it claims.

``no_raw_warnings``: a command must never let Python print its own warning text
(``/path/to/module.py:123: RuntimeWarning: ...`` and the code line) on stderr; every
warning is one ``shipid: warning: ...`` line (:mod:`shipid.cli._common`). The fixture
fails a test when

* the stderr of a ``shipid`` subprocess (``subprocess.run``) or the stderr read
  through ``capsys`` / ``capfd`` holds raw warning text, or
* a Python warning escapes ``shipid.cli.main`` (inside pytest such a warning is
  recorded rather than printed; in a real process Python would print it raw).

It is used automatically by every test module that imports ``shipid.cli.main`` and by
every test under ``tests/cli/``.

Real data: a test that reads the shared data sets is marked ``@pytest.mark.realdata`` and takes the
``data_root`` fixture (the folder, a :class:`pathlib.Path`). Without the folder every ``realdata`` test is
skipped with one reason (and, with ``CI`` true, the whole run stops, above); a test that asks for
``data_root`` is marked ``realdata`` automatically.

``tests/`` is put on ``sys.path`` so that test modules import the known answers of the papers
(``from known.linder2015 import TABLE3_TRUE``, :mod:`known`) under ``--import-mode=importlib``.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

if str(Path(__file__).parent) not in sys.path:      # `import known.<paper>` from any test module
    sys.path.insert(0, str(Path(__file__).parent))

from shipid.io.paths import data_root as _data_root

#: Python's warning format: "<file>.py:<line>: <Category>Warning: <message>" (and friends).
RAW_WARNING = re.compile(r":\d+: \w*Warning\b|^\s*warnings\.warn\(")
_QUIET = (DeprecationWarning, PendingDeprecationWarning, ImportWarning, ResourceWarning)
_CLI_DIR = Path(__file__).parent / "cli"


def assert_no_raw_warning(text: str, where: str = "stderr") -> None:
    """Fail if ``text`` holds Python's own warning format (a source path with a line number)."""
    for line in (text or "").splitlines():
        if RAW_WARNING.search(line):
            pytest.fail(f"raw Python warning text on {where}: {line.strip()!r}", pytrace=False)


def _uses_cli(request) -> bool:
    mod = request.module
    if mod is None:
        return False
    try:
        from shipid.cli import main
    except Exception:  # pragma: no cover - the suite cannot run at all then
        return False
    if getattr(mod, "main", None) is main:
        return True
    path = Path(getattr(mod, "__file__", "") or "")
    return _CLI_DIR in path.parents


@pytest.fixture
def no_raw_warnings(request, monkeypatch):
    """Fail the test on raw Python warning text from the CLI (module docstring)."""
    real_run = subprocess.run

    def run(*args, **kwargs):
        proc = real_run(*args, **kwargs)
        err = getattr(proc, "stderr", None)
        if isinstance(err, bytes):
            err = err.decode("utf-8", "replace")
        if isinstance(err, str):
            assert_no_raw_warning(err, "the stderr of a subprocess")
        return proc

    monkeypatch.setattr(subprocess, "run", run)
    for name in ("capsys", "capfd"):
        if name in request.fixturenames:
            cap = request.getfixturevalue(name)
            real_read = cap.readouterr

            def readouterr(_real=real_read, _name=name):
                res = _real()
                assert_no_raw_warning(res.err, f"stderr ({_name})")
                return res

            monkeypatch.setattr(cap, "readouterr", readouterr)
    import shipid.cli as cli_mod

    escaped: list = []
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        for cat in _QUIET:
            warnings.simplefilter("ignore", cat)
        real_inner = cli_mod.dispatch

        def inner(*args, **kwargs):  # what reaches this recorder while main runs escaped main's own
            i = len(rec)
            try:
                return real_inner(*args, **kwargs)
            finally:
                escaped.extend(w for w in rec[i:] if not issubclass(w.category, _QUIET))

        monkeypatch.setattr(cli_mod, "dispatch", inner)
        yield
    if escaped:
        w = escaped[0]
        pytest.fail(f"{len(escaped)} Python warning(s) escaped shipid.cli.main and would be printed raw, e.g. "
                    f"{w.category.__name__}: {' '.join(str(w.message).split())} "
                    f"({Path(w.filename).name}:{w.lineno})", pytrace=False)


@pytest.fixture(autouse=True)
def _cli_tests_use_no_raw_warnings(request):
    """Every CLI test (module imports ``shipid.cli.main``, or lives under tests/cli) gets ``no_raw_warnings``."""
    if _uses_cli(request):
        request.getfixturevalue("no_raw_warnings")
    yield


def _ci() -> bool:
    return os.environ.get("CI", "").strip().lower() in {"1", "true", "yes", "on"}


def pytest_collection_modifyitems(config, items):
    """Mark every test that takes ``data_root`` as ``realdata``; skip the ``realdata`` tests without the data."""
    root = _data_root()
    skip = pytest.mark.skip(reason="real data absent: ../shared/data or $SHIPID_DATA not found")
    for item in items:
        if "data_root" in getattr(item, "fixturenames", ()) and "realdata" not in item.keywords:
            item.add_marker(pytest.mark.realdata)
        if root is None and "realdata" in item.keywords:
            item.add_marker(skip)


@pytest.fixture(scope="session")
def data_root() -> Path:
    """The folder of the shared real data sets (``../shared/data`` or ``$SHIPID_DATA``); skips when absent."""
    root = _data_root()
    if root is None:
        pytest.skip("real data absent: ../shared/data or $SHIPID_DATA not found")
    return Path(root)


def pytest_sessionstart(session):
    if _ci() and _data_root() is None:
        where = os.environ.get("SHIPID_DATA") or "../shared/data"
        pytest.exit(f"CI: the real data are missing ({where} not found); set SHIPID_DATA or place "
                    "../shared/data beside the checkout", returncode=4)
