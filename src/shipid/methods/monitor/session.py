"""A monitor run that survives sensor faults and restarts: :class:`MonitorSession`, its state file.

The session puts :class:`~shipid.methods.monitor.faults.Conditioner` in front of
:class:`~shipid.methods.monitor.estimator.MassCMMonitor` (Linder et al. 2015, Algorithm 1 on a sliding
window): samples go in as they arrive, updates and warning lines come out. After a break in the stream (a
long gap, a channel that stayed bad) the monitor's filters restart from rest at the first good sample
(:func:`restart_after_gap`): the blocks before the break keep their moments (each block's IV moments are a
valid criterion on their own), the partial block before the break is dropped, and a block that starts after
a break is filtered from rest again whenever the window is rebuilt. While a channel stays bad, the session
gives an update with no estimate and the reason, every update period.

State. :func:`save_state` writes the whole session (the processed nominal / calibration moments, the
window's blocks, the filters' states, the detector, the conditioner, the count of output bytes written)
to a temporary file and moves it over the state file with :func:`os.replace` (atomic on POSIX), after
``fsync``; :func:`load_state` reads it back. The start-up run is not in it and never runs again: the raw
nominal and calibration datasets are dropped once it is done. The file is a Python pickle restricted on
load to numpy, collections and shipid classes; it is checked against a fingerprint of the inputs (nominal,
calibration, known particulars, options) so that a state is never resumed with other inputs.
"""

from __future__ import annotations

import hashlib
import io
import os
import pickle
from dataclasses import replace

import numpy as np

from shipid.errors import InputError
from shipid.methods.monitor.estimator import MassCMMonitor, MonitorUpdate
from shipid.methods.monitor.faults import Conditioner, FaultOptions

STATE_VERSION = 1


def restart_after_gap(mon: MassCMMonitor) -> None:
    """After a break in the stream: drop the partial block, restart the filters at the next sample.

    Before the start-up run, the start-up window starts again (Algorithm 1 needs contiguous samples)."""
    mon._pending, mon._npending = [], 0
    mon._t_next = None
    if not mon.started:
        mon._init_blocks, mon._t_first = [], None
        return
    mon._sim = None


class MonitorSession:
    """Faults handled, then the monitor. ``fingerprint``: a text naming the inputs (see :func:`fingerprint`)."""

    def __init__(self, monitor: MassCMMonitor, faults: FaultOptions = FaultOptions(), fingerprint: str = ""):
        self.mon = monitor
        monitor.keep_updates = False             # the session hands the updates out; the monitor keeps none
        self.cond = Conditioner(monitor.T, replace(faults, every=monitor.opt.every))
        self.fingerprint = fingerprint
        self.t_pushed: float | None = None       # time of the last sample pushed (a resumed file skips to it)
        self.out_bytes = 0                       # bytes of output written when the state was saved
        self.n_updates = 0
        self._gap_starts: list[float] = []

    def push(self, t, p, a_s, r, delta) -> tuple[list[MonitorUpdate], list[str]]:
        """Samples as they arrived (1-D arrays; NaN allowed): ``(updates, warning lines)``."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        X = np.vstack([np.atleast_1d(np.asarray(v, dtype=float)) for v in (p, a_s, r, delta)]).T
        push = self.cond.push
        for ti, row in zip(t.tolist(), X.tolist()):
            push(ti, row)
        if t.size:
            self.t_pushed = float(t[-1])
        return self._run()

    def finish(self) -> tuple[list[MonitorUpdate], list[str]]:
        """End of the stream: the samples the conditioner still holds."""
        self.cond.flush()
        return self._run()

    def _feed(self, rows: list) -> list[MonitorUpdate]:
        if not rows:
            return []
        A = np.array(rows, dtype=float).T
        ups = self.mon.feed(A[0], A[1], A[2], A[3], A[4])
        if self._gap_starts:
            T = self.mon.T
            for b in self.mon.blocks:
                if any(abs(b.t0 - g) < 0.5 * T for g in self._gap_starts):
                    b.after_gap = True
            t0 = self.mon.blocks[0].t0 if self.mon.blocks else -np.inf
            self._gap_starts = [g for g in self._gap_starts if g >= t0 - T]
        if self.mon.started and self.mon._refs is not None:
            self.mon._refs = None                 # the start-up is done: the raw references are not needed
        return ups

    def _run(self) -> tuple[list[MonitorUpdate], list[str]]:
        items, warns, no_est = self.cond.take()
        ups: list[MonitorUpdate] = []
        rows: list = []
        for it in items:
            if it[0] == "row":
                rows.append((it[1], *it[2]))
            else:
                ups += self._feed(rows)
                rows = []
                restart_after_gap(self.mon)
                self._gap_starts.append(float(it[1]))
        ups += self._feed(rows)
        for t, text in no_est:
            ups.append(MonitorUpdate(t, None, None, None, None, None, None, False, False, self.mon.change_at,
                                     window_s=0.0, warnings=(text,)))
        ups.sort(key=lambda u: u.t)
        self.n_updates += len(ups)
        return ups, warns

    @property
    def counts(self) -> dict:
        """Fault counters of the conditioner."""
        return dict(self.cond.counts)


def fingerprint(*parts) -> str:
    """SHA-256 of the inputs' bytes / texts: files are read, other parts are hashed as their ``repr``."""
    h = hashlib.sha256()
    for p in parts:
        if isinstance(p, (str, os.PathLike)) and os.path.isfile(p):
            with open(p, "rb") as fh:
                h.update(fh.read())
        else:
            h.update(repr(p).encode())
        h.update(b"\0")
    return h.hexdigest()


