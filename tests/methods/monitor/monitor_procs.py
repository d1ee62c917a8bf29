"""Helpers of the monitor's command tests: arguments, and the shipid command of this tree as a process."""

import os
import subprocess
import sys
from pathlib import Path

import shipid


def monitor_args(d, *extra):
    return ["monitor", "mass-cm", "--nominal", str(d / "s.nominal.csv"), "--calibration",
            str(d / "s.calibration.csv"), "--known", str(d / "s.known.toml"), *extra]


def shipid_cmd(*args):
    """``python -m shipid ARGS`` of this source tree, as a process."""
    return [sys.executable, "-m", "shipid", *args]


def env():
    e = dict(os.environ)
    src = str(Path(shipid.__file__).resolve().parents[1])
    e["PYTHONPATH"] = src + os.pathsep + e.get("PYTHONPATH", "")
    e["SHIPID_NO_PROGRESS"] = "1"
    return e


def run(*args, timeout=120, **kw):
    return subprocess.run(shipid_cmd(*args), env=env(), capture_output=True, text=True, timeout=timeout, **kw)
