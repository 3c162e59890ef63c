"""Open an SQLite file that several processes share (WAL mode, busy time-out)."""

from __future__ import annotations

import sqlite3
import time
from pathlib import Path


def connect_shared(path: Path, timeout: float = 30.0) -> sqlite3.Connection:
    """An autocommit connection to ``path`` in WAL mode, waiting up to ``timeout`` s for locks.

    WAL lets readers and one writer work at once, so parallel benchmark runs, the web app and the
    CLI can share one file; the busy time-out waits for the writer instead of failing. Switching a
    new file to WAL needs an exclusive lock, and SQLite answers "database is locked" at once,
    without calling the busy handler, when another process holds the file mid-switch. So the switch
    is tried again until ``timeout``.

    Raises:
        sqlite3.OperationalError: the file stayed locked for ``timeout`` seconds.
    """
    conn = sqlite3.connect(path, timeout=timeout, isolation_level=None, check_same_thread=False)
    deadline = time.monotonic() + timeout
    delay = 0.01
    try:
        while True:
            try:
                conn.execute("PRAGMA journal_mode=WAL")
                break
            except sqlite3.OperationalError as exc:
                if "locked" not in str(exc) or time.monotonic() > deadline:
                    raise
                time.sleep(delay)
                delay = min(delay * 2, 0.5)
        conn.execute("PRAGMA synchronous=NORMAL")
        conn.execute(f"PRAGMA busy_timeout={int(timeout * 1000)}")
    except BaseException:
        conn.close()
        raise
    return conn
