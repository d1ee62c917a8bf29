"""The SQLite store: SIGKILL part-way, resume, and the final store equals a clean run row for row."""

import json
import os
import signal
import sqlite3
import subprocess
import sys
import time

import pandas as pd
import pytest

from shipid.cli import main
from shipid.errors import ShipidError
from shipid.campaign.engine import run_campaign
from shipid.campaign.store import CampaignStore

TOY = "shipid.campaign.toy:toy_run"
TOY_KW = {"n": 200, "fail_every": 0, "sleep": 0.02}   # what `shipid study toy --sleep 0.02` passes
N = 400


def _stored_count(path) -> int:
    if not os.path.exists(path):
        return 0
    try:
        con = sqlite3.connect(str(path), timeout=5)
        try:
            return con.execute("SELECT COUNT(*) FROM runs").fetchone()[0]
        finally:
            con.close()
    except sqlite3.OperationalError:  # tables not created yet
        return 0


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def _same(a, b):
    return [(r.index, r.seed, r.inputs, r.outputs, r.status, r.error) for r in a] == \
        [(r.index, r.seed, r.inputs, r.outputs, r.status, r.error) for r in b]


def test_sigkill_then_resume_equals_clean_run(tmp_path):
    store = tmp_path / "toy.sqlite"
    env = {**os.environ, "SHIPID_NO_PROGRESS": "1"}
    cmd = [sys.executable, "-m", "shipid", "study", "toy", "--runs", str(N), "--sleep", "0.02",
           "--seed", "5", "--workers", "2", "--store", str(store)]
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            start_new_session=True)
    try:
        deadline = time.monotonic() + 60
        while _stored_count(store) < 50:
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline, "campaign never stored a chunk"
            time.sleep(0.05)
        proc.send_signal(signal.SIGKILL)
        proc.communicate(timeout=10)   # reaps it and closes its pipes
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == -signal.SIGKILL
    with CampaignStore(store) as st:
        before = {r.index: r for r in st.records("toy")}
    assert 50 <= len(before) < N, "the kill must land part-way"
    # the killed campaign's worker processes end with it (no orphans left behind)
    pids = {int(r.worker.rsplit(":", 1)[1]) for r in before.values()}
    deadline = time.monotonic() + 10
    while any(_pid_alive(p) for p in pids) and time.monotonic() < deadline:
        time.sleep(0.1)
    alive = [p for p in pids if _pid_alive(p)]
    for p in alive:  # clean up what we started before failing
        os.kill(p, signal.SIGKILL)
    assert not alive, f"worker processes {alive} outlived the killed campaign"

    # resume in-process through the CLI
    assert main(["study", "toy", "--runs", str(N), "--sleep", "0.02", "--seed", "5", "--workers", "2",
                 "--store", str(store), "--resume"]) == 0
    with CampaignStore(store) as st:
        resumed = st.records("toy")
        assert st.count("toy") == N
    clean = run_campaign(TOY, N, 5, kwargs={**TOY_KW, "sleep": 0.0}, workers=1, progress=False)
    assert _same(resumed, clean.records)
    # none repeated: the rows stored before the kill are untouched (same worker, same timing)
    for i, r in before.items():
        assert (resumed[i].worker, resumed[i].wall_s) == (r.worker, r.wall_s)


