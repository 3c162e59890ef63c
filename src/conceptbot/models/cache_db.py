"""SQLite store for the LLM response cache, the embedding cache and the call log.

This is the paper's cache-augmented generation: a repeated request (same backend, model, messages,
parameters) is answered from disk, and every text embedding is computed once per model. The
database runs in WAL mode with a busy time-out so several processes (a benchmark run in parallel,
the web app and the CLI) can share it.

Every failure of the file (its folder cannot be made, it is damaged, read-only, locked or on a full
disk) is a :class:`CacheError` that names the file and the fix. Opening the store raises it; the
wrappers in front of the backends (:mod:`conceptbot.models.caching`, OPE) go through
:meth:`CacheStore.attempt` instead, so a cache that fails mid-run costs a warning, never the result
of a call that worked.
"""

from __future__ import annotations

import errno
import hashlib
import json
import logging
import shlex
import sqlite3
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any, ParamSpec, TypeVar

import numpy as np

from conceptbot.core.errors import ConceptBotError
from conceptbot.core.migrations import apply_migrations
from conceptbot.core.sqlite import connect_shared, failure_kind
from conceptbot.core.urls import redact_secrets
from conceptbot.models.migrations import MIGRATIONS

P = ParamSpec("P")
T = TypeVar("T")

# Without a handler configured, logging prints warnings as bare lines on stderr (its last-resort
# handler), which is what a CLI user should see; an application can route them as it likes.
logger = logging.getLogger(__name__)

OR_NO_CACHE = ", or run with --no-cache (no cache, no call log)"
"""The end of the hints that offer ``--no-cache`` as a way round (a warning under it drops it)."""
_WRITABLE_HOME = "set CONCEPTBOT_HOME to a writable folder" + OR_NO_CACHE


class CacheError(ConceptBotError):
    """The cache database cannot be opened, read or written; the message names the file, the hint
    the fix."""


def _move_away(path: Path) -> str:
    """The fix for a damaged file: a command that moves it into a folder beside it, with its -wal
    and -shm files (SQLite would replay a stale WAL into the new database)."""
    keep = shlex.quote(str(path.with_name("broken-cache")))
    return (
        f"move it away: mkdir -p {keep} && mv {shlex.quote(str(path))}* {keep}/ ;"
        " an empty cache is made on the next run"
    )


def folder_error(folder: Path, exc: OSError) -> CacheError:
    """The error for a cache folder (the home) that cannot be created.

    Args:
        folder: The folder that was to hold the cache database.
        exc: What ``mkdir`` raised.
    """
    if isinstance(exc, FileExistsError | NotADirectoryError):
        reason = "it, or a folder above it, is a file"
    elif exc.errno == errno.EROFS:
        reason = "the file system is read-only"
    else:
        reason = exc.strerror or str(exc)
    return CacheError(
        f"cannot create the folder {folder} for the cache database: {reason}",
        hint="set CONCEPTBOT_HOME to a writable folder (it is created if missing)",
    )


def cache_error(path: Path, exc: sqlite3.Error) -> CacheError:
    """The error for an SQLite failure on the cache database ``path``, with its fix."""
    detail = str(exc)
    match failure_kind(exc, path):
        case "locked":
            return CacheError(
                f"the cache database {path} stayed locked by another process ({detail})",
                hint="wait for the other conceptbot process to finish" + OR_NO_CACHE,
            )
        case "full":
            return CacheError(
                f"cannot write the cache database {path}: the disk is full or failing ({detail})",
                hint="free some disk space, or set CONCEPTBOT_HOME to a folder on another disk",
            )
        case "read-only":
            return CacheError(
                f"cannot write the cache database {path}: it or its folder is read-only ({detail})",
                hint=_WRITABLE_HOME,
            )
        case "folder":
            return CacheError(f"the cache database {path} is a folder, not a file", hint=_move_away(path))
        case "unopenable":
            return CacheError(f"cannot open the cache database {path} ({detail})", hint=_WRITABLE_HOME)
        case _:
            return CacheError(
                f"the cache database {path} is damaged or was not made by ConceptBot ({detail})",
                hint=_move_away(path),
            )


