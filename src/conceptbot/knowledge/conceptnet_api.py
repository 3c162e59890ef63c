"""ConceptNet 5 REST API backend with the paper's "ConceptNet cache".

Each normalised concept is fetched once from ``{base_url}/query?node=/c/en/<concept>&other=/c/en``
(one page of up to ``fetch_limit`` edges) and stored in a SQLite file; every later look-up of that
concept is answered from the file without any HTTP request. Concepts the API knows nothing about
are cached too, as an empty list (a negative cache), so unknown names cost one request, not one per
run. The relation filter and the ``limit`` are applied to the cached edges, so one fetch serves
every later query about the concept.

With ``cache_only=True`` the network is never used: a concept that is not in the cache simply has
no edges (``match="none"``), which is how a benchmark is re-run offline from a warm cache.

Names are resolved with :func:`conceptbot.knowledge.normalize.lookup`, the same multi-word and
plural fallback rule that every backend uses ("Knives" -> "knife").

Only the standard library is used (``urllib.request``, ``json``, ``sqlite3``).
"""

from __future__ import annotations

import http.client
import json
import sqlite3
import threading
import time
import urllib.error
import urllib.parse
import urllib.request
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from conceptbot.core.errors import ConfigError, KnowledgeUnavailableError
from conceptbot.core.migrations import apply_migrations
from conceptbot.core.sqlite import connect_shared
from conceptbot.core.urls import check_http_url
from conceptbot.core.version import __version__
from conceptbot.knowledge.base import DEFAULT_LIMIT, ConceptEdges, Edge
from conceptbot.knowledge.normalize import lookup

DEFAULT_BASE_URL = "https://api.conceptnet.io"
SOURCE = "conceptnet-api"

_HINT = "check the network or the base URL, or use --cache-only or the offline SQLite graph instead"
_USER_AGENT = f"conceptbot/{__version__} (+ConceptNet cache)"
_ENGLISH = "/c/en/"

#: Numbered schema migrations of the ConceptNet cache. Append new ones; never edit an applied one.
#: They are recorded in their own ``conceptnet_migrations`` table (not ``_migrations``) so the
#: cache may share a database file with the LLM cache without their migration numbers clashing.
MIGRATIONS: list[tuple[int, str, str]] = [
    (
        1,
        "initial",
        """
        CREATE TABLE conceptnet_cache (
            concept TEXT PRIMARY KEY,      -- normalised concept, e.g. 'ice cream'
            edges TEXT NOT NULL,           -- JSON list of [head, relation, tail, weight], strongest first
            edge_count INTEGER NOT NULL,   -- 0 for a concept the API does not know (negative cache)
            url TEXT NOT NULL,             -- the request the edges came from, for provenance
            fetched_at REAL NOT NULL       -- unix time
        )
        """,
    ),
]


