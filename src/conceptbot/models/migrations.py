"""Numbered schema migrations of the cache database (``$CONCEPTBOT_HOME/cache.db``).

Append new migrations; never edit an applied one. Each runs once, inside a write transaction, and
is recorded in the ``_migrations`` table, so several processes can open the database at once.
"""

from __future__ import annotations

MIGRATIONS: list[tuple[int, str, str]] = [
    (
        1,
        "initial",
        """
        CREATE TABLE llm_cache (
            key TEXT PRIMARY KEY,          -- sha256 of the canonical request
            kind TEXT NOT NULL,            -- 'chat' or 'score'
            backend TEXT NOT NULL,
            model TEXT NOT NULL,
            request TEXT NOT NULL,         -- canonical request JSON (no secrets)
            response TEXT NOT NULL,        -- response JSON
            created_at REAL NOT NULL
        );
        CREATE TABLE embedding_cache (
            model TEXT NOT NULL,
            text TEXT NOT NULL,
            dim INTEGER NOT NULL,
            vector BLOB NOT NULL,          -- little-endian float32, L2-normalised
            created_at REAL NOT NULL,
            PRIMARY KEY (model, text)
        );
        CREATE TABLE calls (
            id INTEGER PRIMARY KEY AUTOINCREMENT,
            ts REAL NOT NULL,
            kind TEXT NOT NULL,            -- 'chat', 'score' or 'embed'
            module TEXT NOT NULL,          -- who asked: 'cli', 'ope', 'urp', 'planner', ...
            backend TEXT NOT NULL,
            model TEXT NOT NULL,
            prompt_tokens INTEGER NOT NULL,
            completion_tokens INTEGER NOT NULL,
            latency_s REAL NOT NULL,
            cost_usd REAL,                 -- NULL when the price is unknown
            cached INTEGER NOT NULL,
            error TEXT
        );
        CREATE INDEX calls_ts ON calls (ts);
        """,
    ),
    (
        2,
        "values",
        """
        CREATE TABLE value_cache (
            namespace TEXT NOT NULL,       -- e.g. 'ope-properties'
            key TEXT NOT NULL,             -- sha256 of what the value depends on
            value TEXT NOT NULL,           -- JSON
            created_at REAL NOT NULL,
            PRIMARY KEY (namespace, key)
        );
        """,
    ),
]
