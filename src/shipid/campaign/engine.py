"""The campaign engine: run a task many times, locally or on Dask, into a resumable store.

A *campaign* is a name, a task, a seed, a number of runs (or a list of per-run
inputs) and fixed keyword arguments. Run ``i`` calls::

    task(i, numpy.random.SeedSequence([seed, i]), **kwargs, **inputs[i]) -> dict

so its randomness depends on (campaign seed, ``i``) only (see
:mod:`shipid.campaign.seeding`), and the results are identical bit for bit whatever
the executor, the number of workers, the order in which runs finish, or a resume
-- provided the task is a function of its arguments only (no state carried between
runs in a process that changes its numbers); BLAS runs one thread per worker, so
reductions do not depend on thread scheduling. The task must be a top-level (picklable, importable) function returning a dict of
JSON-able outputs (floats, ints, strings, lists, nested dicts; NumPy scalars and
arrays are converted). An exception in a run is recorded with the run
(``status="failed"``, ``error="Type: message"``) and never stops the campaign.

Executors
---------
``"local"`` (default)
    A process pool (``concurrent.futures.ProcessPoolExecutor``, ``forkserver``) with
    ``workers`` processes (default: the CPUs this process may use); ``workers=1``
    runs in this process. A worker process that dies (segfault, OOM kill) is
    replaced; the runs it held are re-run, and a run that kills its process again
    when run alone is recorded as failed (``WorkerDied``).
``"dask-local"``
    Starts a ``dask.distributed.LocalCluster`` with ``workers`` single-threaded
    worker processes on loopback (no dashboard) and closes it at the end.
``"scheduler"``
    Uses an existing Dask cluster at ``scheduler_address`` (``tcp://HOST:PORT``); its
    workers must have shipid installed. Dask re-runs work lost with a worker; a
    chunk that kills workers repeatedly is split and its guilty run recorded as failed.

Runs are sent in chunks (at most 100 runs, shrinking towards the end: guided
self-scheduling) so that 10 000 small runs cost about 150 round trips, not 10 000,
and the last chunks balance the workers; every finished chunk is written to the
store in one transaction.

Store and resume
----------------
With ``store=PATH`` every finished run goes into an SQLite file
(:mod:`shipid.campaign.store`). ``resume=True`` continues the campaign of the same
name in that store, skipping the runs already there (ok or failed): no completed
run is lost, none is repeated. It is refused with one line when the stored
definition (task, seed, n_runs, kwargs, inputs, shipid version) differs. Every
run also stores a hash of the shipid source its worker started from, and the
engine warns when it differs from this process's (files edited during the run,
another install on the cluster). Without ``resume`` a store that already holds the
campaign is refused; ``retry_failed=True`` (``--retry-failed``) with ``resume`` runs
the stored failed runs again. One campaign process at a time may write a store (a
lock file ``<store>.lock``); readers (export) are never blocked.

Usage
-----
From Python::

    from shipid.campaign.engine import run_campaign
    res = run_campaign("shipid.campaign.toy:toy_run", 1000, seed=7, kwargs={"n": 100},
                       workers=2, store="toy.sqlite")
    res.outputs          # list of dicts in run order (None where a run failed)
    res.failed           # list of RunRecord with .error

From a ``shipid study`` command, use the shared options (see
:mod:`shipid.cli.campaign_cmds`)::

    from shipid.cli import study
    from shipid.cli.campaign_cmds import campaign_options

    @study.command("my-study")
    @click.option("--runs", type=int, default=100)
    @campaign_options
    def my_study(runs, campaign):          # campaign: CampaignOptions
        res = campaign.run("shipid.methods.x:one_run", runs, kwargs={...}, name="my-study")
"""

from __future__ import annotations

import hashlib
import json
import os
import time
import warnings
from contextlib import ExitStack
from dataclasses import dataclass, field
from typing import Callable, Sequence

import shipid
from shipid.errors import ShipidError
from shipid.progress import progress_bar
from shipid.campaign.executors import (code_fingerprint, dask_local_client, dask_remote_client, iter_dask,
                                      error_text, iter_inprocess, iter_pool, resolve_task, task_reference,
                                      threads_limited, to_json, warm_up_here)
