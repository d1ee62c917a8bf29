"""Campaign warm-up: workers forked from a forkserver that ran the task's warm-up once.

Each check runs in a fresh Python process, because a process has one forkserver and
only the campaign that starts it can warm it (:func:`shipid.campaign.executors.start_forkserver`).
"""

import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from shipid.campaign.engine import run_campaign

PROBE, WARM = "shipid.campaign.toy:toy_probe", "shipid.campaign.toy:toy_warm_up"


def _in_fresh_process(code: str, env: dict | None = None) -> dict:
    script = textwrap.dedent("""
        import json, os, sys, warnings
        from shipid.campaign.engine import run_campaign
        def main():
        {body}
        if __name__ == "__main__":
            main()
        """).format(body=textwrap.indent(textwrap.dedent(code), "    "))
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300,
                          env={**os.environ, **(env or {})})
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("executor", ["local", "dask-local"])
def test_workers_come_warm_from_the_forkserver(executor):
    out = _in_fresh_process(f"""
        res = run_campaign("{PROBE}", 40, 3, workers=2, executor="{executor}", progress=False, warm_up="{WARM}")
        import shipid.campaign.toy as toy
        print(json.dumps({{"parent": os.getpid(), "parent_warm": toy.WARMED_IN,
                          "runs": [r.outputs for r in res.records]}}))
        """)
    pids = {r["pid"] for r in out["runs"]}
    warmed = {r["warmed_in"] for r in out["runs"]}
    assert out["parent_warm"] == out["parent"]            # the parent ran it first (compiles, writes caches)
    assert len(warmed) == 1 and None not in warmed        # every worker inherited one warm-up ...
    (server,) = warmed
    assert server != out["parent"] and server not in pids  # ... run in neither the parent nor a worker
    assert out["parent"] not in pids


def test_without_warm_up_workers_start_cold():
    out = _in_fresh_process(f"""
        res = run_campaign("{PROBE}", 20, 3, workers=2, progress=False)
        print(json.dumps([r.outputs for r in res.records]))
        """)
    assert {r["warmed_in"] for r in out} == {None}


def test_failing_warm_up_warns_and_the_campaign_completes():
    with pytest.warns(RuntimeWarning, match="warm-up .*toy_warm_up failed .*toy warm-up failure"):
        res = run_campaign(PROBE, 10, 3, kwargs={"fail": True}, workers=1, progress=False, warm_up=WARM)
    assert res.n_ok == 10


def test_mass_cm_study_warm_workers_equal_in_process_bit_for_bit():
    """The Table-3 task with its warm-up, on 2 warm workers, equals the same runs computed in one process
    whose BLAS runs 4 threads (as on a 4-core machine): OpenBLAS splits its reductions between threads, so
    without :func:`shipid.numerics.linalg.one_blas_thread` around every computation (the cached datasets
    included) 219 fields differed by ~1e-9 relative (k 10.379489411238223 vs 10.37948941371897)."""
    out = _in_fresh_process("""
        res = run_campaign("shipid.methods.masscm.study:run_one", 24, 5, workers=2, progress=False,
                           kwargs={"data_seed": 0}, warm_up="shipid.methods.masscm.study:warm_up")
        print(json.dumps([r.outputs for r in res.records]))
        """)
    here = _in_fresh_process("""
        import numpy as np
        from shipid.methods.masscm.study import run_one
        print(json.dumps([run_one(i, np.random.SeedSequence([5, i]), data_seed=0) for i in range(24)]))
        """, env={"OPENBLAS_NUM_THREADS": "4", "OMP_NUM_THREADS": "4"})
    assert out == here