class ConceptNetAPI:
    """KnowledgeGraph backed by the ConceptNet 5 REST API, with a persistent SQLite cache.

    The object is thread-safe: the SQLite connection is guarded by a lock and HTTP requests run
    outside it.

    Args:
        cache_path: SQLite file of the cache; its folder is created if needed.
        base_url: Absolute ``http(s)`` URL of the API (a mirror or a local server works too).
        timeout_s: Time-out of one HTTP request, in seconds.
        max_retries: Extra attempts after a time-out, a refused connection, HTTP 429 or 5xx.
        backoff_s: Wait before the first retry; doubled for every further retry.
        cache_only: Never use the network; a concept not in the cache has no edges.
        fetch_limit: Edges fetched (and cached) per concept: one page of the API.

    Raises:
        ConfigError: A malformed ``base_url`` or an out-of-range number.
        KnowledgeUnavailableError: The cache file cannot be opened (e.g. it is not a database).
    """

    name = SOURCE
    version = ""  # the live API is not versioned; see KnowledgeGraph.version

    def __init__(
        self,
        cache_path: Path,
        base_url: str = DEFAULT_BASE_URL,
        timeout_s: float = 10,
        max_retries: int = 3,
        backoff_s: float = 0.5,
        cache_only: bool = False,
        fetch_limit: int = 100,
    ) -> None:
        self.base_url = _validate_base_url(base_url)
        if not timeout_s > 0:
            raise ConfigError(f"ConceptNet API timeout must be positive, got {timeout_s!r}.")
        if max_retries < 0:
            raise ConfigError(f"ConceptNet API max_retries must be 0 or more, got {max_retries!r}.")
        if backoff_s < 0:
            raise ConfigError(f"ConceptNet API backoff must be 0 or more, got {backoff_s!r}.")
        if fetch_limit < 1:
            raise ConfigError(f"ConceptNet API fetch_limit must be at least 1, got {fetch_limit!r}.")
        self.cache_path = Path(cache_path)
        self.timeout_s = float(timeout_s)
        self.max_retries = int(max_retries)
        self.backoff_s = float(backoff_s)
        self.cache_only = cache_only
        self.fetch_limit = int(fetch_limit)
        self._lock = threading.Lock()
        self._conn = self._open()

    # -- KnowledgeGraph -------------------------------------------------------------------------
    def edges(
        self, concept: str, relations: Sequence[str] | None = None, limit: int = DEFAULT_LIMIT
    ) -> ConceptEdges:
        """Edges where ``concept`` is the head or the tail, from the cache or (once) from the API.

        Args:
            concept: Any object or keyword name; resolved with the shared fallback rule
                (exact, lemma, head noun, modifiers).
            relations: Keep only these relation names (None: all).
            limit: At most this many edges, strongest first.

        Returns:
            The matched concept and its edges; empty with ``match="none"`` when the API knows
            nothing about any candidate, or, with ``cache_only``, when none is cached.

        Raises:
            KnowledgeUnavailableError: The API is unreachable or answered with an error or
                malformed data, or the cache file is unusable.
        """
        return lookup(concept, self._fetch, relations, limit)

    # -- cache ------------------------------------------------------------------------------------
    def cached_concepts(self) -> list[str]:
        """Every concept in the cache (including negative entries), sorted.

        Returns:
            The normalised concept names.

        Raises:
            KnowledgeUnavailableError: The cache file is unusable.
        """
        try:
            with self._lock:
                rows = self._conn.execute("SELECT concept FROM conceptnet_cache ORDER BY concept").fetchall()
        except sqlite3.Error as exc:
            raise self._cache_error(exc) from exc
        return [str(r[0]) for r in rows]

    def applied_migrations(self) -> list[tuple[int, str]]:
        """``(number, name)`` of every applied cache migration.

        Returns:
            The applied migrations, oldest first.
        """
        with self._lock:
            rows = self._conn.execute("SELECT id, name FROM conceptnet_migrations ORDER BY id").fetchall()
        return [(int(r[0]), str(r[1])) for r in rows]

    def close(self) -> None:
        """Close the cache database."""
        with self._lock:
            self._conn.close()

    def __enter__(self) -> ConceptNetAPI:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- internals --------------------------------------------------------------------------------
    def _fetch(self, concept: str, relations: Sequence[str] | None, limit: int) -> list[Edge]:
        """All edges of one normalised concept (cache first), filtered by relation, at most ``limit``."""
        cached = self._get(concept)
        if cached is None:
            if self.cache_only:
                return []  # documented: a miss in cache-only mode is "nothing known", not an error
            url = self.query_url(concept)
            cached = _parse(self._request(url), url)
            self._put(concept, cached, url)
        if relations is not None:
            wanted = set(relations)
            cached = [e for e in cached if e.relation in wanted]
        return cached[: max(limit, 0)]

    def query_url(self, concept: str) -> str:
        """The API URL that fetches one page of edges of a normalised concept.

        Args:
            concept: Normalised concept ("ice cream"); spaces become underscores as in ConceptNet URIs.

        Returns:
            ``{base_url}/query?node=/c/en/ice_cream&other=/c/en&limit={fetch_limit}``.
        """
        term = urllib.parse.quote(concept.replace(" ", "_"), safe="")
        return f"{self.base_url}/query?node=/c/en/{term}&other=/c/en&limit={self.fetch_limit}"

    def _request(self, url: str) -> Any:
        """GET ``url`` and decode its JSON, retrying transient failures with exponential backoff."""
        request = urllib.request.Request(
            url, headers={"Accept": "application/json", "User-Agent": _USER_AGENT}
        )
        attempts = self.max_retries + 1
        reason = "no attempt made"
        for attempt in range(attempts):
            if attempt:
                time.sleep(self.backoff_s * 2 ** (attempt - 1))
            try:
                with urllib.request.urlopen(request, timeout=self.timeout_s) as response:
                    body = response.read()
            except urllib.error.HTTPError as exc:
                exc.close()  # an HTTPError holds the open response; free the socket now
                # 429 (rate limit) and 5xx are the server's temporary trouble: worth another try.
                # Any other 4xx means the request itself is wrong; repeating it cannot help.
                if exc.code == 429 or exc.code >= 500:
                    reason = f"HTTP {exc.code} {exc.reason}"
                    continue
                raise KnowledgeUnavailableError(
                    f"ConceptNet API refused {url}: HTTP {exc.code} {exc.reason}.", hint=_HINT
                ) from exc
            except (OSError, http.client.HTTPException) as exc:
                # URLError (refused, DNS), TimeoutError and dropped connections are all OSErrors;
                # a garbled status line or a truncated body is an HTTPException.
                reason = _describe(exc)
                continue
            try:
                return json.loads(body)
            except ValueError as exc:  # JSONDecodeError and UnicodeDecodeError
                raise _malformed(url, "the body is not JSON") from exc
        raise KnowledgeUnavailableError(
            f"ConceptNet API unreachable at {url} after {attempts} attempt(s): {reason}.", hint=_HINT
        )

    def _open(self) -> sqlite3.Connection:
        """Open the cache database (WAL, busy time-out) and apply pending migrations."""
        conn: sqlite3.Connection | None = None
        try:
            self.cache_path.parent.mkdir(parents=True, exist_ok=True)
            # Shared with parallel benchmark runs, the web app and the CLI (WAL, busy time-out).
            conn = connect_shared(self.cache_path)
            # Its own migrations table, so this cache may share a file with the LLM cache.
            apply_migrations(conn, MIGRATIONS, "conceptnet_migrations")
        except (OSError, sqlite3.Error) as exc:
            if conn is not None:
                conn.close()
            raise self._cache_error(exc) from exc
        return conn

    def _get(self, concept: str) -> list[Edge] | None:
        """The cached edges of a concept, ``[]`` for a negative entry, ``None`` when not cached."""
        try:
            with self._lock:
                row = self._conn.execute(
                    "SELECT edges FROM conceptnet_cache WHERE concept = ?", (concept,)
                ).fetchone()
        except sqlite3.Error as exc:
            raise self._cache_error(exc) from exc
        if row is None:
            return None
        try:
            return [Edge(str(h), str(r), str(t), float(w), SOURCE) for h, r, t, w in json.loads(row[0])]
        except (ValueError, TypeError):
            # A damaged row is treated as a miss so it is fetched again and overwritten, rather
            # than making the concept unusable until someone deletes the cache by hand.
            return None

    def _put(self, concept: str, edges: list[Edge], url: str) -> None:
        """Store a concept's edges (last writer wins)."""
        payload = json.dumps([[e.head, e.relation, e.tail, e.weight] for e in edges], ensure_ascii=False)
        try:
            with self._lock:
                self._conn.execute(
                    "INSERT OR REPLACE INTO conceptnet_cache VALUES (?, ?, ?, ?, ?)",
                    (concept, payload, len(edges), url, time.time()),
                )
        except sqlite3.Error as exc:
            raise self._cache_error(exc) from exc

    def _cache_error(self, exc: BaseException) -> KnowledgeUnavailableError:
        return KnowledgeUnavailableError(
            f"ConceptNet cache {self.cache_path} is unusable: {exc}.",
            hint="delete the file to rebuild the cache from the API",
        )


