"""Dask executors: a 2-worker LocalCluster gives the local results bit for bit, even when a worker dies."""

import pytest

distributed = pytest.importorskip("distributed")

from shipid.cli import main  # noqa: E402
from shipid.errors import ShipidError  # noqa: E402
from shipid.campaign.engine import run_campaign  # noqa: E402

TOY = "shipid.campaign.toy:toy_run"
KW = {"n": 50, "fail_every": 61}


def _key(res):
    return [(r.index, r.seed, r.inputs, r.outputs, r.status, r.error) for r in res.records]


@pytest.fixture(scope="module")
def cluster():
    """One real 2-worker LocalCluster (separate processes, loopback) shared by this module."""
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cl, distributed.Client(cl) as client:
        yield cl, client


@pytest.fixture(scope="module")
def local_reference():
    return run_campaign(TOY, 400, 21, kwargs=KW, workers=1, progress=False)


def test_scheduler_executor_equals_local(cluster, local_reference):
    cl, client = cluster
    res = run_campaign(TOY, 400, 21, kwargs=KW, executor="scheduler", scheduler_address=cl.scheduler_address,
                       progress=False)
    assert res.executor == "scheduler" and res.workers == 2
    assert _key(res) == _key(local_reference)
    assert res.records[60].error == "ValueError: toy failure at run 60"


def test_two_local_workers_equal_dask(cluster, local_reference):
    res = run_campaign(TOY, 400, 21, kwargs=KW, workers=2, progress=False)
    assert _key(res) == _key(local_reference)


def test_dask_cli_with_store_then_resume_is_noop(cluster, tmp_path, capsys):
    cl, _ = cluster
    store = str(tmp_path / "d.sqlite")
    args = ["study", "toy", "--runs", "50", "--seed", "3", "--scheduler", cl.scheduler_address, "--store", store]
    assert main(args + ["--json"]) == 0
    assert main(args + ["--resume", "--json"]) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert '"reused_from_store": 50' in out[-1]
    assert main(["study", "toy", "--workers", "2", "--scheduler", cl.scheduler_address]) == 2
    assert "--workers is for the local pool" in capsys.readouterr().err


def test_unreachable_scheduler_is_one_line(monkeypatch):
    monkeypatch.setattr("shipid.campaign.executors.DASK_CONNECT_TIMEOUT_S", 1)
    with pytest.raises(ShipidError, match="cannot reach the Dask scheduler"):
        run_campaign(TOY, 3, 0, executor="scheduler", scheduler_address="tcp://127.0.0.1:9", progress=False)


def test_killed_worker_mid_campaign_still_equals_local(cluster, local_reference, tmp_path):
    """A worker process dies (os._exit) while running run 200; Dask re-runs its work elsewhere."""
    cl, client = cluster
    pids_before = set(client.run(lambda: __import__("os").getpid()).values())
    marker = tmp_path / "died"
    res = run_campaign(TOY, 400, 21, kwargs={**KW, "die_at": 200, "marker": str(marker)},
                       executor="scheduler", scheduler_address=cl.scheduler_address, progress=False)
    assert marker.exists()
    dead_pid = int(marker.read_text())
    assert dead_pid in pids_before           # it was one of the cluster's worker processes
    assert [(r.index, r.outputs, r.status, r.error) for r in res.records] == \
        [(r.index, r.outputs, r.status, r.error) for r in local_reference.records]
    client.wait_for_workers(2, timeout=60)   # the nanny restarts it
    assert dead_pid not in set(client.run(lambda: __import__("os").getpid()).values())


def test_dask_local_cli_into_store_equals_local(local_reference, tmp_path):
    """`shipid study toy --dask-local 2 --store F` starts its own LocalCluster; the store equals the local run."""
    from shipid.campaign.store import CampaignStore

    store = str(tmp_path / "dl.sqlite")
    assert main(["study", "toy", "--runs", "400", "--seed", "21", "--points", "50", "--fail-every", "61",
                 "--dask-local", "2", "--store", store, "--json"]) == 0
    with CampaignStore(store) as st:
        recs = st.records("toy")
    assert [(r.index, r.seed, r.outputs, r.status, r.error) for r in recs] == \
        [(r.index, r.seed, r.outputs, r.status, r.error) for r in local_reference.records]


def test_run_that_always_kills_its_dask_worker_is_recorded_failed(local_reference):
    """Dask gives up on the chunk (KilledWorker); the engine splits it and records only the guilty run."""
    dask = pytest.importorskip("dask")
    with dask.config.set({"distributed.scheduler.allowed-failures": 1}):   # fewer worker restarts: faster test
        res = run_campaign(TOY, 400, 21, kwargs={**KW, "die_at": 77}, executor="dask-local", workers=2,
                           progress=False)
    assert [r.index for r in res.failed if r.error.startswith("WorkerDied")] == [77]
    others = [k for k in range(400) if k != 77]
    assert [res.records[k].outputs for k in others] == [local_reference.records[k].outputs for k in others]


def test_external_scheduler_and_worker_processes(tmp_path, local_reference):
    """`--scheduler` against a cluster started by the `dask` CLI in separate processes (loopback only)."""
    import json
    import os
    import signal
    import subprocess
    import sys
    import time

    dask_cli = [sys.executable, "-m", "dask"]
    sched_file = tmp_path / "scheduler.json"
    common = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "start_new_session": True}
    procs = [subprocess.Popen(dask_cli + ["scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                                          "--scheduler-file", str(sched_file)], **common)]
    try:
        deadline = time.monotonic() + 60
        while not sched_file.exists():
            assert time.monotonic() < deadline and procs[0].poll() is None, "scheduler did not start"
            time.sleep(0.1)
        time.sleep(0.2)   # the file is written in one go, but let the writer finish
        address = json.loads(sched_file.read_text())["address"]
        procs.append(subprocess.Popen(dask_cli + ["worker", address, "--nworkers", "2", "--nthreads", "1",
                                                  "--host", "127.0.0.1", "--no-dashboard"], **common))
        with distributed.Client(address, timeout=30) as c:
            c.wait_for_workers(2, timeout=60)
        store = str(tmp_path / "ext.sqlite")
        assert main(["study", "toy", "--runs", "400", "--seed", "21", "--points", "50", "--fail-every", "61",
                     "--scheduler", address, "--store", store]) == 0
        from shipid.campaign.store import CampaignStore
        with CampaignStore(store) as st:
            recs = st.records("toy")
        assert [(r.index, r.outputs, r.status, r.error) for r in recs] == \
            [(r.index, r.outputs, r.status, r.error) for r in local_reference.records]
        assert len({r.worker for r in recs}) >= 1
    finally:
        for p in reversed(procs):   # only the process groups this test started
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGTERM)
        for p in procs:
            try:
                p.wait(timeout=15)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)


def test_scheduler_workers_run_the_warm_up_before_the_first_run(cluster):
    """With an existing scheduler the warm-up runs on every connected worker (``client.run``) first."""
    cl, client = cluster
    res = run_campaign("shipid.campaign.toy:toy_probe", 20, 3, executor="scheduler",
                       scheduler_address=cl.scheduler_address, progress=False,
                       warm_up="shipid.campaign.toy:toy_warm_up")
    outs = [r.outputs for r in res.records]
    assert all(o["warmed_in"] == o["pid"] for o in outs)          # warmed in the worker itself
    assert len(set(client.run(_warmed_pid).values()) - {None}) == 2   # both workers, not just those that ran


def _warmed_pid():
    import shipid.campaign.toy as toy
    return toy.WARMED_IN
