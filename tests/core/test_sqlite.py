import sqlite3
import threading
import time
from pathlib import Path

import pytest

from conceptbot.core.sqlite import connect_shared


def _writer_holding_the_file(path: Path) -> sqlite3.Connection:
    """A connection in rollback-journal mode with a write transaction open (RESERVED lock)."""
    conn = sqlite3.connect(path, isolation_level=None, check_same_thread=False)
    conn.execute("CREATE TABLE t (x)")
    conn.execute("BEGIN IMMEDIATE")
    conn.execute("INSERT INTO t VALUES (1)")
    return conn


def test_switch_to_wal_waits_for_a_writer_that_sqlite_does_not_wait_for(tmp_path: Path) -> None:
    # SQLite answers "database is locked" at once here (deadlock avoidance skips the busy
    # handler), which is what failed in CI when four processes opened one new cache file.
    path = tmp_path / "shared.db"
    writer = _writer_holding_the_file(path)
    timer = threading.Timer(0.3, lambda: writer.execute("COMMIT"))
    timer.start()
    try:
        conn = connect_shared(path, timeout=10.0)
    finally:
        timer.join()
    assert conn.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    assert conn.execute("SELECT x FROM t").fetchall() == [(1,)]
    conn.close()
    writer.close()


def test_a_file_locked_past_the_timeout_is_an_error(tmp_path: Path) -> None:
    path = tmp_path / "shared.db"
    writer = _writer_holding_the_file(path)
    started = time.monotonic()
    with pytest.raises(sqlite3.OperationalError, match="locked"):
        connect_shared(path, timeout=0.3)
    assert time.monotonic() - started >= 0.3
    writer.execute("ROLLBACK")
    writer.close()
