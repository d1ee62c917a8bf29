"""Where a campaign's runs execute: in this process, a local process pool, or Dask.

Each executor is a generator that takes the chunks of run indices and yields, as
chunks finish, lists of row dicts (one per run: ``index``, ``seed``,
``outputs_json``, ``status``, ``error``, ``wall_s``, ``cpu_s``, ``worker``). The work done on a
worker is :func:`run_chunk`, which never raises for a failing run: the exception is
recorded with the run. See :mod:`shipid.campaign.engine` for the behaviour on lost
worker processes.
"""

from __future__ import annotations

import atexit
import functools
import hashlib
import importlib
import json
import multiprocessing
import os
import socket
import time
import warnings
from collections import deque
from pathlib import Path
from typing import Any, Callable, Iterator, Sequence

import numpy as np

from shipid.errors import ShipidError
from shipid.numerics.linalg import one_blas_thread
from shipid.outputs import json_default
from shipid.campaign.seeding import run_entropy

MAX_DASK_ATTEMPTS = 3    # Dask: tries per chunk when the cluster (not the task) fails it
DASK_CONNECT_TIMEOUT_S = 15  # seconds to reach an existing scheduler


# --------------------------------------------------------------------------------------
# JSON
# --------------------------------------------------------------------------------------
def to_json(obj, *, canonical: bool = False) -> str:
    """JSON text of ``obj`` (floats written exactly; NumPy values converted)."""
    if canonical:
        return json.dumps(obj, default=json_default, sort_keys=True, separators=(",", ":"))
    return json.dumps(obj, default=json_default)


# --------------------------------------------------------------------------------------
# Code identity
# --------------------------------------------------------------------------------------
@functools.lru_cache(maxsize=1)
def code_fingerprint() -> str:
    """SHA-256 of shipid's Python source as this process imported it (file names and bytes).

    Computed once per process (what the files held then, as a proxy for what the process
    imported). Stored with every run, so a campaign whose workers ran other code (a
    source tree edited during the run, a cluster with another install) can be seen;
    the engine warns when it happens. A task outside the shipid package is not covered.
    """
    root = Path(__file__).resolve().parents[1]     # the shipid package
    h = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        h.update(path.relative_to(root).as_posix().encode() + b"\0")
        h.update(path.read_bytes() + b"\0")
    return h.hexdigest()


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
#: Thread counts set to 1 in every worker process: the BLAS libraries' and shipid's own compiled row
#: simulation's (``SHIPID_THREADS``, :func:`shipid.models.mmg_kernels.threads`): the workers are the parallelism.
BLAS_ENV = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "SHIPID_THREADS")


def _worker_init() -> None:
    """Process-pool initializer: one BLAS (and row-simulation) thread per worker, and exit with the main process.

    BLAS libraries loaded later read the environment; those already loaded are limited
    per chunk with threadpoolctl. ``concurrent.futures`` workers otherwise outlive a
    main process killed with SIGKILL (they wait on their queue for ever), so a daemon
    thread waits on the parent's sentinel and ends the worker when it goes.
    """
    for var in BLAS_ENV:
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


