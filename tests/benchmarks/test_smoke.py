"""Every script in ``benchmarks/`` runs: each at its smallest size (``--smoke``), in a fresh interpreter.

No timing is asserted (benchmarks print ratios; a test does not time). The test catches a renamed or
removed function, module or option that a benchmark uses, which nothing else imports. A script that
needs an optional peer library (filterpy, statsmodels) or the shared real data is skipped without it.
A new script in ``benchmarks/`` is picked up here and must accept ``--smoke``.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest

import shipid
from shipid.io.paths import data_root

ROOT = Path(__file__).resolve().parents[2]
BENCH = ROOT / "benchmarks"
SRC = str(Path(shipid.__file__).resolve().parents[1])
SCRIPTS = sorted(p.name for p in BENCH.glob("*.py") if not p.name.startswith("_"))

#: Optional peers a script compares against (the script fails without them; the test skips).
NEEDS = {"bench_dp_ekf.py": ("filterpy",), "bench_ebm_filter.py": ("filterpy",),
         "bench_masscm_arma.py": ("statsmodels",)}
#: Scripts that read the shared real data.
REAL_DATA = {"bench_mmg_cv.py"}


def test_the_benchmarks_are_found():
    assert len(SCRIPTS) >= 10 and "bench_cli_startup.py" in SCRIPTS


@pytest.mark.parametrize("script", SCRIPTS)
def test_benchmark_runs_at_its_smallest_size(script, tmp_path):
    missing = [m for m in NEEDS.get(script, ()) if importlib.util.find_spec(m) is None]
    if missing:
        pytest.skip(f"{script} compares against {', '.join(missing)} (not installed)")
    if script in REAL_DATA and data_root() is None:
        pytest.skip(f"{script} reads the shared real data (not found)")
    env = dict(os.environ, SHIPID_NO_PROGRESS="1",
               PYTHONPATH=os.pathsep.join([SRC, *filter(None, [os.environ.get("PYTHONPATH")])]))
    p = subprocess.run([sys.executable, str(BENCH / script), "--smoke"], cwd=tmp_path, env=env,
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, f"{script} --smoke failed (exit {p.returncode}):\n{p.stderr[-3000:]}"
    assert p.stdout.strip(), f"{script} --smoke printed nothing"
    assert "Traceback" not in p.stderr, p.stderr[-3000:]
