"""The local engine: same results for any worker count, failures recorded, worker deaths survived."""

import json

import numpy as np
import pytest

from shipid.errors import ShipidError
from shipid.campaign.engine import CampaignOptions, chunk_indices, run_campaign, task_reference
from shipid.campaign.toy import toy_run

TOY = "shipid.campaign.toy:toy_run"


def _key(res):
    return [(r.index, r.seed, r.inputs, r.outputs, r.status, r.error) for r in res.records]


@pytest.fixture(scope="module")
def reference():
    """A 300-run toy campaign computed in this process (workers=1)."""
    return run_campaign(TOY, 300, 11, kwargs={"n": 50, "fail_every": 97}, workers=1, progress=False)


def test_in_process_matches_direct_calls(reference):
    assert reference.executor == "in-process"
    for i in (0, 1, 150, 299):
        expect = toy_run(i, np.random.SeedSequence([11, i]), n=50)
        assert reference.records[i].outputs == expect
        assert reference.records[i].seed == [11, i]


def test_two_local_workers_equal_one_bit_for_bit(reference):
    # a short sleep per run (no effect on outputs) makes both processes take chunks
    res = run_campaign(TOY, 300, 11, kwargs={"n": 50, "fail_every": 97, "sleep": 0.01}, workers=2,
                       progress=False)
    assert res.executor == "local" and res.workers == 2
    assert len({r.worker for r in res.records}) == 2  # really two processes
    assert _key(res) == _key(reference)


def test_chunking_does_not_change_results(reference):
    res = run_campaign(toy_run, 300, 11, kwargs={"n": 50, "fail_every": 97}, workers=2, chunk_size=7,
                       progress=False)
    assert _key(res) == _key(reference)


def test_failed_runs_are_recorded_with_their_error(reference):
    failed = reference.failed
    assert [r.index for r in failed] == [96, 193, 290]
    assert all(r.status == "failed" and r.outputs is None for r in failed)
    assert failed[0].error == "ValueError: toy failure at run 96"
    assert reference.n_ok == 297
    assert reference.outputs[96] is None


def test_per_run_inputs_are_merged_and_stored():
    inputs = [{"slope": float(k)} for k in range(6)]
    res = run_campaign(TOY, None, 3, inputs=inputs, kwargs={"n": 400, "noise": 0.0}, workers=1, progress=False)
    assert res.n_runs == 6
    assert [r.inputs for r in res.records] == inputs
    np.testing.assert_allclose([o["b"] for o in res.outputs], np.arange(6.0), atol=1e-9)


def test_worker_process_death_is_survived(tmp_path, reference):
    """A pool worker dies (os._exit) at run 120 once: the run is redone elsewhere, results unchanged."""
    marker = tmp_path / "died"
    kw = {"n": 50, "fail_every": 97, "die_at": 120, "marker": str(marker)}
    res = run_campaign(TOY, 300, 11, kwargs=kw, workers=2, progress=False)
    assert marker.exists()
    assert [(r.index, r.outputs, r.status, r.error) for r in res.records] == \
        [(r.index, r.outputs, r.status, r.error) for r in reference.records]


def test_a_pool_that_breaks_between_collecting_and_submitting_is_replaced(monkeypatch, reference):
    """The race CI met on 2026-12-03: a worker died while other futures were being collected, so the next
    ``submit`` raised BrokenProcessPool before the dead worker's futures were marked. Here a stand-in pool
    (threads) refuses its 3rd and 9th submissions that way and stays broken, as a real one does, while the
    futures already in flight end normally: the chunk goes back to its queue, a fresh pool takes it once
    nothing is in flight, and the results equal the in-process reference."""
    import concurrent.futures as cf
    from concurrent.futures.process import BrokenProcessPool

    from shipid.campaign import executors

    calls = [0]

    class FlakyPool(cf.ThreadPoolExecutor):
        def __init__(self, max_workers=None, mp_context=None, initializer=None):
            super().__init__(max_workers=max_workers)
            self.broke = False

        def submit(self, fn, /, *args, **kwargs):
            calls[0] += 1
            if self.broke or calls[0] in (3, 9):
                self.broke = True            # a broken pool stays broken, as the real one does
                raise BrokenProcessPool("stand-in: broken since the last wait")
            return super().submit(fn, *args, **kwargs)

    monkeypatch.setattr(cf, "ProcessPoolExecutor", FlakyPool)
    monkeypatch.setattr(executors, "start_forkserver", lambda *a, **k: False)
    rows = [r for rows in executors.iter_pool([list(range(k, min(k + 25, 300))) for k in range(0, 300, 25)], 2,
                                               lambda c: (TOY, 11, c, None, {"n": 50, "fail_every": 97}), 11)
            for r in rows]
    assert calls[0] > 9
    got = sorted((r["index"], None if r["outputs_json"] is None else json.loads(r["outputs_json"]), r["status"])
                 for r in rows)
    assert got == [(r.index, r.outputs, r.status) for r in reference.records]


