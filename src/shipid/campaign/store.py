"""The campaign store: one SQLite file (WAL) with one row per run.

Tables
------
``campaigns``
    One row per campaign, keyed by its name: task reference (``"module:function"``),
    seed, number of runs, fixed keyword arguments (JSON), a SHA-256 of the per-run
    inputs, the shipid version, a SHA-256 of shipid's source code when the campaign was
    created (``code_sha256``; informational), and the creation time (UTC).
``runs``
    One row per finished run, primary key ``(campaign, run)``: the run's seed entropy
    ``[seed, i]`` (JSON), its inputs (JSON), outputs (JSON, ``NULL`` when it failed),
    ``status`` (``"ok"`` or ``"failed"``), ``error`` (``"Type: message"``), wall and CPU
    time of the run in seconds (``wall_s``, ``cpu_s``: the process's CPU time, so a loaded
    machine shows as wall >> CPU), the worker (``host:pid``) that ran it, and the
    SHA-256 of the shipid source that worker started with (``code``).

Durability: the engine writes each finished chunk of runs in one transaction
(``synchronous=FULL``), so a process killed at any moment (SIGKILL included) leaves
every committed chunk intact and no half-written row; the primary key makes a
repeated run impossible. Only the main process writes, so there is one writer.
"""

from __future__ import annotations

import json
import os
import sqlite3
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, Iterable

from shipid.errors import ShipidError
from shipid.outputs import atomic_write

SCHEMA = """
CREATE TABLE IF NOT EXISTS campaigns (
    name TEXT PRIMARY KEY,
    task TEXT NOT NULL,
    seed INTEGER NOT NULL,
    n_runs INTEGER NOT NULL,
    kwargs TEXT NOT NULL,
    inputs_sha256 TEXT,
    shipid_version TEXT NOT NULL,
    code_sha256 TEXT,
    created_utc TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS runs (
    campaign TEXT NOT NULL REFERENCES campaigns(name),
    run INTEGER NOT NULL,
    seed TEXT NOT NULL,
    inputs TEXT NOT NULL,
    outputs TEXT,
    status TEXT NOT NULL CHECK (status IN ('ok', 'failed')),
    error TEXT,
    wall_s REAL,
    worker TEXT,
    cpu_s REAL,
    code TEXT,
    PRIMARY KEY (campaign, run)
);
"""

#: Fields of a campaign definition that must agree for ``--resume``.
DEFINITION_FIELDS = ("task", "seed", "n_runs", "kwargs", "inputs_sha256", "shipid_version")


@dataclass(frozen=True)
class RunRecord:
    """One finished run as stored (``outputs`` is ``None`` for a failed run)."""

    index: int
    seed: list
    inputs: Any
    outputs: dict | None
    status: str
    error: str | None = None
    wall_s: float | None = None
    worker: str | None = None
    cpu_s: float | None = None
    code: str | None = None

    def same_result(self, other: "RunRecord") -> bool:
        """True when index, seed, inputs, outputs, status and error agree (timing and worker ignored)."""
        return (self.index, self.seed, self.inputs, self.outputs, self.status, self.error) == \
            (other.index, other.seed, other.inputs, other.outputs, other.status, other.error)


@dataclass(frozen=True)
class CampaignDefinition:
    """What a campaign is: everything that decides its results.

    ``kwargs`` is the canonical JSON text of the fixed keyword arguments, and
    ``inputs_sha256`` the SHA-256 of the canonical JSON of the per-run inputs
    (``None`` when the runs have no inputs).
    """

    name: str
    task: str
    seed: int
    n_runs: int
    kwargs: str = "{}"
    inputs_sha256: str | None = None
    shipid_version: str = field(default="")
    code_sha256: str | None = None

    def differences(self, other: "CampaignDefinition") -> list[str]:
        """Names of the definition fields that differ between ``self`` and ``other``."""
        return [f for f in DEFINITION_FIELDS if getattr(self, f) != getattr(other, f)]