from shipid.campaign.seeding import check_seed
from shipid.campaign.store import CampaignDefinition, CampaignStore, RunRecord, records_frame
EXECUTORS = ("local", "dask-local", "scheduler")
MAX_CHUNK = 100          # runs per chunk at most
CHUNKS_PER_WORKER = 4    # at least this many chunks per worker, for balance and progress


# --------------------------------------------------------------------------------------
# Results
# --------------------------------------------------------------------------------------
@dataclass
class CampaignResult:
    """All runs of a campaign in run order, with how they were obtained.

    Attributes
    ----------
    name, task, seed, n_runs : str, str, int, int
        The campaign definition.
    records : list of RunRecord
        One per run, in run order (``records[i].index == i``).
    executor : str
        ``"in-process"``, ``"local"``, ``"dask-local"``, ``"scheduler"``, or
        ``"none (all runs in the store)"`` when a resume found nothing left to do.
    workers : int
        Number of worker processes used (Dask: workers in the cluster at the start; 0: none).
    wall_s : float
        Wall time of this call.
    reused : int
        Runs taken from the store by ``resume`` instead of computed now.
    store : str or None
        The store file.
    kwargs : dict
        The fixed keyword arguments.
    mixed_code : int
        Runs computed now by a worker whose shipid source differed from this process's
        (a warning was issued; 0 is the normal case).
    """

    name: str
    task: str
    seed: int
    n_runs: int
    records: list[RunRecord]
    executor: str
    workers: int
    wall_s: float
    reused: int = 0
    store: str | None = None
    kwargs: dict = field(default_factory=dict)
    mixed_code: int = 0

    @property
    def outputs(self) -> list[dict | None]:
        """Outputs of every run in run order (``None`` for a failed run)."""
        return [r.outputs for r in self.records]

    @property
    def ok(self) -> list[RunRecord]:
        return [r for r in self.records if r.status == "ok"]

    @property
    def failed(self) -> list[RunRecord]:
        return [r for r in self.records if r.status != "ok"]

    @property
    def n_ok(self) -> int:
        return len(self.ok)

    @property
    def n_failed(self) -> int:
        return len(self.failed)

    def failed_text(self, shown: int = 3) -> str:
        """The first ``shown`` failed runs as ``run i: Type: message`` joined by ``; `` (and how many more):
        the part of a warning line that says what failed."""
        text = "; ".join(f"run {r.index}: {r.error}" for r in self.failed[:shown])
        return text + (f"; {self.n_failed - shown} more" if self.n_failed > shown else "")

    def to_frame(self):
        """A pandas DataFrame, one row per run (see :func:`shipid.campaign.store.records_frame`)."""
        return records_frame(self.records, self.name)

    def summary(self) -> dict:
        """JSON-able summary: counts, executor, timing and where the runs are stored."""
        return {"campaign": self.name, "task": self.task, "seed": self.seed, "runs": self.n_runs,
                "ok": self.n_ok, "failed": self.n_failed, "reused_from_store": self.reused,
                "executor": self.executor, "workers": self.workers, "wall_s": self.wall_s,
                "store": self.store, "mixed_code": self.mixed_code}


