"""The knowledge graph in SQLite: an atomic builder (write side) and ``SQLiteGraph`` (read side).

Schema (version 1)::

    meta(key, value)                      schema_version, built_at, build_seconds, install set
    sources(id, name, version, edges)     one row per source label (omcs, wordnet, conceptnet5/...)
    relations(id, name)
    concepts(id, text UNIQUE)             readable concept text ("ice cream")
    edges(head, rel, tail, weight, source)  integer ids; indexes on (head) and (tail)

A database is built in a temporary file beside the target and renamed over it only when complete,
so a failed or interrupted import never replaces the current graph, and readers never see a
half-built one. Re-installing builds a fresh file and swaps it in (idempotent).
"""

from __future__ import annotations

import os
import sqlite3
import time
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

from conceptbot.core.errors import KnowledgeUnavailableError
from conceptbot.knowledge.base import DEFAULT_LIMIT, ConceptEdges, Edge
from conceptbot.knowledge.normalize import lookup

SCHEMA_VERSION = 1
INSTALL_HINT = "run `conceptbot kg install` (offline bundle) or `conceptbot kg install conceptnet5`"

_SCHEMA = """
CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE sources (id INTEGER PRIMARY KEY, name TEXT UNIQUE NOT NULL, version TEXT,
                      edges INTEGER NOT NULL);
CREATE TABLE relations (id INTEGER PRIMARY KEY, name TEXT UNIQUE NOT NULL);
CREATE TABLE concepts (id INTEGER PRIMARY KEY, text TEXT UNIQUE NOT NULL);
CREATE TABLE edges (head INTEGER NOT NULL, rel INTEGER NOT NULL, tail INTEGER NOT NULL,
                    weight REAL NOT NULL, source INTEGER NOT NULL);
"""