def save_state(session: MonitorSession, path: str) -> None:
    """Write ``session`` to ``path`` atomically (temporary file, fsync, :func:`os.replace`)."""
    data = pickle.dumps({"version": STATE_VERSION, "fingerprint": session.fingerprint, "session": session},
                        protocol=pickle.HIGHEST_PROTOCOL)
    tmp = f"{path}.tmp{os.getpid()}"
    with open(tmp, "wb") as fh:
        fh.write(data)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)


class _Restricted(pickle.Unpickler):
    """Only what a session holds: numpy arrays and scalars, deques, builtin containers, shipid classes."""

    _NUMPY = ("_reconstruct", "ndarray", "dtype", "scalar", "_frombuffer")

    def find_class(self, module, name):
        top = module.split(".")[0]
        if (top == "numpy" and name in self._NUMPY) or (module == "collections" and name == "deque") \
                or (module == "builtins" and name in ("complex", "slice", "frozenset", "set")):
            return super().find_class(module, name)
        if top == "shipid":
            obj = super().find_class(module, name)
            if isinstance(obj, type):
                return obj
        raise pickle.UnpicklingError(f"{module}.{name} is not allowed in a monitor state file")


def load_state(path: str, fingerprint_: str) -> MonitorSession:
    """The session saved in ``path``; :class:`~shipid.errors.InputError` if it is unreadable or not of these
    inputs."""
    try:
        with open(path, "rb") as fh:
            obj = _Restricted(io.BytesIO(fh.read())).load()
    except (OSError, EOFError, pickle.UnpicklingError, AttributeError, ImportError, IndexError, TypeError,
            ValueError) as err:
        raise InputError(f"not a readable monitor state ({type(err).__name__})", file=path) from None
    if not isinstance(obj, dict) or obj.get("version") != STATE_VERSION or not isinstance(obj.get("session"),
                                                                                        MonitorSession):
        raise InputError("not a monitor state of this version", file=path)
    if obj["fingerprint"] != fingerprint_:
        raise InputError("the state was saved with other inputs (nominal, calibration, known or options); "
                         "use another --state file", file=path)
    return obj["session"]


__all__ = ["MonitorSession", "restart_after_gap", "fingerprint", "save_state", "load_state"]
