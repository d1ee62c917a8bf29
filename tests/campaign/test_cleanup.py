"""No process of shipid's outlives a campaign command.

A local pool forks its workers from a ``forkserver`` that ``multiprocessing`` pairs with a resource
tracker; both outlive the pool. The command is run in a session of its own
(``start_new_session``), so every process it started, and every process those started, carries its
session id whoever reaps it; when the command has returned, none may be left, not even as a zombie
waiting for ``init`` to reap it.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import shipid

SRC = str(Path(shipid.__file__).resolve().parents[1])

pytestmark = pytest.mark.skipif(not hasattr(os, "getsid"), reason="needs POSIX sessions")


def _pids() -> list[int]:
    try:
        import psutil
    except ImportError:
        if not os.path.isdir("/proc"):
            pytest.skip("neither psutil nor /proc to list processes")
        return [int(d) for d in os.listdir("/proc") if d.isdigit()]
    return psutil.pids()


def _in_session(sid: int) -> list[int]:
    out = []
    for pid in _pids():
        try:
            if os.getsid(pid) == sid:
                out.append(pid)
        except OSError:                       # gone meanwhile
            pass
    return out


def _describe(pid: int) -> str:
    try:
        with open(f"/proc/{pid}/stat", encoding="utf-8") as fh:
            return fh.read()[:80]
    except OSError:
        return str(pid)


@pytest.mark.parametrize("engine", [pytest.param(["--workers", "2"], id="pool"),
                                    pytest.param(["--dask-local", "2"], id="dask-local", marks=pytest.mark.slow)])
def test_a_campaign_leaves_no_process_behind(engine, tmp_path):
    if engine[0] == "--dask-local":
        pytest.importorskip("distributed")
    env = dict(os.environ, SHIPID_NO_PROGRESS="1",
               PYTHONPATH=os.pathsep.join([SRC, *filter(None, [os.environ.get("PYTHONPATH")])]))
    p = subprocess.Popen([sys.executable, "-m", "shipid", "study", "mass-cm-sensitivity", "--runs", "4", *engine,
                          "--json"], cwd=tmp_path, env=env, start_new_session=True, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    out, err = p.communicate(timeout=300)
    left = _in_session(p.pid)                 # the command has returned: nothing of it may remain
    assert p.returncode == 0, err
    assert json.loads(out)["runs"] == 4
    assert "leaked" not in err and "Traceback" not in err
    assert left == [], [_describe(pid) for pid in left]