def test_resume_with_another_definition_is_refused(tmp_path, capsys):
    store = str(tmp_path / "s.sqlite")
    assert main(["study", "toy", "--runs", "20", "--workers", "1", "--store", store]) == 0
    capsys.readouterr()
    assert main(["study", "toy", "--runs", "20", "--workers", "1", "--store", store, "--resume",
                 "--seed", "9"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "seed=0, not seed=9" in err and "refusing to resume" in err
    assert main(["study", "toy", "--runs", "21", "--workers", "1", "--store", store, "--resume"]) == 2
    assert "n_runs=20, not n_runs=21" in capsys.readouterr().err
    assert main(["study", "toy", "--runs", "20", "--points", "30", "--workers", "1", "--store", store,
                 "--resume"]) == 2
    assert "kwargs=" in capsys.readouterr().err
    # without --resume an existing campaign is not silently extended or overwritten
    assert main(["study", "toy", "--runs", "20", "--workers", "1", "--store", store]) == 2
    assert "add --resume" in capsys.readouterr().err


def test_resume_of_a_complete_campaign_computes_nothing(tmp_path):
    store = tmp_path / "s.sqlite"
    first = run_campaign(TOY, 30, 2, workers=1, store=store, progress=False)
    again = run_campaign(TOY, 30, 2, workers=1, store=store, resume=True, progress=False)
    assert again.reused == 30 and again.workers == 0
    assert _same(first.records, again.records)


def test_store_is_wal_and_holds_metadata(tmp_path):
    store = tmp_path / "s.sqlite"
    run_campaign(TOY, 12, 4, kwargs={"n": 20, "fail_every": 5}, workers=1, store=store, name="demo",
                 progress=False)
    con = sqlite3.connect(str(store))
    assert con.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    row = con.execute("SELECT task, seed, n_runs, kwargs, shipid_version FROM campaigns WHERE name='demo'").fetchone()
    assert row[:3] == (TOY, 4, 12)
    assert json.loads(row[3]) == {"fail_every": 5, "n": 20}
    failed = con.execute("SELECT run, error, outputs FROM runs WHERE status='failed' ORDER BY run").fetchall()
    assert failed == [(4, "ValueError: toy failure at run 4", None), (9, "ValueError: toy failure at run 9", None)]
    con.close()
    with CampaignStore(store) as st, pytest.raises(sqlite3.IntegrityError):
        st.write("demo", [{"index": 0, "seed": [4, 0], "inputs_json": "{}", "outputs_json": "{}",
                           "status": "ok", "error": None, "wall_s": 0.0, "worker": "x"}])


@pytest.mark.parametrize("suffix", [".parquet", ".csv"])
def test_export(tmp_path, capsys, suffix):
    store = tmp_path / "s.sqlite"
    res = run_campaign(TOY, 15, 4, kwargs={"fail_every": 6}, workers=1, store=store, name="toy", progress=False)
    out = tmp_path / f"runs{suffix}"
    assert main(["study", "export", str(store), "--out", str(out)]) == 0
    frame = pd.read_parquet(out) if suffix == ".parquet" else pd.read_csv(out)
    assert list(frame["run"]) == list(range(15))
    assert list(frame["status"]) == [r.status for r in res.records]
    ok = frame["status"] == "ok"
    assert list(frame.loc[ok, "out.b"]) == [r.outputs["b"] for r in res.records if r.status == "ok"]
    assert main(["study", "export", str(store), "--out", str(out)]) == 2   # never clobbered
    assert "exists" in capsys.readouterr().err
    assert main(["study", "export", str(store), "--out", str(tmp_path / "x.txt")]) == 2


def test_export_needs_campaign_name_when_several(tmp_path):
    store = tmp_path / "s.sqlite"
    run_campaign(TOY, 3, 1, workers=1, store=store, name="a", progress=False)
    run_campaign(TOY, 3, 1, workers=1, store=store, name="b", progress=False)
    from shipid.campaign.store import export_store
    with pytest.raises(ShipidError, match="--campaign"):
        export_store(store, tmp_path / "o.csv")
    path, n = export_store(store, tmp_path / "o.csv", campaign="b")
    assert n == 3


def test_store_info_and_toy_json(tmp_path, capsys):
    store = str(tmp_path / "s.sqlite")
    assert main(["study", "toy", "--runs", "10", "--fail-every", "4", "--workers", "1", "--store", store,
                 "--json"]) == 0
    cap = capsys.readouterr()
    out = json.loads(cap.out)
    assert (out["runs"], out["ok"], out["failed"]) == (10, 8, 2)
    # the failed runs are one warning line, on stderr and in the JSON (shipid.cli.campaign_cmds.failure_lines)
    assert len(out["warnings"]) == 1 and "2 of 10 runs failed" in out["warnings"][0]
    assert "run 3: " in out["warnings"][0] and "run 7: " in out["warnings"][0]
    assert out["warnings"][0] in cap.err
    assert main(["study", "store-info", store, "--json"]) == 0
    info = json.loads(capsys.readouterr().out)["campaigns"][0]
    assert (info["name"], info["done"], info["failed"], info["n_runs"]) == ("toy", 10, 2, 10)


def test_failed_runs_and_strict_exit_3(tmp_path, capsys):
    """A study whose runs failed warns, so ``--strict`` exits 3; without failures it does not warn."""
    assert main(["--strict", "study", "toy", "--runs", "6", "--fail-every", "4", "--workers", "1", "--json"]) == 3
    assert "1 of 6 runs failed" in capsys.readouterr().err
    assert main(["--strict", "study", "toy", "--runs", "6", "--workers", "1", "--json"]) == 0
    cap = capsys.readouterr()
    assert json.loads(cap.out)["warnings"] == [] and "failed and are left out" not in cap.err


def test_not_a_store_is_one_line(tmp_path, capsys):
    bad = tmp_path / "junk.sqlite"
    bad.write_text("this is not sqlite\n" * 100)
    assert main(["study", "toy", "--runs", "3", "--store", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "not a usable campaign store" in err


def test_two_campaign_processes_never_share_a_store(tmp_path):
    store = tmp_path / "s.sqlite"
    with CampaignStore(store, writer=True):
        with pytest.raises(ShipidError, match="in use by another running campaign"):
            run_campaign(TOY, 3, 0, workers=1, store=store, progress=False)
        with CampaignStore(store) as reader:   # readers are never locked out
            assert reader.campaign_names() == []
    assert run_campaign(TOY, 3, 0, workers=1, store=store, progress=False).n_ok == 3


def test_retry_failed_reruns_only_failed_runs(tmp_path):
    """A resume skips failed runs; --retry-failed runs them again and leaves the ok rows alone."""
    store = tmp_path / "s.sqlite"
    marker = tmp_path / "died"
    kw = {"n": 30, "die_at": 5, "marker": str(marker)}
    with CampaignStore(store, writer=True) as st:   # simulate a campaign whose run 5 was lost to a dead worker
        from shipid.campaign.store import CampaignDefinition
        from shipid.campaign.engine import to_json
        import shipid
        st.create(CampaignDefinition("toy_run", TOY, 2, 12, to_json(kw, canonical=True), None, shipid.__version__))
        st.write("toy_run", [{"index": 5, "seed": [2, 5], "inputs_json": "{}", "outputs_json": None,
                              "status": "failed", "error": "WorkerDied: test", "wall_s": None, "worker": None}])
    marker.write_text("already died once")   # the run will now succeed
    res = run_campaign(TOY, 12, 2, kwargs=kw, workers=1, store=store, resume=True, progress=False)
    assert res.records[5].error == "WorkerDied: test"             # plain resume: not repeated
    before = {r.index: (r.worker, r.wall_s) for r in res.records}
    res2 = run_campaign(TOY, 12, 2, kwargs=kw, workers=1, store=store, resume=True, retry_failed=True,
                        progress=False)
    assert res2.n_failed == 0 and res2.reused == 11
    assert all((r.worker, r.wall_s) == before[r.index] for r in res2.records if r.index != 5)
    clean = run_campaign(TOY, 12, 2, kwargs=kw, workers=1, progress=False)
    assert _same(res2.records, clean.records)


def test_resume_with_other_inputs_is_refused(tmp_path):
    store = tmp_path / "s.sqlite"
    run_campaign(TOY, None, 1, inputs=[{"slope": 1.0}, {"slope": 2.0}], workers=1, store=store, progress=False)
    with pytest.raises(ShipidError, match="inputs_sha256"):
        run_campaign(TOY, None, 1, inputs=[{"slope": 1.0}, {"slope": 3.0}], workers=1, store=store, resume=True,
                     progress=False)


def test_export_of_nested_and_mixed_outputs(tmp_path):
    """Lists, nested dicts and an output whose type varies between runs all survive a Parquet export."""
    from shipid.campaign.store import RunRecord, records_frame
    recs = [RunRecord(0, [1, 0], {}, {"m": 0.4, "reasons": [], "fit": {"rmse": 0.1}, "note": "x"}, "ok"),
            RunRecord(1, [1, 1], {}, {"m": 1, "reasons": ["A1 <= 0"], "fit": {"rmse": 0.2}, "note": 3.5}, "ok"),
            RunRecord(2, [1, 2], {}, None, "failed", "ValueError: boom")]
    frame = records_frame(recs, "c")
    assert list(frame["out.fit.rmse"][:2]) == [0.1, 0.2]
    assert json.loads(frame["out.reasons"][1]) == ["A1 <= 0"]
    out = tmp_path / "x.parquet"
    frame.to_parquet(out, index=False)
    back = pd.read_parquet(out)
    assert list(back["out.note"][:2]) == ['"x"', "3.5"]
    assert back["error"][2] == "ValueError: boom"