def _validate_base_url(base_url: str) -> str:
    """The base URL without a trailing slash (no query string: paths are appended to it)."""
    return check_http_url(base_url, "ConceptNet API base URL", DEFAULT_BASE_URL, allow_query=False)


def _parse(payload: Any, url: str) -> list[Edge]:
    """Edges of an API answer: English-only, no ExternalURL, duplicates merged, strongest first.

    Raises:
        KnowledgeUnavailableError: The answer is not an object with an ``edges`` list of edges.
    """
    if not isinstance(payload, dict) or not isinstance(payload.get("edges"), list):
        raise _malformed(url, "no 'edges' list")
    best: dict[tuple[str, str, str], Edge] = {}
    for raw in payload["edges"]:
        if not isinstance(raw, dict):
            raise _malformed(url, "an edge is not an object")
        rel, start, end = raw.get("rel"), raw.get("start"), raw.get("end")
        if not (isinstance(rel, dict) and isinstance(start, dict) and isinstance(end, dict)):
            raise _malformed(url, "an edge lacks rel/start/end")
        relation = str(rel.get("label") or rel.get("@id") or "").removeprefix("/r/")
        weight = raw.get("weight", 1.0)  # ConceptNet's default weight when none is given
        if not relation or isinstance(weight, bool) or not isinstance(weight, int | float):
            raise _malformed(url, "an edge lacks a relation or a numeric weight")
        head, tail = _english_text(start), _english_text(end)
        # ExternalURL edges point at other sites (DBpedia, Wiktionary), not at concepts.
        if relation == "ExternalURL" or head is None or tail is None:
            continue
        edge = Edge(head, relation, tail, float(weight), SOURCE)
        # The same assertion often comes back once per word sense (/c/en/knife/n, /c/en/knife/v):
        # keep one copy, the strongest, so it does not crowd out other edges.
        key = (head, relation, tail)
        if key not in best or best[key].weight < edge.weight:
            best[key] = edge
    # sorted() is stable, so equal weights keep the API's order and results are reproducible.
    return sorted(best.values(), key=lambda e: -e.weight)