def error_text(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {' '.join(str(exc).split())}".rstrip(": ").strip()


def run_chunk(task, seed: int, indices: Sequence[int], inputs: Sequence[Any] | None, kwargs: dict,
               limit_threads: bool = True) -> list[dict]:
    """Run the runs ``indices`` of a campaign and return one row dict per run (never raises for a run)."""
    fn = resolve_task(task) if isinstance(task, str) else task
    if limit_threads:
        _limit_threads()
    worker = f"{socket.gethostname()}:{os.getpid()}"
    code = code_fingerprint()
    rows = []
    for k, i in enumerate(indices):
        inp = None if inputs is None else inputs[k]
        entropy = run_entropy(seed, i)
        t0, c0 = time.perf_counter(), time.process_time()
        try:
            call_kwargs = dict(kwargs)
            if inp is not None:
                call_kwargs.update(inp)
            out = fn(int(i), np.random.SeedSequence(entropy), **call_kwargs)
            if not isinstance(out, dict):
                raise TypeError(f"task returned {type(out).__name__}, not a dict of outputs")
            out_json, status, error = to_json(out), "ok", None
        except Exception as exc:  # a failed run is data, not a crash
            out_json, status, error = None, "failed", error_text(exc)
        rows.append({"index": int(i), "seed": entropy, "outputs_json": out_json, "status": status,
                     "error": error, "wall_s": time.perf_counter() - t0, "worker": worker,
                     "cpu_s": time.process_time() - c0, "code": code})
    return rows


def failed_rows(seed: int, indices: Sequence[int], error: str) -> list[dict]:
    return [{"index": int(i), "seed": run_entropy(seed, i), "outputs_json": None, "status": "failed",
             "error": error, "wall_s": None, "worker": None, "cpu_s": None} for i in indices]


# --------------------------------------------------------------------------------------
# Executors: each yields lists of finished rows
# --------------------------------------------------------------------------------------
_SERVER_WARM: list = []     # the warm-up spec this process's forkserver was started with (at most one)
WARM_UP_VAR = "SHIPID_WORKER_WARM_UP"   # how the spec reaches the forkserver (read by shipid.campaign.worker_preload)


def start_forkserver(warm_up: str | None = None, warm_kwargs: dict | None = None,
                     modules: Sequence[str] = ()) -> bool:
    """Start this process's ``forkserver`` with the task's warm-up run in it; True if it ran there.

    The server (one per process, shared by the local pool and the Dask LocalCluster) imports
    :mod:`shipid.campaign.worker_preload` and ``modules`` and runs ``warm_up(**warm_kwargs)``
    once; every worker forked from it starts warm (see that module). When the server is
    already running (an earlier campaign of this process started it) it is left as it is and
    False is returned unless it was started with the same warm-up: workers then warm up on
    their own, as they would without this (slower to start, same results).
    """
    from multiprocessing import forkserver

    spec = None if warm_up is None else to_json({"warm_up": warm_up, "kwargs": warm_kwargs or {}}, canonical=True)
    server = forkserver._forkserver
    if getattr(server, "_forkserver_pid", None) is not None:   # running (private attribute; absent: start)
        return spec is not None and _SERVER_WARM == [spec]
    multiprocessing.get_context("forkserver").set_forkserver_preload(
        ["shipid.campaign.worker_preload", *modules])
    old = os.environ.get(WARM_UP_VAR)
    try:
        if spec is None:
            os.environ.pop(WARM_UP_VAR, None)
        else:
            os.environ[WARM_UP_VAR] = spec       # read by the server as it imports worker_preload
        server.ensure_running()
        atexit.unregister(stop_servers)      # once, however often the server is restarted
        atexit.register(stop_servers)
    finally:
        if old is None:
            os.environ.pop(WARM_UP_VAR, None)
        else:
            os.environ[WARM_UP_VAR] = old
    _SERVER_WARM[:] = [spec]
    return spec is not None


def _reap(pid: int, timeout: float) -> bool:
    """Wait up to ``timeout`` s for this process's child ``pid`` to exit and reap it; True if it did."""
    deadline = time.monotonic() + timeout
    while True:
        try:
            done, _ = os.waitpid(pid, os.WNOHANG)
        except ChildProcessError:            # not ours, or reaped already
            return True
        if done:
            return True
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)


def stop_servers(timeout: float = 5.0) -> None:
    """Stop this process's ``forkserver`` and ``multiprocessing`` resource tracker and reap both.

    Both outlive a pool: they exit only when this process's end of their pipes closes, so after
    a campaign command they ran on (and, under an init that reaps late, lingered as zombies) for
    a moment after the command itself had returned. Registered with :mod:`atexit` by
    :func:`start_forkserver`, so campaigns of one process still share one warm server, and no
    process of shipid's outlives the command. Each is given ``timeout`` s to exit (a process
    still holding the tracker's pipe would keep it alive; it is then left to exit on its own).
    """
    from multiprocessing import forkserver, resource_tracker

    server = forkserver._forkserver
    pid, fd = getattr(server, "_forkserver_pid", None), getattr(server, "_forkserver_alive_fd", None)
    if pid is not None and fd is not None:
        os.close(fd)                         # EOF on its "alive" pipe: the server exits
        server._forkserver_alive_fd = None
        if _reap(pid, timeout):
            server._forkserver_pid = None
            address = getattr(server, "_forkserver_address", None)
            if address and not address.startswith("\0") and os.path.exists(address):
                os.unlink(address)
            server._forkserver_address = None
        _SERVER_WARM.clear()
    tracker = resource_tracker._resource_tracker
    pid, fd = getattr(tracker, "_pid", None), getattr(tracker, "_fd", None)
    if pid is not None and fd is not None:
        os.close(fd)                         # the tracker exits when every writer has closed its pipe
        tracker._fd = None
        if _reap(pid, timeout):
            tracker._pid = None


