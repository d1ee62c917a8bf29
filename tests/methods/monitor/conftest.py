"""A simulated stream with its reference files, shared by the monitor's command tests."""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
from monitor_procs import monitor_args  # noqa: E402


@pytest.fixture(scope="session")
def stream300(tmp_path_factory):
    """300 s at 50 Hz, the load changed at 200 s (0.4 kg / -0.182 m -> 0.7 kg / -0.14 m), seed 3; plus the
    monitor's JSON lines read from the file directly (``ref.jsonl``)."""
    from shipid.cli import main

    d = tmp_path_factory.mktemp("stream300")
    assert main(["simulate", "fishing-vessel", "mass-cm-stream", "--duration", "300", "--change-at", "200",
                 "--to", "0.7,-0.14", "--seed", "3", "--out", str(d / "s.csv")]) == 0
    assert main(monitor_args(d, "--stream", str(d / "s.csv"), "-o", str(d / "ref.jsonl"))) == 0
    return d