@cache
def _expected_columns() -> dict[str, tuple[tuple[str, str], ...]]:
    """Each table the migrations make, with its columns' names and types (from an in-memory copy)."""
    conn = sqlite3.connect(":memory:", isolation_level=None)
    try:
        apply_migrations(conn, MIGRATIONS, "_migrations")
        tables = [r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")]
        return {t: _columns(conn, t) for t in tables if not t.startswith("sqlite_")}
    finally:
        conn.close()


def _columns(conn: sqlite3.Connection, table: str) -> tuple[tuple[str, str], ...]:
    return tuple((str(r[1]), str(r[2]).upper()) for r in conn.execute(f"PRAGMA table_info({table})"))


def request_key(kind: str, backend: str, model: str, request: Mapping[str, Any]) -> str:
    """sha256 of the canonical JSON of a request (sorted keys, no whitespace, no secrets)."""
    payload = {"kind": kind, "backend": backend, "model": model, "request": request}
    text = json.dumps(payload, sort_keys=True, separators=(",", ":"), ensure_ascii=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _loads(text: str) -> Any | None:
    """A stored JSON value, or ``None`` (a miss) for a row damaged on disk: the value is then
    computed again and overwritten instead of failing every run that needs it."""
    try:
        return json.loads(text)
    except (TypeError, ValueError):
        return None


@dataclass(frozen=True)
class CallRecord:
    """One row of the call log."""

    kind: str
    module: str
    backend: str
    model: str
    prompt_tokens: int
    completion_tokens: int
    latency_s: float
    cost_usd: float | None
    cached: bool
    error: str | None = None
    ts: float = 0.0


class CacheStore:
    """The cache database. Open once per process and share; it is thread-safe.

    Args:
        path: SQLite file; its folder is created if needed.

    Raises:
        CacheError: The folder cannot be created, or the file cannot be opened, is damaged, is
            not ConceptBot's (a table missing or with other columns), is read-only or locked, or
            the disk is full. Every method raises it too when the file fails later.
    """

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise folder_error(self.path.parent, exc) from exc
        self._lock = threading.Lock()
        self._warned: set[str] = set()
        try:
            self._conn = connect_shared(self.path)
        except sqlite3.Error as exc:
            raise cache_error(self.path, exc) from exc
        try:
            self._migrate()
        except BaseException:
            self._conn.close()
            raise

    @contextmanager
    def _db(self) -> Iterator[sqlite3.Connection]:
        """The connection, held under the lock; an SQLite failure becomes a :class:`CacheError`."""
        with self._lock:
            try:
                yield self._conn
            except sqlite3.Error as exc:
                raise cache_error(self.path, exc) from exc

    # -- schema ---------------------------------------------------------------------------------
    def _migrate(self) -> None:
        """Apply pending migrations, then check that every table is there with its columns.

        The check catches a table dropped by hand, or a same-named table of another program,
        now, with the fix, instead of as "no such table" in the middle of a run. Extra tables and
        columns are allowed: a newer ConceptBot may have added them.
        """
        with self._db() as db:
            apply_migrations(db, MIGRATIONS, "_migrations")
            for table, columns in _expected_columns().items():
                found = set(_columns(db, table))
                if not found:
                    problem = f"table {table} is missing"
                elif not set(columns) <= found:
                    problem = f"table {table} has other columns than ConceptBot's"
                else:
                    continue
                raise CacheError(
                    f"the cache database {self.path} is damaged or was not made by ConceptBot ({problem})",
                    hint=_move_away(self.path),
                )

    def applied_migrations(self) -> list[tuple[int, str]]:
        """``(number, name)`` of every applied migration."""
        with self._db() as db:
            rows = db.execute("SELECT id, name FROM _migrations ORDER BY id").fetchall()
        return [(int(r[0]), str(r[1])) for r in rows]

    def attempt(self, what: str, action: Callable[P, T], /, *args: P.args, **kwargs: P.kwargs) -> T | None:
        """``action(*args, **kwargs)``, or ``None`` when the database fails (:class:`CacheError`).

        For callers whose result must not depend on the cache: a failed read counts as a miss, a
        failed write or log entry is skipped. The failure is logged as a warning once per
        ``what`` (e.g. ``"write the cache"``) and store, not once per call of a long run.

        Args:
            what: What was being done, for the warning ("could not WHAT").
            action: A method of this store.
            *args, **kwargs: Its arguments.
        """
        try:
            return action(*args, **kwargs)
        except CacheError as exc:
            with self._lock:
                first = what not in self._warned
                self._warned.add(what)
            if first:
                hint = f" Hint: {exc.hint}" if exc.hint else ""
                logger.warning("warning: could not %s, going on without it: %s.%s", what, exc.message, hint)
            return None

    def close(self) -> None:
        """Close the connection."""
        with self._lock:
            self._conn.close()

    # -- LLM responses --------------------------------------------------------------------------
    def get_response(self, key: str) -> dict[str, Any] | None:
        """The cached response JSON for a request key, or ``None``."""
        with self._db() as db:
            row = db.execute("SELECT response FROM llm_cache WHERE key = ?", (key,)).fetchone()
        return None if row is None else _loads(row[0])

    def put_response(
        self,
        key: str,
        *,
        kind: str,
        backend: str,
        model: str,
        request: Mapping[str, Any],
        response: Mapping[str, Any],
    ) -> None:
        """Store a response under its request key (last writer wins)."""
        with self._db() as db:
            db.execute(
                "INSERT OR REPLACE INTO llm_cache VALUES (?, ?, ?, ?, ?, ?, ?)",
                (
                    key,
                    kind,
                    backend,
                    model,
                    json.dumps(request, sort_keys=True, ensure_ascii=False),
                    json.dumps(response, ensure_ascii=False),
                    time.time(),
                ),
            )

    # -- derived values (e.g. OPE properties per object, mode, model and graph version) ---------
    def get_value(self, namespace: str, key: str) -> Any | None:
        """A cached JSON value, or None."""
        with self._db() as db:
            row = db.execute(
                "SELECT value FROM value_cache WHERE namespace = ? AND key = ?", (namespace, key)
            ).fetchone()
        return None if row is None else _loads(row[0])

    def put_value(self, namespace: str, key: str, value: Any) -> None:
        """Store a JSON value (last writer wins)."""
        with self._db() as db:
            db.execute(
                "INSERT OR REPLACE INTO value_cache VALUES (?, ?, ?, ?)",
                (namespace, key, json.dumps(value, ensure_ascii=False), time.time()),
            )

    # -- embeddings -----------------------------------------------------------------------------
    def get_embeddings(self, model: str, texts: Iterable[str]) -> dict[str, np.ndarray]:
        """Cached vectors for those of ``texts`` that have one."""
        unique = list(dict.fromkeys(texts))
        found: dict[str, np.ndarray] = {}
        with self._db() as db:
            # Chunked to stay under SQLite's bound-parameter limit.
            for start in range(0, len(unique), 500):
                chunk = unique[start : start + 500]
                marks = ",".join("?" * len(chunk))
                rows = db.execute(
                    f"SELECT text, vector FROM embedding_cache WHERE model = ? AND text IN ({marks})",
                    (model, *chunk),
                ).fetchall()
                for text, blob in rows:
                    found[text] = np.frombuffer(blob, dtype="<f4").copy()
        return found

    def put_embeddings(self, model: str, texts: Sequence[str], vectors: np.ndarray) -> None:
        """Store one vector per text."""
        now = time.time()
        rows = [
            (model, text, int(vec.shape[0]), np.asarray(vec, dtype="<f4").tobytes(), now)
            for text, vec in zip(texts, vectors, strict=False)
        ]
        with self._db() as db:
            db.execute("BEGIN IMMEDIATE")
            try:
                db.executemany("INSERT OR REPLACE INTO embedding_cache VALUES (?, ?, ?, ?, ?)", rows)
                db.execute("COMMIT")
            except BaseException:
                if db.in_transaction:  # SQLite may have rolled back already (after SQLITE_FULL)
                    db.execute("ROLLBACK")
                raise

    # -- call log -------------------------------------------------------------------------------
    def log_call(self, record: CallRecord) -> None:
        """Append a row to the call log.

        The error text is masked again here (:func:`conceptbot.core.urls.redact_secrets`), whoever
        built the record: the log outlives the run and may be shared in a bug report.
        """
        with self._db() as db:
            db.execute(
                "INSERT INTO calls (ts, kind, module, backend, model, prompt_tokens, "
                "completion_tokens, latency_s, cost_usd, cached, error) "
                "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                (
                    record.ts or time.time(),
                    record.kind,
                    record.module,
                    record.backend,
                    record.model,
                    record.prompt_tokens,
                    record.completion_tokens,
                    record.latency_s,
                    record.cost_usd,
                    int(record.cached),
                    None if record.error is None else redact_secrets(record.error),
                ),
            )

    def calls(self, limit: int = 100) -> list[CallRecord]:
        """The most recent calls, newest first."""
        with self._db() as db:
            rows = db.execute(
                "SELECT kind, module, backend, model, prompt_tokens, completion_tokens, latency_s, "
                "cost_usd, cached, error, ts FROM calls ORDER BY id DESC LIMIT ?",
                (limit,),
            ).fetchall()
        return [
            CallRecord(
                kind=r[0],
                module=r[1],
                backend=r[2],
                model=r[3],
                prompt_tokens=r[4],
                completion_tokens=r[5],
                latency_s=r[6],
                cost_usd=r[7],
                cached=bool(r[8]),
                error=r[9],
                ts=r[10],
            )
            for r in rows
        ]