# --------------------------------------------------------------------------------------
# The engine
# --------------------------------------------------------------------------------------
def available_cpus() -> int:
    """CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def chunk_indices(indices: Sequence[int], workers: int, chunk_size: int | None = None) -> list[list[int]]:
    """Split run indices into consecutive chunks.

    With ``chunk_size`` given, chunks have that size. Otherwise chunks are sized by
    guided self-scheduling: each is ``remaining / (CHUNKS_PER_WORKER * workers)`` runs,
    at most ``MAX_CHUNK`` and at least 1, so a 10 000-run campaign costs about 150
    round trips, not 10 000, while the chunks shrink towards the end and no worker is
    left alone with a long last chunk. Results do not depend on the chunking.
    """
    idx = list(indices)
    n = len(idx)
    if chunk_size is not None:
        return [idx[k:k + chunk_size] for k in range(0, n, chunk_size)]
    per = max(1, workers) * CHUNKS_PER_WORKER
    chunks, k = [], 0
    while k < n:
        size = max(1, min(MAX_CHUNK, -(-(n - k) // per)))
        chunks.append(idx[k:k + size])
        k += size
    return chunks


def _short(value, width: int = 60) -> str:
    text = str(value)
    return text if len(text) <= width else text[:width - 3] + "..."


def run_campaign(task: str | Callable, n_runs: int | None = None, seed: int = 0, *,
                 inputs: Sequence[dict] | None = None, kwargs: dict | None = None, name: str | None = None,
                 executor: str = "local", workers: int | None = None, scheduler_address: str | None = None,
                 store: str | os.PathLike | None = None, resume: bool = False, retry_failed: bool = False,
                 progress: bool = True, chunk_size: int | None = None,
                 warm_up: str | None = None) -> CampaignResult:
    """Run ``task`` for runs ``0 .. n_runs-1`` and return every run's outputs in run order.

    Parameters
    ----------
    task : str or callable
        ``"module:function"`` or a top-level function ``task(i, seedseq, **kwargs) -> dict``.
    n_runs : int, optional
        Number of runs; may be omitted when ``inputs`` is given.
    seed : int
        Campaign seed; run ``i`` receives ``numpy.random.SeedSequence([seed, i])``.
    inputs : sequence of dict, optional
        Per-run keyword arguments (JSON-able), merged over ``kwargs`` for run ``i``.
    kwargs : dict, optional
        Keyword arguments shared by all runs (JSON-able; part of the definition).
    name : str, optional
        Campaign name (key in the store); default: the task's function name.
    executor : {"local", "dask-local", "scheduler"}
        See the module docstring.
    workers : int, optional
        Local: process count (default: available CPUs; 1 runs in this process).
        Dask-local: number of workers (default: available CPUs). Ignored for "scheduler".
    scheduler_address : str, optional
        ``tcp://HOST:PORT`` of an existing Dask scheduler (executor "scheduler").
    store : path-like, optional
        SQLite store file; every finished chunk is committed to it.
    resume : bool
        Continue the campaign ``name`` found in ``store``.
    retry_failed : bool
        With ``resume``: run the stored failed runs again (e.g. after ``WorkerDied``);
        their old rows are replaced. Runs that succeeded are never repeated.
    progress : bool
        Show a progress bar (on an interactive stderr only).
    chunk_size : int, optional
        Runs per chunk (default chosen from the number of runs and workers).
    warm_up : str, optional
        ``"module:function"`` called as ``warm_up(**kwargs)`` (the campaign's shared kwargs;
        it may ignore those it does not use) before the first run: once in this process
        (numba compiles here and writes its disk cache), once in the forkserver the local
        pool's and the LocalCluster's workers are forked from (every worker then starts
        warm, :mod:`shipid.campaign.worker_preload`), and on every worker of an existing
        scheduler. It must not change any run's numbers, only do work earlier (imports,
        compiled kernels, per-process caches). Not part of the campaign's definition.

    Returns
    -------
    CampaignResult

    Raises
    ------
    ShipidError
        Bad definition, a store that refuses the campaign, an unreachable scheduler.
    """
    t_start = time.perf_counter()
    seed = check_seed(seed)
    ref = task_reference(task)
    fn = resolve_task(task) if isinstance(task, str) else task
    if inputs is not None:
        inputs = list(inputs)
        if n_runs is None:
            n_runs = len(inputs)
        elif n_runs != len(inputs):
            raise ShipidError(f"n_runs={n_runs} but {len(inputs)} run inputs were given")
        if not all(isinstance(x, dict) for x in inputs):
            raise ShipidError("each run input must be a dict of keyword arguments")
    if n_runs is None or isinstance(n_runs, bool) or int(n_runs) != n_runs or n_runs < 0:
        raise ShipidError(f"number of runs must be a non-negative integer, got {n_runs!r}")
    n_runs = int(n_runs)
    kwargs = dict(kwargs or {})
    if executor not in EXECUTORS:
        raise ShipidError(f"unknown executor '{executor}' (one of {', '.join(EXECUTORS)})")
    if workers is not None and (isinstance(workers, bool) or int(workers) != workers or workers < 1):
        raise ShipidError(f"workers must be a positive integer, got {workers!r}")
    if executor == "scheduler" and not scheduler_address:
        raise ShipidError("executor 'scheduler' needs a scheduler address (tcp://HOST:PORT)")
    if resume and store is None:
        raise ShipidError("--resume needs --store FILE")
    if retry_failed and not resume:
        raise ShipidError("--retry-failed needs --resume (and --store)")
    name = name or ref.rpartition(":")[2]
    try:
        kwargs_json = to_json(kwargs, canonical=True)
        inputs_json = None if inputs is None else [to_json(x, canonical=True) for x in inputs]
    except TypeError as err:
        raise ShipidError(f"campaign '{name}': kwargs and inputs must be JSON-serialisable ({err})") from None
    inputs_sha = None if inputs_json is None else hashlib.sha256(
        ("[" + ",".join(inputs_json) + "]").encode()).hexdigest()
    code = code_fingerprint()
    definition = CampaignDefinition(name, ref, seed, n_runs, kwargs_json, inputs_sha, shipid.__version__, code)

    with ExitStack() as stack:
        st = None
        done: set[int] = set()
        memory: dict[int, RunRecord] = {}
        mixed = 0
        if store is not None:
            st = stack.enter_context(CampaignStore(store, writer=True))
            old = st.definition(name)
            if old is None:
                st.create(definition)
            elif not resume:
                raise ShipidError(f"{store}: already holds campaign '{name}' ({st.count(name)} of {old.n_runs} "
                                  "runs); add --resume to continue it, or use another --store")
            else:
                diff = old.differences(definition)
                if diff:
                    was = ", ".join(f"{f}={_short(getattr(old, f))}" for f in diff)
                    now = ", ".join(f"{f}={_short(getattr(definition, f))}" for f in diff)
                    raise ShipidError(f"{store}: campaign '{name}' was defined with {was}, not {now}: "
                                      "refusing to resume (use another --store)")
                if retry_failed:
                    st.delete_failed(name)
            done = st.done_indices(name)
        todo = [i for i in range(n_runs) if i not in done]

        # executor set-up (nothing to start when a resumed campaign is already complete)
        client = None
        warm = None if warm_up is None else (task_reference(warm_up), kwargs)
        if todo and warm is not None:
            try:
                with threads_limited():
                    warm_up_here(*warm)
            except Exception as err:  # noqa: BLE001 - the runs will record their own failures
                warnings.warn(f"campaign '{name}': warm-up {warm[0]} failed ({error_text(err)}); "
                              "the runs go ahead without it", RuntimeWarning, stacklevel=2)
                warm = None
        if not todo:
            n_workers = 0
        elif executor == "local":
            n_workers = workers or available_cpus()
        elif executor == "dask-local":
            n_workers = workers or available_cpus()
            client = stack.enter_context(dask_local_client(n_workers, warm))
        else:
            client = stack.enter_context(dask_remote_client(scheduler_address))
            n_workers = max(1, len(client.scheduler_info().get("workers", {})))
            if warm is not None:
                try:
                    client.run(warm_up_here, *warm)
                except Exception as err:  # noqa: BLE001 - a slower start, not a failed campaign
                    warnings.warn(f"campaign '{name}': warm-up on the scheduler's workers failed "
                                  f"({error_text(err)}); each warms up on its first run", RuntimeWarning,
                                  stacklevel=2)
        chunks = chunk_indices(todo, n_workers, chunk_size)

        task_arg = ref if isinstance(task, str) else fn
        inputs_by_index = inputs

        def args(c):
            inp = None if inputs_by_index is None else [inputs_by_index[i] for i in c]
            return (task_arg, seed, c, inp, kwargs)

        if not todo:
            label, stream = "none (all runs in the store)", iter(())
        elif client is not None:
            label = executor
            stream = iter_dask(client, chunks, args, seed)
        elif n_workers == 1 or len(chunks) <= 1:
            label, n_workers = "in-process", 1
            stream = iter_inprocess(chunks, args)
            stack.enter_context(threads_limited())
        else:
            label = "local"
            n_workers = min(n_workers, len(chunks))
            stream = iter_pool(chunks, n_workers, args, seed, warm)

        if progress:
            advance = stack.enter_context(progress_bar(n_runs, name, completed=len(done)))
        else:
            advance = lambda k=1: None  # noqa: E731

        try:
            for rows in stream:
                for r in rows:
                    if r.get("code") not in (None, code):
                        mixed += 1
                        if mixed == 1:
                            warnings.warn(
                                f"campaign '{name}': worker {r['worker']} started from other shipid source "
                                f"({r['code'][:12]} vs {code[:12]}: files edited during the run, or another "
                                "install on the cluster); results may mix code (see the 'code' column)",
                                RuntimeWarning, stacklevel=2)
                    r["inputs_json"] = "{}" if inputs_json is None else inputs_json[r["index"]]
                if st is not None:
                    st.write(name, rows)
                else:
                    for r in rows:
                        memory[r["index"]] = RunRecord(
                            r["index"], r["seed"], json.loads(r["inputs_json"]),
                            None if r["outputs_json"] is None else json.loads(r["outputs_json"]),
                            r["status"], r["error"], r["wall_s"], r["worker"], r["cpu_s"], r.get("code"))
                advance(len(rows))
        finally:
            if hasattr(stream, "close"):
                stream.close()
        records = st.records(name) if st is not None else [memory[i] for i in sorted(memory)]
    if len(records) != n_runs or any(r.index != k for k, r in enumerate(records)):
        raise ShipidError(f"campaign '{name}': {len(records)} of {n_runs} runs came back (engine bug)")
    return CampaignResult(name=name, task=ref, seed=seed, n_runs=n_runs, records=records, executor=label,
                          workers=n_workers, wall_s=time.perf_counter() - t_start, reused=len(done),
                          store=None if store is None else str(store), kwargs=kwargs, mixed_code=mixed)


# --------------------------------------------------------------------------------------
# Options shared by the `shipid study` commands (the click decorator is in shipid.cli.campaign_cmds)
# --------------------------------------------------------------------------------------
@dataclass(frozen=True)
class CampaignOptions:
    """How and where to run a campaign, as given on the command line.

    Parameters
    ----------
    seed : int
        Campaign seed.
    workers : int, optional
        Local process count (``--workers``).
    dask_local : int, optional
        Start a LocalCluster with this many workers (``--dask-local N``).
    scheduler : str, optional
        Address of an existing Dask scheduler (``--scheduler tcp://HOST:PORT``).
    store : str, optional
        SQLite store (``--store FILE``).
    resume : bool
        Continue the campaign in ``store`` (``--resume``).
    retry_failed : bool
        With ``resume``, run the stored failed runs again (``--retry-failed``).
    progress : bool
        Show the progress bar.
    """

    seed: int = 0
    workers: int | None = None
    dask_local: int | None = None
    scheduler: str | None = None
    store: str | None = None
    resume: bool = False
    retry_failed: bool = False
    progress: bool = True

    def __post_init__(self):
        check_seed(self.seed)
        if self.dask_local is not None and self.scheduler is not None:
            raise ShipidError("--dask-local and --scheduler exclude each other")
        if self.workers is not None and (self.dask_local is not None or self.scheduler is not None):
            raise ShipidError("--workers is for the local pool; with --dask-local N give the worker count as N, "
                              "with --scheduler the cluster decides")
        for label, v in (("--workers", self.workers), ("--dask-local", self.dask_local)):
            if v is not None and v < 1:
                raise ShipidError(f"{label} must be at least 1, got {v}")
        if self.resume and self.store is None:
            raise ShipidError("--resume needs --store FILE")
        if self.retry_failed and not self.resume:
            raise ShipidError("--retry-failed needs --resume (and --store)")

    def engine_kwargs(self) -> dict:
        """Keyword arguments for :func:`run_campaign` (everything but task, runs and seed)."""
        if self.scheduler is not None:
            ex = {"executor": "scheduler", "scheduler_address": self.scheduler}
        elif self.dask_local is not None:
            ex = {"executor": "dask-local", "workers": self.dask_local}
        else:
            ex = {"executor": "local", "workers": self.workers}
        return {**ex, "store": self.store, "resume": self.resume, "retry_failed": self.retry_failed,
                "progress": self.progress}

    def run(self, task: str | Callable, n_runs: int | None = None, *, inputs=None, kwargs=None,
            name: str | None = None, chunk_size: int | None = None,
            warm_up: str | None = None) -> CampaignResult:
        """``run_campaign(task, n_runs, self.seed, ...)`` with these options."""
        return run_campaign(task, n_runs, self.seed, inputs=inputs, kwargs=kwargs, name=name,
                            chunk_size=chunk_size, warm_up=warm_up, **self.engine_kwargs())