class GraphBuilder:
    """Write a new graph database atomically.

    Use as a context manager; ``add`` edges, then leaving the block without an exception indexes
    the file and renames it over ``path``. On an exception the temporary file is deleted and the
    current database is left as it was.

    Args:
        path: The database to (re)place.
        install: A label for what was installed (``offline``, ``conceptnet5``), kept in ``meta``.
    """

    BATCH = 50_000

    def __init__(self, path: Path, install: str) -> None:
        self.path = Path(path)
        self.install = install
        self.tmp = self.path.with_name(f".{self.path.name}.{os.getpid()}.building")
        self._concepts: dict[str, int] = {}
        self._relations: dict[str, int] = {}
        self._sources: dict[str, int] = {}
        self._source_counts: dict[str, int] = {}
        self._source_versions: dict[str, str] = {}
        # One packed int per edge (not a tuple): ~3x less memory on a full ConceptNet 5 import.
        self._seen: set[int] = set()
        self._batch: list[tuple[int, int, int, float, int]] = []
        self._conn: sqlite3.Connection | None = None
        self._started = 0.0
        self.duplicates = 0

    def __enter__(self) -> GraphBuilder:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.tmp.unlink(missing_ok=True)
        self._started = time.time()
        try:
            self._conn = sqlite3.connect(self.tmp, isolation_level=None)
            # A private temp file: durability comes from the final fsync + rename, not the journal.
            self._conn.execute("PRAGMA journal_mode=OFF")
            self._conn.execute("PRAGMA synchronous=OFF")
            self._conn.executescript(_SCHEMA)
            self._conn.execute("BEGIN")
        except BaseException:
            # Interrupted before the block began (SIGTERM right after the file appeared): __exit__
            # will not run, so the temporary file is removed here.
            if self._conn is not None:
                self._conn.close()
            self.tmp.unlink(missing_ok=True)
            raise
        return self

    def _id(self, table: dict[str, int], name: str) -> int:
        found = table.get(name)
        if found is None:
            found = table[name] = len(table) + 1
        return found

    def set_source_version(self, source: str, version: str) -> None:
        """Record where a source's data came from (file name, package version, URL)."""
        self._source_versions[source] = version

    def add(self, head: str, relation: str, tail: str, weight: float, source: str) -> bool:
        """Queue one edge; exact duplicates (same head, relation, tail, source) are dropped.

        Returns:
            True if the edge was new.
        """
        if not head or not tail or head == tail:
            return False
        h, t = self._id(self._concepts, head), self._id(self._concepts, tail)
        r, s = self._id(self._relations, relation), self._id(self._sources, source)
        key = (((h << 32) | t) << 16) | (r << 8) | s
        if key in self._seen:
            self.duplicates += 1
            return False
        self._seen.add(key)
        self._batch.append((h, r, t, float(weight), s))
        self._source_counts[source] = self._source_counts.get(source, 0) + 1
        if len(self._batch) >= self.BATCH:
            self._flush()
        return True

    def add_edges(self, edges: Iterable[Edge]) -> int:
        """Queue many edges; returns how many were new."""
        return sum(self.add(e.head, e.relation, e.tail, e.weight, e.source) for e in edges)

    @property
    def edge_count(self) -> int:
        """Edges queued so far."""
        return sum(self._source_counts.values())

    @property
    def concept_count(self) -> int:
        """Distinct concepts seen so far."""
        return len(self._concepts)

    @property
    def source_names(self) -> list[str]:
        """Source labels seen so far."""
        return list(self._sources)

    def _flush(self) -> None:
        assert self._conn is not None
        self._conn.executemany("INSERT INTO edges VALUES (?, ?, ?, ?, ?)", self._batch)
        self._batch.clear()

    def __exit__(self, exc_type: object, exc: object, tb: object) -> None:
        assert self._conn is not None
        try:
            if exc_type is not None:
                return
            self._flush()
            self._seen.clear()  # free memory before indexing
            conn = self._conn
            conn.executemany(
                "INSERT INTO concepts VALUES (?, ?)", ((i, t) for t, i in self._concepts.items())
            )
            conn.executemany(
                "INSERT INTO relations VALUES (?, ?)", ((i, n) for n, i in self._relations.items())
            )
            conn.executemany(
                "INSERT INTO sources VALUES (?, ?, ?, ?)",
                (
                    (i, n, self._source_versions.get(n, ""), self._source_counts.get(n, 0))
                    for n, i in self._sources.items()
                ),
            )
            conn.execute("CREATE INDEX edges_head ON edges (head)")
            conn.execute("CREATE INDEX edges_tail ON edges (tail)")
            meta = {
                "schema_version": str(SCHEMA_VERSION),
                "install": self.install,
                "built_at": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
                "build_seconds": f"{time.time() - self._started:.1f}",
                "edges": str(self.edge_count),
                "concepts": str(len(self._concepts)),
            }
            conn.executemany("INSERT INTO meta VALUES (?, ?)", meta.items())
            conn.execute("COMMIT")
            conn.execute("ANALYZE")
            conn.close()
            self._conn = None
            with open(self.tmp, "rb+") as handle:
                os.fsync(handle.fileno())
            os.replace(self.tmp, self.path)
        finally:
            if self._conn is not None:
                self._conn.close()
            self.tmp.unlink(missing_ok=True)


