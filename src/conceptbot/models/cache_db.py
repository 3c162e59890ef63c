"""SQLite store for the LLM response cache, the embedding cache and the call log.

This is the paper's cache-augmented generation: a repeated request (same backend, model, messages,
parameters) is answered from disk, and every text embedding is computed once per model. The
database runs in WAL mode with a busy time-out so several processes (a benchmark run in parallel,
the web app and the CLI) can share it.
"""

from __future__ import annotations

import hashlib
import json
import threading
import time
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from conceptbot.core.migrations import apply_migrations
from conceptbot.core.sqlite import connect_shared
from conceptbot.core.urls import redact_secrets
from conceptbot.models.migrations import MIGRATIONS


def request_key(kind: str, backend: str, model: str, request: Mapping[str, Any]) -> str:
    """sha256 of the canonical JSON of a request (sorted keys, no whitespace, no secrets)."""
    payload = {"kind": kind, "backend": backend, "model": model, "request": request}
    text = json.dumps(payload, sort_keys=True, separators=(",", ":"), ensure_ascii=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


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
    """

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._lock = threading.Lock()
        self._conn = connect_shared(self.path)
        self._migrate()

    # -- schema ---------------------------------------------------------------------------------
    def _migrate(self) -> None:
        with self._lock:
            apply_migrations(self._conn, MIGRATIONS, "_migrations")

    def applied_migrations(self) -> list[tuple[int, str]]:
        """``(number, name)`` of every applied migration."""
        with self._lock:
            rows = self._conn.execute("SELECT id, name FROM _migrations ORDER BY id").fetchall()
        return [(int(r[0]), str(r[1])) for r in rows]

    def close(self) -> None:
        """Close the connection."""
        with self._lock:
            self._conn.close()

    # -- LLM responses --------------------------------------------------------------------------
    def get_response(self, key: str) -> dict[str, Any] | None:
        """The cached response JSON for a request key, or ``None``."""
        with self._lock:
            row = self._conn.execute("SELECT response FROM llm_cache WHERE key = ?", (key,)).fetchone()
        return None if row is None else json.loads(row[0])

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
        with self._lock:
            self._conn.execute(
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
        with self._lock:
            row = self._conn.execute(
                "SELECT value FROM value_cache WHERE namespace = ? AND key = ?", (namespace, key)
            ).fetchone()
        return None if row is None else json.loads(row[0])

    def put_value(self, namespace: str, key: str, value: Any) -> None:
        """Store a JSON value (last writer wins)."""
        with self._lock:
            self._conn.execute(
                "INSERT OR REPLACE INTO value_cache VALUES (?, ?, ?, ?)",
                (namespace, key, json.dumps(value, ensure_ascii=False), time.time()),
            )

    # -- embeddings -----------------------------------------------------------------------------
    def get_embeddings(self, model: str, texts: Iterable[str]) -> dict[str, np.ndarray]:
        """Cached vectors for those of ``texts`` that have one."""
        unique = list(dict.fromkeys(texts))
        found: dict[str, np.ndarray] = {}
        with self._lock:
            # Chunked to stay under SQLite's bound-parameter limit.
            for start in range(0, len(unique), 500):
                chunk = unique[start : start + 500]
                marks = ",".join("?" * len(chunk))
                rows = self._conn.execute(
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
        with self._lock:
            self._conn.execute("BEGIN IMMEDIATE")
            try:
                self._conn.executemany("INSERT OR REPLACE INTO embedding_cache VALUES (?, ?, ?, ?, ?)", rows)
                self._conn.execute("COMMIT")
            except BaseException:
                self._conn.execute("ROLLBACK")
                raise

    # -- call log -------------------------------------------------------------------------------
    def log_call(self, record: CallRecord) -> None:
        """Append a row to the call log.

        The error text is masked again here (:func:`conceptbot.core.urls.redact_secrets`), whoever
        built the record: the log outlives the run and may be shared in a bug report.
        """
        with self._lock:
            self._conn.execute(
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
        with self._lock:
            rows = self._conn.execute(
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