def warm_up_here(warm_up: str, warm_kwargs: dict | None = None) -> None:
    """Run a campaign's warm-up in this process (Dask workers: ``client.run``; the parent)."""
    resolve_task(warm_up)(**(warm_kwargs or {}))


def iter_inprocess(chunks, args) -> Iterator[list[dict]]:
    for c in chunks:
        yield run_chunk(*args(c), limit_threads=False)


def iter_pool(chunks, workers: int, args, seed: int, warm: tuple | None = None) -> Iterator[list[dict]]:
    """Process pool with recovery from dead worker processes.

    Workers are forked from this process's forkserver, started warm with ``warm``
    (``(warm_up, kwargs)``, see :func:`start_forkserver`) when it is not running yet.

    When a worker dies, every chunk in flight is lost (the pool breaks). Those chunks
    become *suspects* and are re-run one at a time in a fresh pool; a suspect that
    breaks the pool alone is split into single runs, and a single run that does so
    is recorded as failed (``WorkerDied``). A pool found broken when a chunk is submitted (a worker died
    while finished futures were being collected) takes the chunk back into its queue; the dead worker's
    futures then end broken in the wait, or, with none in flight, a fresh pool is started.
    """
    import concurrent.futures as cf
    from concurrent.futures.process import BrokenProcessPool

    start_forkserver(*(warm or (None, None)))
    ctx = multiprocessing.get_context("forkserver")
    normal, suspects = deque(chunks), deque()
    inflight: dict = {}
    pool = None

    def submit(queue: deque, alone: bool) -> bool:
        """Submit the head of ``queue``; False (the chunk put back) if the pool broke since the last wait:
        a worker died while other futures were being collected, and its own futures are not yet marked."""
        c = queue.popleft()
        try:
            inflight[pool.submit(run_chunk, *args(c))] = (c, alone)
            return True
        except BrokenProcessPool:
            queue.appendleft(c)
            return False

    def drop() -> None:
        """Shut the (broken) pool down; the loop starts a fresh one."""
        nonlocal pool
        pool.shutdown(wait=True, cancel_futures=True)
        pool = None

    idle_breaks = 0
    try:
        while normal or suspects or inflight:
            if pool is None:
                pool = cf.ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_worker_init)
            ok = True
            if suspects:
                if not inflight:
                    ok = submit(suspects, True)
            else:
                while ok and normal and len(inflight) < 2 * workers:
                    ok = submit(normal, False)
            if not ok and not inflight:       # broken with nothing in flight: nothing to blame, a fresh pool
                drop()
                idle_breaks += 1
                if idle_breaks > 3:
                    raise RuntimeError("the worker pool broke four times with no run in flight")
                continue
            idle_breaks = 0
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
                    yield failed_rows(seed, c, error_text(exc))
            if broken:
                drop()
                for c, alone in broken:
                    if not alone:
                        suspects.append(c)
                    elif len(c) > 1:
                        suspects.extendleft([[i] for i in reversed(c)])
                    else:
                        yield failed_rows(seed, c, "WorkerDied: the worker process died running this run")
    finally:
        if pool is not None:
            drop()


