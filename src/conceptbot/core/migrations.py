"""Numbered SQLite schema migrations, shared by every database ConceptBot writes."""

from __future__ import annotations

import sqlite3
import time
from collections.abc import Sequence

Migration = tuple[int, str, str]


def apply_migrations(conn: sqlite3.Connection, migrations: Sequence[Migration], table: str) -> None:
    """Apply each ``(number, name, sql)`` not yet recorded in ``table``, once, in order.

    Each migration runs inside ``BEGIN IMMEDIATE``, which takes the write lock first, so two
    processes opening the same file cannot both apply it. ``conn`` must be in autocommit mode
    (``isolation_level=None``).
    """
    conn.execute(
        f"CREATE TABLE IF NOT EXISTS {table} "
        "(id INTEGER PRIMARY KEY, name TEXT NOT NULL, applied_at REAL NOT NULL)"
    )
    for number, name, sql in migrations:
        conn.execute("BEGIN IMMEDIATE")
        try:
            if not conn.execute(f"SELECT 1 FROM {table} WHERE id = ?", (number,)).fetchone():
                for statement in sql.split(";"):
                    if statement.strip():
                        conn.execute(statement)
                conn.execute(f"INSERT INTO {table} VALUES (?, ?, ?)", (number, name, time.time()))
            conn.execute("COMMIT")
        except BaseException:
            # SQLite may have rolled back already after some errors (a full disk): a second ROLLBACK
            # would fail and hide the error that matters.
            if conn.in_transaction:
                conn.execute("ROLLBACK")
            raise
