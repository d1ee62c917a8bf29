"""The ``shipid`` process ends through :func:`shipid.cli.exit_now`: status and output as with Python's own exit."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import shipid

SRC = str(Path(shipid.__file__).resolve().parents[1])


def _shipid(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": SRC, "SHIPID_NO_PROGRESS": "1"}
    return subprocess.run([sys.executable, "-m", "shipid", *args], capture_output=True, text=True, env=env, cwd=cwd)


def test_status_and_piped_output_survive_the_quick_exit(tmp_path):
    ok = _shipid("vessels", cwd=tmp_path)
    assert ok.returncode == 0 and ok.stdout.count("\n") > 3 and ok.stdout.endswith("\n")   # all of it, flushed
    trial = tmp_path / "t.csv"
    trial.write_text("t [s],u [m/s],r [rad/s]\n" + "".join(f"{0.1 * i:.1f},1,0.01\n" for i in range(50)))
    check = _shipid("check", str(trial), "-o", str(tmp_path / "r.json"), cwd=tmp_path)
    assert check.returncode == 0 and (tmp_path / "r.json").stat().st_size > 0
    bad = _shipid("check", str(tmp_path / "missing.csv"), cwd=tmp_path)
    assert bad.returncode == 2 and bad.stderr.strip().count("\n") == 0 and "missing.csv" in bad.stderr
