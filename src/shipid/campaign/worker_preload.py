"""Warm a campaign's worker processes once, in the forkserver they are forked from.

The local pool and the Dask LocalCluster start their workers from one ``forkserver``
process (:mod:`multiprocessing.forkserver`). The campaign engine starts that server
with this module in its preload list and, in the environment variable
:data:`shipid.campaign.executors.WARM_UP_VAR`, the task's warm-up (``{"warm_up": "module:function", "kwargs":
{...}}``). Importing this module in the server then runs the warm-up there, once:
imports, numba kernels loaded from the disk cache, datasets a task caches per process.
Every worker forked afterwards starts with all of it in memory, instead of each
worker paying it again (about 1.6 s per worker for the Table-3 study of
:mod:`shipid.methods.masscm.study`, i.e. 4 % of a 2-worker 10 000-run campaign).

A warm-up must not change any run's numbers (tasks are functions of their
arguments only, see :mod:`shipid.campaign.engine`); it only moves work earlier.
A warm-up that fails is reported on stderr and skipped: the workers then warm up on
their own, as without this module. With the variable unset, importing this module
imports numpy and the engine's worker code only.
"""

from __future__ import annotations

import json
import os
import sys

import numpy  # noqa: F401  - imported once here for every worker

from shipid.campaign.executors import BLAS_ENV, WARM_UP_VAR, code_fingerprint, resolve_task

#: What the warm-up did in this process: ``None`` (none asked), ``"ok"`` or the error text.
STATUS: str | None = None


def _warm_up_from_environment() -> None:
    global STATUS
    spec = os.environ.get(WARM_UP_VAR)
    if not spec:
        return
    for var in BLAS_ENV:                  # workers run one BLAS thread each (as _worker_init sets)
        os.environ[var] = "1"
    try:
        from threadpoolctl import threadpool_limits

        code_fingerprint()                 # cached: workers report the source this server loaded
        d = json.loads(spec)
        fn = resolve_task(d["warm_up"])
        with threadpool_limits(limits=1):
            fn(**d.get("kwargs", {}))
        STATUS = "ok"
    except Exception as exc:  # noqa: BLE001 - the server must live on; workers warm up on their own
        STATUS = f"{type(exc).__name__}: {exc}"
        print(f"shipid: worker warm-up {spec} failed in the forkserver ({STATUS}); "
              "each worker warms up on its own", file=sys.stderr, flush=True)


_warm_up_from_environment()
