"""The campaign engine: run a task many times, locally or on Dask, into a resumable store.

A *campaign* is a name, a task, a seed, a number of runs (or a list of per-run
inputs) and fixed keyword arguments. Run ``i`` calls::

    task(i, numpy.random.SeedSequence([seed, i]), **kwargs, **inputs[i]) -> dict

so its randomness depends on (campaign seed, ``i``) only (see
:mod:`shipid.studies.seeding`), and the results are identical bit for bit whatever
the executor, the number of workers, the order in which runs finish, or a resume.
The task must be a top-level (picklable, importable) function returning a dict of
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

Runs are sent in chunks (at most 100 runs, at least ~4 chunks per worker) so that
10 000 small runs cost about a hundred round trips, not 10 000; every finished
chunk is written to the store in one transaction.

Store and resume
----------------
With ``store=PATH`` every finished run goes into an SQLite file
(:mod:`shipid.studies.store`). ``resume=True`` continues the campaign of the same
name in that store, skipping the runs already there (ok or failed): no completed
run is lost, none is repeated. It is refused with one line when the stored
definition (task, seed, n_runs, kwargs, inputs, shipid version) differs. Without
``resume`` a store that already holds the campaign is refused.

Usage
-----
From Python::

    from shipid.studies.engine import run_campaign
    res = run_campaign("shipid.studies.toy:toy_run", 1000, seed=7, kwargs={"n": 100},
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

import dataclasses
import hashlib
import importlib
import json
import multiprocessing
import os
import socket
import time
import warnings
from collections import deque
from contextlib import ExitStack, nullcontext
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator, Sequence

import numpy as np

import shipid
from shipid.errors import ShipidError
from shipid.studies.seeding import check_seed, run_entropy
from shipid.studies.store import CampaignDefinition, CampaignStore, RunRecord, records_frame

EXECUTORS = ("local", "dask-local", "scheduler")
MAX_CHUNK = 100          # runs per chunk at most
CHUNKS_PER_WORKER = 4    # at least this many chunks per worker, for balance and progress
MAX_DASK_ATTEMPTS = 3    # Dask: tries per chunk when the cluster (not the task) fails it
DASK_CONNECT_TIMEOUT_S = 15  # seconds to reach an existing scheduler


# --------------------------------------------------------------------------------------
# JSON helpers
# --------------------------------------------------------------------------------------
def _jsonable(obj):
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return dataclasses.asdict(obj)
    if isinstance(obj, Path):
        return str(obj)
    if isinstance(obj, (set, frozenset)):
        return sorted(obj)
    raise TypeError(f"{type(obj).__name__} is not JSON-serialisable")


def to_json(obj, *, canonical: bool = False) -> str:
    """JSON text of ``obj`` (floats written exactly; NumPy values converted)."""
    if canonical:
        return json.dumps(obj, default=_jsonable, sort_keys=True, separators=(",", ":"))
    return json.dumps(obj, default=_jsonable)


# --------------------------------------------------------------------------------------
# Tasks
# --------------------------------------------------------------------------------------
def task_reference(task: str | Callable) -> str:
    """The ``"module:function"`` reference of a task (a string is checked by importing it)."""
    if isinstance(task, str):
        resolve_task(task)
        return task
    if not callable(task):
        raise ShipidError(f"task must be a 'module:function' string or a function, got {task!r}")
    qual = getattr(task, "__qualname__", "")
    mod = getattr(task, "__module__", None)
    if not mod or not qual or "<" in qual:
        raise ShipidError(f"task {task!r} must be a top-level function (picklable by reference)")
    return f"{mod}:{qual}"


def resolve_task(ref: str) -> Callable:
    """Import and return the function named by ``"module:function"``."""
    mod_name, sep, attr = ref.partition(":")
    if not sep or not mod_name or not attr:
        raise ShipidError(f"task '{ref}' is not of the form 'module:function'")
    try:
        obj = importlib.import_module(mod_name)
    except ImportError as err:
        raise ShipidError(f"task '{ref}': cannot import {mod_name} ({err})") from None
    for part in attr.split("."):
        obj = getattr(obj, part, None)
        if obj is None:
            raise ShipidError(f"task '{ref}': {mod_name} has no '{attr}'")
    if not callable(obj):
        raise ShipidError(f"task '{ref}' is not callable")
    return obj


# --------------------------------------------------------------------------------------
# What runs on a worker
# --------------------------------------------------------------------------------------
_BLAS_ENV = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def _worker_init() -> None:
    """Process-pool initializer: one BLAS thread per worker, and exit with the main process.

    BLAS libraries loaded later read the environment; those already loaded are limited
    per chunk with threadpoolctl. ``concurrent.futures`` workers otherwise outlive a
    main process killed with SIGKILL (they wait on their queue for ever), so a daemon
    thread waits on the parent's sentinel and ends the worker when it goes.
    """
    for var in _BLAS_ENV:
        os.environ[var] = "1"
    parent = multiprocessing.parent_process()
    if parent is not None:
        import threading
        from multiprocessing.connection import wait

        def _watch(sentinel=parent.sentinel):
            wait([sentinel])
            os._exit(3)

        threading.Thread(target=_watch, name="shipid-parent-watch", daemon=True).start()


def _limit_threads() -> None:
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # optional at run time; the env vars still act on libraries loaded later
        return
    threadpool_limits(limits=1)


def _error_text(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {' '.join(str(exc).split())}".rstrip(": ").strip()


def _run_chunk(task, seed: int, indices: Sequence[int], inputs: Sequence[Any] | None, kwargs: dict,
               limit_threads: bool = True) -> list[dict]:
    """Run the runs ``indices`` of a campaign and return one row dict per run (never raises for a run)."""
    fn = resolve_task(task) if isinstance(task, str) else task
    if limit_threads:
        _limit_threads()
    worker = f"{socket.gethostname()}:{os.getpid()}"
    rows = []
    for k, i in enumerate(indices):
        inp = None if inputs is None else inputs[k]
        entropy = run_entropy(seed, i)
        t0 = time.perf_counter()
        try:
            call_kwargs = dict(kwargs)
            if inp is not None:
                call_kwargs.update(inp)
            out = fn(int(i), np.random.SeedSequence(entropy), **call_kwargs)
            if not isinstance(out, dict):
                raise TypeError(f"task returned {type(out).__name__}, not a dict of outputs")
            out_json, status, error = to_json(out), "ok", None
        except Exception as exc:  # a failed run is data, not a crash
            out_json, status, error = None, "failed", _error_text(exc)
        rows.append({"index": int(i), "seed": entropy, "outputs_json": out_json, "status": status,
                     "error": error, "wall_s": time.perf_counter() - t0, "worker": worker})
    return rows


def _failed_rows(seed: int, indices: Sequence[int], error: str) -> list[dict]:
    return [{"index": int(i), "seed": run_entropy(seed, i), "outputs_json": None, "status": "failed",
             "error": error, "wall_s": None, "worker": None} for i in indices]


# --------------------------------------------------------------------------------------
# Executors: each yields lists of finished rows
# --------------------------------------------------------------------------------------
def _iter_inprocess(chunks, args) -> Iterator[list[dict]]:
    for c in chunks:
        yield _run_chunk(*args(c), limit_threads=False)


def _iter_pool(chunks, workers: int, args, seed: int) -> Iterator[list[dict]]:
    """Process pool with recovery from dead worker processes.

    When a worker dies, every chunk in flight is lost (the pool breaks). Those chunks
    become *suspects* and are re-run one at a time in a fresh pool; a suspect that
    breaks the pool alone is split into single runs, and a single run that does so
    is recorded as failed (``WorkerDied``).
    """
    import concurrent.futures as cf
    from concurrent.futures.process import BrokenProcessPool

    ctx = multiprocessing.get_context("forkserver")
    normal, suspects = deque(chunks), deque()
    inflight: dict = {}
    pool = None
    try:
        while normal or suspects or inflight:
            if pool is None:
                pool = cf.ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_worker_init)
            if suspects:
                if not inflight:
                    c = suspects.popleft()
                    inflight[pool.submit(_run_chunk, *args(c))] = (c, True)
            else:
                while normal and len(inflight) < 2 * workers:
                    c = normal.popleft()
                    inflight[pool.submit(_run_chunk, *args(c))] = (c, False)
            done, _ = cf.wait(list(inflight), return_when=cf.FIRST_COMPLETED)
            if any(isinstance(f.exception(), BrokenProcessPool) for f in done):
                cf.wait(list(inflight))  # the rest of the pool's futures end now too
                done = list(inflight)
            broken = []
            for f in done:
                c, alone = inflight.pop(f)
                exc = f.exception()
                if exc is None:
                    yield f.result()
                elif isinstance(exc, BrokenProcessPool):
                    broken.append((c, alone))
                else:  # e.g. outputs that cannot be pickled back
                    yield _failed_rows(seed, c, _error_text(exc))
            if broken:
                pool.shutdown(wait=True, cancel_futures=True)
                pool = None
                for c, alone in broken:
                    if not alone:
                        suspects.append(c)
                    elif len(c) > 1:
                        suspects.extendleft([[i] for i in reversed(c)])
                    else:
                        yield _failed_rows(seed, c, "WorkerDied: the worker process died running this run")
    finally:
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)


def _iter_dask(client, chunks, args, seed: int) -> Iterator[list[dict]]:
    from distributed import as_completed
    from distributed.scheduler import KilledWorker

    futs = {}
    ac = as_completed()

    def submit(c, attempt=1):
        f = client.submit(_run_chunk, *args(c), pure=False, retries=0)
        futs[f] = (c, attempt)
        ac.add(f)

    for c in chunks:
        submit(c)
    try:
        for f in ac:
            c, attempt = futs.pop(f)
            try:
                rows = f.result()
            except KilledWorker:
                if len(c) > 1:
                    for i in c:
                        submit([i])
                else:
                    yield _failed_rows(seed, c, "WorkerDied: Dask workers died running this run")
            except Exception as exc:  # noqa: BLE001
                # _run_chunk records every task exception itself, so this is the cluster
                # (lost data, communication): try again, then record it with the runs.
                if attempt < MAX_DASK_ATTEMPTS:
                    submit(c, attempt + 1)
                else:
                    yield _failed_rows(seed, c, _error_text(exc))
            else:
                yield rows
            f.release()
    finally:
        for f in list(futs):
            f.cancel()


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
        ``"in-process"``, ``"local"``, ``"dask-local"`` or ``"scheduler"``.
    workers : int
        Number of worker processes used (Dask: workers in the cluster at the start).
    wall_s : float
        Wall time of this call.
    reused : int
        Runs taken from the store by ``resume`` instead of computed now.
    store : str or None
        The store file.
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

    def to_frame(self):
        """A pandas DataFrame, one row per run (see :func:`shipid.studies.store.records_frame`)."""
        return records_frame(self.records, self.name)

    def summary(self) -> dict:
        """JSON-able summary: counts, executor, timing and where the runs are stored."""
        return {"campaign": self.name, "task": self.task, "seed": self.seed, "runs": self.n_runs,
                "ok": self.n_ok, "failed": self.n_failed, "reused_from_store": self.reused,
                "executor": self.executor, "workers": self.workers, "wall_s": self.wall_s,
                "store": self.store}


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
    """Split run indices into consecutive chunks (≤ ``MAX_CHUNK``, ≥ ``CHUNKS_PER_WORKER`` per worker)."""
    n = len(indices)
    if n == 0:
        return []
    if chunk_size is None:
        chunk_size = max(1, min(MAX_CHUNK, -(-n // (max(1, workers) * CHUNKS_PER_WORKER))))
    return [list(indices[k:k + chunk_size]) for k in range(0, n, chunk_size)]


def _short(value, width: int = 60) -> str:
    text = str(value)
    return text if len(text) <= width else text[:width - 3] + "..."


def run_campaign(task: str | Callable, n_runs: int | None = None, seed: int = 0, *,
                 inputs: Sequence[dict] | None = None, kwargs: dict | None = None, name: str | None = None,
                 executor: str = "local", workers: int | None = None, scheduler_address: str | None = None,
                 store: str | os.PathLike | None = None, resume: bool = False, progress: bool = True,
                 chunk_size: int | None = None) -> CampaignResult:
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
    progress : bool
        Show a progress bar (on an interactive stderr only).
    chunk_size : int, optional
        Runs per chunk (default chosen from the number of runs and workers).

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
    name = name or ref.rpartition(":")[2]
    try:
        kwargs_json = to_json(kwargs, canonical=True)
        inputs_json = None if inputs is None else [to_json(x, canonical=True) for x in inputs]
    except TypeError as err:
        raise ShipidError(f"campaign '{name}': kwargs and inputs must be JSON-serialisable ({err})") from None
    inputs_sha = None if inputs_json is None else hashlib.sha256(
        ("[" + ",".join(inputs_json) + "]").encode()).hexdigest()
    definition = CampaignDefinition(name, ref, seed, n_runs, kwargs_json, inputs_sha, shipid.__version__)

    with ExitStack() as stack:
        st = None
        done: set[int] = set()
        memory: dict[int, RunRecord] = {}
        if store is not None:
            st = stack.enter_context(CampaignStore(store))
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
            done = st.done_indices(name)
        todo = [i for i in range(n_runs) if i not in done]

        # executor set-up
        client = None
        if executor == "local":
            n_workers = workers or available_cpus()
        elif executor == "dask-local":
            n_workers = workers or available_cpus()
            client = stack.enter_context(_dask_local_client(n_workers))
        else:
            client = stack.enter_context(_dask_remote_client(scheduler_address))
            n_workers = max(1, len(client.scheduler_info().get("workers", {})))
        chunks = chunk_indices(todo, n_workers, chunk_size)

        task_arg = ref if isinstance(task, str) else fn
        inputs_by_index = inputs

        def args(c):
            inp = None if inputs_by_index is None else [inputs_by_index[i] for i in c]
            return (task_arg, seed, c, inp, kwargs)

        if client is not None:
            label = executor
            stream = _iter_dask(client, chunks, args, seed)
        elif n_workers == 1 or len(chunks) <= 1:
            label, n_workers = "in-process", 1
            stream = _iter_inprocess(chunks, args)
            stack.enter_context(_threads_limited())
        else:
            label = "local"
            n_workers = min(n_workers, len(chunks))
            stream = _iter_pool(chunks, n_workers, args, seed)

        if progress:
            from shipid.progress import progress_bar
            advance = stack.enter_context(progress_bar(n_runs, name, completed=len(done)))
        else:
            advance = lambda k=1: None  # noqa: E731

        try:
            for rows in stream:
                for r in rows:
                    r["inputs_json"] = "{}" if inputs_json is None else inputs_json[r["index"]]
                if st is not None:
                    st.write(name, rows)
                else:
                    for r in rows:
                        memory[r["index"]] = RunRecord(
                            r["index"], r["seed"], json.loads(r["inputs_json"]),
                            None if r["outputs_json"] is None else json.loads(r["outputs_json"]),
                            r["status"], r["error"], r["wall_s"], r["worker"])
                advance(len(rows))
        finally:
            stream.close()
        records = st.records(name) if st is not None else [memory[i] for i in sorted(memory)]
    if len(records) != n_runs or any(r.index != k for k, r in enumerate(records)):
        raise ShipidError(f"campaign '{name}': {len(records)} of {n_runs} runs came back (engine bug)")
    return CampaignResult(name=name, task=ref, seed=seed, n_runs=n_runs, records=records, executor=label,
                          workers=n_workers, wall_s=time.perf_counter() - t_start, reused=len(done),
                          store=None if store is None else str(store), kwargs=kwargs)


# --------------------------------------------------------------------------------------
# Context managers for the executors
# --------------------------------------------------------------------------------------
def _threads_limited():
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # pragma: no cover
        return nullcontext()
    return threadpool_limits(limits=1)


def _import_distributed():
    try:
        import distributed  # noqa: F401
    except ImportError:
        raise ShipidError("Dask executors need dask[distributed]: pip install 'shipid[dask]'") from None
    return distributed


class _dask_local_client:
    """A LocalCluster on loopback with ``n`` single-threaded worker processes, and its client."""

    def __init__(self, n: int):
        self.n = n

    def __enter__(self):
        distributed = _import_distributed()
        with warnings.catch_warnings():
            # no dashboard; the scheduler's small HTTP (health) server binds 127.0.0.1 and, when
            # 8787 is taken by another cluster, moves to a free port with a warning that means nothing here
            warnings.filterwarnings("ignore", message="Port .* is already in use")
            self.cluster = distributed.LocalCluster(n_workers=self.n, threads_per_worker=1, processes=True,
                                                    host="127.0.0.1", dashboard_address=None)
        self.client = distributed.Client(self.cluster)
        return self.client

    def __exit__(self, *exc):
        self.client.close()
        self.cluster.close()


class _dask_remote_client:
    """A client of an existing Dask scheduler."""

    def __init__(self, address: str):
        self.address = address

    def __enter__(self):
        distributed = _import_distributed()
        try:
            self.client = distributed.Client(self.address, timeout=DASK_CONNECT_TIMEOUT_S)
        except Exception as err:  # noqa: BLE001 - OSError, TimeoutError, bad address ...: one line
            raise ShipidError(f"cannot reach the Dask scheduler at {self.address} ({_error_text(err)})") from None
        return self.client

    def __exit__(self, *exc):
        self.client.close()


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
    progress : bool
        Show the progress bar.
    """

    seed: int = 0
    workers: int | None = None
    dask_local: int | None = None
    scheduler: str | None = None
    store: str | None = None
    resume: bool = False
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

    def engine_kwargs(self) -> dict:
        """Keyword arguments for :func:`run_campaign` (everything but task, runs and seed)."""
        if self.scheduler is not None:
            ex = {"executor": "scheduler", "scheduler_address": self.scheduler}
        elif self.dask_local is not None:
            ex = {"executor": "dask-local", "workers": self.dask_local}
        else:
            ex = {"executor": "local", "workers": self.workers}
        return {**ex, "store": self.store, "resume": self.resume, "progress": self.progress}

    def run(self, task: str | Callable, n_runs: int | None = None, *, inputs=None, kwargs=None,
            name: str | None = None, chunk_size: int | None = None) -> CampaignResult:
        """``run_campaign(task, n_runs, self.seed, ...)`` with these options."""
        return run_campaign(task, n_runs, self.seed, inputs=inputs, kwargs=kwargs, name=name,
                            chunk_size=chunk_size, **self.engine_kwargs())