class CampaignStore:
    """A campaign store in an SQLite file (created on first use, WAL mode).

    Parameters
    ----------
    path : path-like
        The SQLite file.
    writer : bool
        Open it to run a campaign into: takes an exclusive lock (``flock`` on
        ``<path>.lock``, released when the process ends, even by SIGKILL) so that two
        campaign processes never write one store at once. Readers (export, info) need
        no lock: WAL lets them read while a campaign writes.
    """

    def __init__(self, path: str | os.PathLike, *, writer: bool = False):
        self.path = Path(path)
        self._lock = None
        if self.path.exists() and self.path.is_dir():
            raise ShipidError(f"{path}: store is a directory, not a file")
        if writer:
            self._lock = _exclusive_lock(self.path)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._con = sqlite3.connect(str(self.path), timeout=60.0, isolation_level=None)
            self._con.execute("PRAGMA journal_mode=WAL")
            self._con.execute("PRAGMA synchronous=FULL")
            self._con.executescript(SCHEMA)
        except sqlite3.DatabaseError as err:
            self._release()
            raise ShipidError(f"{path}: not a usable campaign store ({err})") from None

    # -- life cycle ---------------------------------------------------------------
    def close(self) -> None:
        """Close the connection and release the writer lock (the file stays)."""
        self._con.close()
        self._release()

    def _release(self) -> None:
        if self._lock is not None:
            self._lock.close()   # closing the descriptor releases the flock
            self._lock = None

    def __enter__(self) -> "CampaignStore":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- campaigns ----------------------------------------------------------------
    def campaign_names(self) -> list[str]:
        """Names of the campaigns in the store, in creation order."""
        return [r[0] for r in self._con.execute("SELECT name FROM campaigns ORDER BY rowid")]

    def definition(self, name: str) -> CampaignDefinition | None:
        """The stored definition of campaign ``name``, or ``None``."""
        row = self._con.execute(
            "SELECT name, task, seed, n_runs, kwargs, inputs_sha256, shipid_version, code_sha256 "
            "FROM campaigns WHERE name = ?", (name,)).fetchone()
        return CampaignDefinition(*row) if row else None

    def metadata(self, name: str) -> dict | None:
        """All stored metadata of campaign ``name`` as a dict, or ``None``."""
        cur = self._con.execute("SELECT * FROM campaigns WHERE name = ?", (name,))
        row = cur.fetchone()
        if row is None:
            return None
        return dict(zip([d[0] for d in cur.description], row))

    def create(self, d: CampaignDefinition) -> None:
        """Record a new campaign definition."""
        with self._transaction():
            self._con.execute(
                "INSERT INTO campaigns (name, task, seed, n_runs, kwargs, inputs_sha256, shipid_version, "
                "code_sha256, created_utc) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
                (d.name, d.task, d.seed, d.n_runs, d.kwargs, d.inputs_sha256, d.shipid_version, d.code_sha256,
                 datetime.now(timezone.utc).isoformat(timespec="seconds")))

    # -- runs ---------------------------------------------------------------------
    def done_indices(self, name: str) -> set[int]:
        """Indices of the runs of ``name`` already stored (ok or failed)."""
        return {r[0] for r in self._con.execute("SELECT run FROM runs WHERE campaign = ?", (name,))}

    def delete_failed(self, name: str) -> int:
        """Remove the failed runs of ``name`` (so that a resume runs them again); return how many."""
        with self._transaction():
            cur = self._con.execute("DELETE FROM runs WHERE campaign = ? AND status != 'ok'", (name,))
        return cur.rowcount

    def count(self, name: str) -> int:
        """Number of stored runs of ``name``."""
        return self._con.execute("SELECT COUNT(*) FROM runs WHERE campaign = ?", (name,)).fetchone()[0]

    def write(self, name: str, rows: Iterable[dict]) -> None:
        """Insert finished runs (dicts as produced by the engine) in one transaction.

        A run already in the store raises ``sqlite3.IntegrityError`` and the whole
        transaction is rolled back: a run is never stored twice.
        """
        data = [(name, r["index"], json.dumps(r["seed"]), r["inputs_json"], r["outputs_json"],
                 r["status"], r["error"], r["wall_s"], r["worker"], r.get("cpu_s"), r.get("code")) for r in rows]
        try:
            with self._transaction():
                self._con.executemany(
                    "INSERT INTO runs (campaign, run, seed, inputs, outputs, status, error, wall_s, worker, cpu_s, "
                    "code) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)", data)
        except sqlite3.IntegrityError:
            raise
        except sqlite3.Error as err:  # disk full, I/O error ...: one line; committed chunks stay
            raise ShipidError(f"{self.path}: cannot write runs ({err}); finished chunks are kept, "
                              "--resume continues") from None

    def records(self, name: str) -> list[RunRecord]:
        """All stored runs of ``name`` in run order."""
        cur = self._con.execute(
            "SELECT run, seed, inputs, outputs, status, error, wall_s, worker, cpu_s, code FROM runs "
            "WHERE campaign = ? ORDER BY run", (name,))
        return [RunRecord(run, json.loads(seed), json.loads(inputs),
                          None if outputs is None else json.loads(outputs), status, error, wall_s, worker, cpu_s,
                          code)
                for run, seed, inputs, outputs, status, error, wall_s, worker, cpu_s, code in cur]

    def _transaction(self):
        con = self._con

        class _Tx:
            def __enter__(self_inner):
                con.execute("BEGIN IMMEDIATE")

            def __exit__(self_inner, exc_type, exc, tb):
                con.execute("ROLLBACK" if exc_type else "COMMIT")
                return False

        return _Tx()