def iter_dask(client, chunks, args, seed: int) -> Iterator[list[dict]]:
    """Dask executor. Dask itself re-runs work lost with a worker; when it gives up on a
    chunk (``KilledWorker``) the chunk is split into single runs, and a single run that
    is killed again becomes a *suspect*, re-run alone once nothing else is in flight
    (an innocent run queued on the same dying worker then succeeds); a suspect killed
    alone is recorded as failed (``WorkerDied``).
    """
    from distributed import as_completed
    from distributed.scheduler import KilledWorker

    futs = {}
    ac = as_completed()
    suspects: deque = deque()

    def submit(c, attempt=1, alone=False):
        f = client.submit(run_chunk, *args(c), pure=False, retries=0)
        futs[f] = (c, attempt, alone)
        ac.add(f)

    for c in chunks:
        submit(c)
    try:
        while True:
            for f in ac:
                c, attempt, alone = futs.pop(f)
                try:
                    rows = f.result()
                except KilledWorker:
                    if len(c) > 1:
                        for i in c:
                            submit([i])
                    elif not alone:
                        suspects.append(c)
                    else:
                        yield failed_rows(seed, c, "WorkerDied: Dask workers died running this run")
                except Exception as exc:  # noqa: BLE001
                    # run_chunk records every task exception itself, so this is the cluster
                    # (lost data, communication): try again, then record it with the runs.
                    if attempt < MAX_DASK_ATTEMPTS:
                        submit(c, attempt + 1, alone)
                    else:
                        yield failed_rows(seed, c, error_text(exc))
                else:
                    yield rows
                f.release()
            if not suspects:
                break
            submit(suspects.popleft(), alone=True)   # nothing else in flight: it runs alone
    finally:
        for f in list(futs):
            f.cancel()


# --------------------------------------------------------------------------------------
# Context managers for the executors
# --------------------------------------------------------------------------------------
def threads_limited():
    """One BLAS thread for in-process runs, as the workers have (:func:`shipid.numerics.linalg.one_blas_thread`)."""
    return one_blas_thread()


def _import_distributed():
    try:
        import distributed  # noqa: F401
    except ImportError:
        raise ShipidError("Dask executors need dask[distributed]: pip install 'shipid[dask]'") from None
    return distributed


class dask_local_client:
    """A LocalCluster on loopback with ``n`` single-threaded worker processes, and its client."""

    def __init__(self, n: int, warm: tuple | None = None):
        self.n = n
        self.warm = warm

    def __enter__(self):
        distributed = _import_distributed()
        # the nanny forks its worker from this process's forkserver: start it warm (and with
        # distributed imported) when it is not running yet, see start_forkserver
        start_forkserver(*(self.warm or (None, None)), modules=("distributed",))
        with warnings.catch_warnings():
            # no dashboard; the scheduler's small HTTP (health) server binds 127.0.0.1 and, when
            # 8787 is taken by another cluster, moves to a free port with a warning that means nothing here
            warnings.filterwarnings("ignore", message="Port .* is already in use")
            # Dask's default worker environment sets MALLOC_TRIM_THRESHOLD_=65536, which switches off
            # glibc's dynamic mmap threshold: every numpy array over 128 KiB is then a fresh mmap with
            # page faults (measured: the Table-3 study 34 -> 56 ms/run). Our workers run short numeric
            # tasks, not long-lived memory hogs: keep glibc's default (None unsets it, see distributed.nanny).
            #
            # Worker processes come from a forkserver, not a fresh `spawn` interpreter each: the
            # forkserver has distributed and numpy imported once, and a forked worker exits at once
            # on close. Measured (2 workers, fresh process, load 5-6 on 2 cores): start + close
            # 3.3 s -> 2.5 s on average, almost all of it in the close (0.7 s -> 0.07 s). The
            # settings stay in force while the cluster lives, so a worker the nanny restarts after
            # a crash is started the same way.
            import dask
            self._config = dask.config.set({"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
                                            "distributed.worker.multiprocessing-method": "forkserver"})
            try:
                self.cluster = distributed.LocalCluster(n_workers=self.n, threads_per_worker=1, processes=True,
                                                        host="127.0.0.1", dashboard_address=None)
            except BaseException:
                self._config.__exit__(None, None, None)
                raise
        self.client = distributed.Client(self.cluster)
        return self.client

    def __exit__(self, *exc):
        try:
            self.client.close()
            self.cluster.close()
        finally:
            self._config.__exit__(None, None, None)


class dask_remote_client:
    """A client of an existing Dask scheduler."""

    def __init__(self, address: str):
        self.address = address

    def __enter__(self):
        distributed = _import_distributed()
        try:
            self.client = distributed.Client(self.address, timeout=DASK_CONNECT_TIMEOUT_S)
        except Exception as err:  # noqa: BLE001 - OSError, TimeoutError, bad address ...: one line
            raise ShipidError(f"cannot reach the Dask scheduler at {self.address} ({error_text(err)})") from None
        return self.client

    def __exit__(self, *exc):
        self.client.close()
