"""The CI guard of tests/conftest.py: with CI=true, missing real data fails the run instead of skipping."""

import os
import subprocess
import sys
from pathlib import Path

TESTS = Path(__file__).resolve().parents[1]


def _pytest(env_extra, tmp_path):
    env = {**os.environ, **env_extra}
    # one tiny test of this folder, collected with the suite's conftest
    return subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                           str(TESTS / "ci" / "test_ci_guard.py::test_trivial")],
                          capture_output=True, text=True, env=env, cwd=TESTS.parent, timeout=120)


def test_trivial():
    assert 1 + 1 == 2


def test_ci_without_real_data_fails(tmp_path):
    done = _pytest({"CI": "true", "SHIPID_DATA": str(tmp_path / "nowhere")}, tmp_path)
    assert done.returncode == 4, done.stdout + done.stderr
    assert "real data are missing" in done.stdout + done.stderr


def test_without_ci_missing_data_only_skips(tmp_path):
    done = _pytest({"CI": "", "SHIPID_DATA": str(tmp_path / "nowhere")}, tmp_path)
    assert done.returncode == 0, done.stdout + done.stderr
