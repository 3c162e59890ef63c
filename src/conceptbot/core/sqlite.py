"""Open an SQLite file that several processes share (WAL mode, busy time-out), and say what an
SQLite failure on such a file means for the user (:func:`failure_kind`)."""

from __future__ import annotations

import os
import sqlite3
import time
from pathlib import Path
from typing import Literal

FailureKind = Literal["locked", "full", "read-only", "folder", "unopenable", "damaged"]
"""What went wrong with an SQLite file, by what the user does about it: wait for the other process
(``locked``), free disk space (``full``), choose a writable folder (``read-only``, ``unopenable``),
or move the file away (``folder``, ``damaged``)."""

# SQLite's primary result codes (``sqlite3.Error.sqlite_errorname``, extended codes start with
# these), by kind; the message is the fallback for an error raised without a code.
_CODES: tuple[tuple[str, FailureKind], ...] = (
    ("SQLITE_BUSY", "locked"),
    ("SQLITE_LOCKED", "locked"),
    ("SQLITE_FULL", "full"),
    ("SQLITE_IOERR", "full"),
    ("SQLITE_READONLY", "read-only"),
    ("SQLITE_NOTADB", "damaged"),
    ("SQLITE_CORRUPT", "damaged"),
)
_MESSAGES: tuple[tuple[str, FailureKind], ...] = (
    ("locked", "locked"),
    ("disk is full", "full"),
    ("disk i/o error", "full"),
    ("readonly", "read-only"),
    ("read-only", "read-only"),
)


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


def _writable(path: Path) -> bool:
    # os.access answers False on a read-only mount even for root, which permission bits do not.
    folder = path if path.is_dir() else path.parent
    return os.access(folder, os.W_OK) and (not path.is_file() or os.access(path, os.W_OK))


def failure_kind(exc: sqlite3.Error, path: Path) -> FailureKind:
    """What an SQLite error raised on the file ``path`` means for the user.

    ``unable to open database file`` (SQLITE_CANTOPEN) covers a folder in the file's place, a
    read-only folder and a missing one, so for that error the file system is asked which it is.
    An I/O error is counted as a full disk: on a full disk SQLite often reports "disk I/O error"
    (it failed to grow the WAL), and freeing space is the first thing to try either way.

    Args:
        exc: The error.
        path: The database file it was raised on.

    Returns:
        ``locked``, ``full``, ``read-only``, ``folder``, ``unopenable`` or ``damaged`` (not a
        database, a corrupt page, or tables that are not the expected ones).
    """
    code = getattr(exc, "sqlite_errorname", None) or ""
    text = str(exc).lower()
    for prefix, kind in _CODES:
        if code.startswith(prefix):
            return kind
    for words, kind in _MESSAGES:
        if words in text:
            return kind
    if path.is_dir():
        return "folder"
    if code.startswith("SQLITE_CANTOPEN") or "unable to open" in text:
        return "read-only" if path.parent.is_dir() and not _writable(path) else "unopenable"
    return "damaged"