class SQLiteGraph:
    """Read edges from a built graph database (the default, offline KnowledgeGraph).

    Args:
        path: The database file.

    Raises:
        KnowledgeUnavailableError: The file is missing, empty, corrupt or of another schema.
    """

    name = "sqlite"

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        if not self.path.is_file() or self.path.stat().st_size == 0:
            raise KnowledgeUnavailableError(f"no knowledge graph at {self.path}", hint=INSTALL_HINT)
        try:
            self._conn = sqlite3.connect(f"file:{self.path}?mode=ro", uri=True, check_same_thread=False)
            meta = dict(self._conn.execute("SELECT key, value FROM meta").fetchall())
            self._relations = dict(self._conn.execute("SELECT name, id FROM relations").fetchall())
            self._relation_names = {i: n for n, i in self._relations.items()}
            self._source_names = dict(self._conn.execute("SELECT id, name FROM sources").fetchall())
        except sqlite3.DatabaseError as exc:
            raise KnowledgeUnavailableError(
                f"{self.path} is not a readable knowledge graph ({exc})", hint=INSTALL_HINT
            ) from None
        if meta.get("schema_version") != str(SCHEMA_VERSION):
            raise KnowledgeUnavailableError(
                f"{self.path} has schema {meta.get('schema_version')!r}, expected {SCHEMA_VERSION}",
                hint=INSTALL_HINT,
            )
        self.meta = meta

    @property
    def version(self) -> str:
        """``INSTALL:BUILT_AT`` from the build metadata; see :class:`KnowledgeGraph`."""
        return f"{self.meta.get('install', '')}:{self.meta.get('built_at', '')}"

    @contextmanager
    def _reading(self) -> Iterator[None]:
        """Turn damage found while reading into one clear error.

        Opening checks only the first pages; a file with corrupted pages further in (a bad disk, an
        interrupted copy) fails at the first query that touches them, as ``sqlite3.DatabaseError`` or
        as rows pointing at ids that do not exist.
        """
        try:
            yield
        except (sqlite3.DatabaseError, KeyError, ValueError, TypeError) as exc:
            raise KnowledgeUnavailableError(
                f"{self.path} is damaged ({exc.__class__.__name__}: {exc})",
                hint="rebuild it with `conceptbot kg install --force`",
            ) from None

    def concept_id(self, concept: str) -> int | None:
        """The id of an exact (already normalised) concept, or None."""
        if not concept.isascii() and any(0xD800 <= ord(c) <= 0xDFFF for c in concept):
            return None  # a lone surrogate (bytes that were not UTF-8) names no stored concept
        with self._reading():
            row = self._conn.execute("SELECT id FROM concepts WHERE text = ?", (concept,)).fetchone()
            return None if row is None else int(row[0])

    def _fetch(self, concept: str, relations: Sequence[str] | None, limit: int) -> list[Edge]:
        with self._reading():
            return self._fetch_rows(concept, relations, limit)

    def _fetch_rows(self, concept: str, relations: Sequence[str] | None, limit: int) -> list[Edge]:
        cid = self.concept_id(concept)
        if cid is None or limit <= 0:
            return []
        rel_filter, params = "", []
        if relations is not None:
            ids = [self._relations[r] for r in relations if r in self._relations]
            if not ids:
                return []
            rel_filter = f" AND rel IN ({','.join('?' * len(ids))})"
            params = ids
        sql = (
            f"SELECT head, rel, tail, weight, source FROM edges WHERE head = ?{rel_filter} "
            f"UNION ALL SELECT head, rel, tail, weight, source FROM edges WHERE tail = ?{rel_filter} "
            "ORDER BY 4 DESC LIMIT ?"
        )
        rows = self._conn.execute(sql, (cid, *params, cid, *params, limit)).fetchall()
        ids = {r[0] for r in rows} | {r[2] for r in rows}
        marks = ",".join("?" * len(ids))
        texts = dict(self._conn.execute(f"SELECT id, text FROM concepts WHERE id IN ({marks})", tuple(ids)))
        return [
            Edge(texts[h], self._relation_names[r], texts[t], w, self._source_names[s])
            for h, r, t, w, s in rows
        ]

    def edges(
        self, concept: str, relations: Sequence[str] | None = None, limit: int = DEFAULT_LIMIT
    ) -> ConceptEdges:
        """Edges of ``concept`` as head or tail, strongest first; see :class:`KnowledgeGraph`."""
        return lookup(concept, self._fetch, relations, limit)

    def stats(self) -> dict[str, object]:
        """Edge counts per source and per relation, concept count and build metadata."""
        with self._reading():
            return self._stats()

    def _stats(self) -> dict[str, object]:
        sources = self._conn.execute(
            "SELECT name, version, edges FROM sources ORDER BY edges DESC"
        ).fetchall()
        relations = self._conn.execute(
            "SELECT r.name, COUNT(*) FROM edges e JOIN relations r ON r.id = e.rel GROUP BY r.name "
            "ORDER BY 2 DESC"
        ).fetchall()
        return {
            "path": str(self.path),
            "meta": self.meta,
            "sources": [{"name": n, "version": v, "edges": c} for n, v, c in sources],
            "relations": dict(relations),
            "edges": int(self.meta.get("edges", 0)),
            "concepts": int(self.meta.get("concepts", 0)),
        }

    def random_concepts(self, n: int, seed: int = 0) -> list[str]:
        """``n`` concept texts drawn uniformly by id (for benchmarks)."""
        import random

        with self._reading():
            count = int(self.meta.get("concepts", 0))
            rng = random.Random(seed)
            ids = [rng.randint(1, count) for _ in range(n)]
            rows = dict(
                self._conn.execute(
                    f"SELECT id, text FROM concepts WHERE id IN ({','.join('?' * len(ids))})", tuple(set(ids))
                ).fetchall()
            )
            return [rows[i] for i in ids if i in rows]

    def close(self) -> None:
        """Close the connection."""
        self._conn.close()