def _exclusive_lock(path: Path):
    """Open ``<path>.lock`` and take a non-blocking exclusive ``flock`` on it, or raise one line."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX: no cross-process guard
        return None
    path.parent.mkdir(parents=True, exist_ok=True)
    fh = open(f"{path}.lock", "a+")
    try:
        fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        fh.close()
        raise ShipidError(f"{path}: store is in use by another running campaign; "
                          "wait for it to finish (or use another --store)") from None
    return fh


def records_frame(records: list[RunRecord], campaign: str | None = None):
    """A pandas DataFrame of runs: metadata columns plus one column per scalar output.

    Scalar outputs (numbers, strings, booleans, ``None``) become columns named
    ``out.<key>`` (nested dicts flattened with dots); other values (lists) are kept
    as JSON text. The full ``inputs`` and ``outputs`` are also kept as JSON text.
    """
    import pandas as pd

    def flat(prefix: str, value, into: dict) -> None:
        if isinstance(value, dict):
            for k, v in value.items():
                flat(f"{prefix}.{k}", v, into)
        elif value is None or isinstance(value, (int, float, str, bool)):
            into[prefix] = value
        else:
            into[prefix] = json.dumps(value)

    rows = []
    for r in records:
        row = {"campaign": campaign, "run": r.index, "seed": json.dumps(r.seed), "status": r.status,
               "error": r.error, "wall_s": r.wall_s, "cpu_s": r.cpu_s, "worker": r.worker, "code": r.code,
               "inputs": json.dumps(r.inputs), "outputs": None if r.outputs is None else json.dumps(r.outputs)}
        if r.outputs is not None:
            flat("out", r.outputs, row)
        rows.append(row)
    frame = pd.DataFrame(rows)
    for col in frame.columns:   # an output whose type varies between runs: keep it as JSON text (Parquet-safe)
        if col.startswith("out.") and frame[col].dtype == object:
            kinds = {type(v) for v in frame[col] if v is not None and v == v}
            if len(kinds) > 1 and not kinds <= {int, float}:
                frame[col] = [None if v is None else json.dumps(v) for v in frame[col]]
    return frame


def export_store(store_path: str | os.PathLike, out: str | os.PathLike, *, campaign: str | None = None,
                 force: bool = False) -> tuple[Path, int]:
    """Export one campaign of a store to Parquet (``.parquet``/``.pq``) or CSV (``.csv``).

    Parameters
    ----------
    store_path : path-like
        An existing store.
    out : path-like
        Output file; its suffix chooses the format. Written atomically, never clobbered
        unless ``force``.
    campaign : str or None
        Campaign name; may be omitted when the store holds exactly one.
    force : bool
        Overwrite ``out``.

    Returns
    -------
    (Path, int)
        The written file and the number of runs in it.
    """
    if not Path(store_path).is_file():
        raise ShipidError(f"{store_path}: no such store")
    suffix = Path(out).suffix.lower()
    if suffix not in (".parquet", ".pq", ".csv"):
        raise ShipidError(f"{out}: unknown export format '{suffix}' (use .parquet or .csv)")
    with CampaignStore(store_path) as st:
        names = st.campaign_names()
        if campaign is None:
            if len(names) != 1:
                raise ShipidError(f"{store_path}: holds {len(names)} campaigns ({', '.join(names) or 'none'}); "
                                  "name one with --campaign")
            campaign = names[0]
        elif campaign not in names:
            raise ShipidError(f"{store_path}: no campaign '{campaign}' (has: {', '.join(names) or 'none'})")
        frame = records_frame(st.records(campaign), campaign)
    if suffix == ".csv":
        written = atomic_write(out, lambda p: frame.to_csv(p, index=False), force=force)
    else:
        written = atomic_write(out, lambda p: frame.to_parquet(p, index=False), force=force)
    return written, len(frame)