def test_run_that_always_kills_its_worker_is_recorded_failed(reference):
    res = run_campaign(TOY, 300, 11, kwargs={"n": 50, "fail_every": 97, "die_at": 40}, workers=2, progress=False)
    assert res.records[40].status == "failed"
    assert res.records[40].error.startswith("WorkerDied")
    others = [k for k in range(300) if k != 40]
    assert [res.records[k].outputs for k in others] == [reference.records[k].outputs for k in others]


def test_outputs_survive_json_exactly():
    res = run_campaign("shipid.campaign.toy:toy_run", 5, 1, workers=1, progress=False)
    for r in res.records:
        assert json.loads(json.dumps(r.outputs)) == r.outputs
        assert isinstance(r.outputs["a"], float)


def test_chunk_indices_cover_everything_once():
    idx = list(range(1003))
    chunks = chunk_indices(idx, 2)
    assert [i for c in chunks for i in c] == idx
    assert max(len(c) for c in chunks) <= 100
    assert [len(c) for c in chunks] == sorted((len(c) for c in chunks), reverse=True)   # shrinking
    big = chunk_indices(list(range(10_000)), 2)
    assert 100 <= len(big) <= 200                              # not 10 000 round trips
    assert len(big[0]) == 100 and len(big[-1]) == 1
    assert [len(c) for c in chunk_indices(idx, 2, chunk_size=500)] == [500, 500, 3]


def test_bad_definitions_are_one_line_errors():
    with pytest.raises(ShipidError, match="module:function"):
        run_campaign("no_colon", 3, 0)
    with pytest.raises(ShipidError, match="cannot import"):
        run_campaign("shipid.nope:f", 3, 0)
    with pytest.raises(ShipidError, match="top-level"):
        task_reference(lambda i, s: {})
    with pytest.raises(ShipidError, match="needs --store"):
        run_campaign(TOY, 3, 0, resume=True)
    with pytest.raises(ShipidError, match="JSON"):
        run_campaign(TOY, 3, 0, kwargs={"n": object()})
    with pytest.raises(ShipidError, match="2 run inputs"):
        run_campaign(TOY, 3, 0, inputs=[{}, {}])


def test_campaign_options_validation():
    with pytest.raises(ShipidError, match="exclude"):
        CampaignOptions(dask_local=2, scheduler="tcp://127.0.0.1:1")
    with pytest.raises(ShipidError, match="--workers"):
        CampaignOptions(workers=2, dask_local=2)
    with pytest.raises(ShipidError, match="--resume needs"):
        CampaignOptions(resume=True)
    opts = CampaignOptions(seed=4, dask_local=3, store="s.sqlite")
    assert opts.engine_kwargs() == {"executor": "dask-local", "workers": 3, "store": "s.sqlite",
                                    "resume": False, "retry_failed": False, "progress": True}


def test_runs_carry_their_code_and_mixed_code_warns(monkeypatch):
    from shipid.campaign.executors import code_fingerprint
    res = run_campaign(TOY, 4, 0, workers=1, progress=False)
    assert {r.code for r in res.records} == {code_fingerprint()} and res.mixed_code == 0
    # the engine believing it runs other source than its workers (an edited tree, another install)
    monkeypatch.setattr("shipid.campaign.engine.code_fingerprint", lambda: "f" * 64)
    with pytest.warns(RuntimeWarning, match="other shipid source"):
        res = run_campaign(TOY, 4, 0, workers=1, progress=False)
    assert res.mixed_code == 4