def _english_text(node: dict[str, Any]) -> str | None:
    """Readable text of an English node (``/c/en/sharp_object/n`` -> "sharp object"), else None."""
    # The URI, not the "language" field, decides: it is always present, and an ExternalURL end node
    # (http://...) has no language at all.
    uri = node.get("term") or node.get("@id")
    if not isinstance(uri, str) or not uri.startswith(_ENGLISH):
        return None
    # /c/en/<text>[/<sense>/...]: the text is the fourth path segment, senses follow it.
    text = urllib.parse.unquote(uri.split("/")[3]).replace("_", " ").strip()
    return text or None


def _malformed(url: str, why: str) -> KnowledgeUnavailableError:
    return KnowledgeUnavailableError(f"ConceptNet API at {url} returned malformed data ({why}).", hint=_HINT)


def _describe(exc: BaseException) -> str:
    """A short reason for a network failure ("timed out", "connection refused", ...)."""
    if isinstance(exc, urllib.error.URLError) and not isinstance(exc.reason, str):
        exc = exc.reason if isinstance(exc.reason, BaseException) else exc
    if isinstance(exc, TimeoutError):
        return "timed out"
    if isinstance(exc, ConnectionRefusedError):
        return "connection refused"
    text = str(exc) or type(exc).__name__
    return text
