"""Temporary files that interrupted installs left behind, found by the process id in their name.

An install writes to a temporary file named with its process id and renames it when done; a
SIGKILL or a power cut leaves that file. The next install removes such files, but never the file of
an install that is still running in another process. The model store (``models install``) and the
knowledge graph (``kg install``) share this.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from pathlib import Path


def pid_running(pid: int) -> bool:
    """Whether process ``pid`` exists (on Windows: assumed, so a file's age decides alone)."""
    if pid == os.getpid():
        return True
    if os.name == "nt":
        return True  # os.kill(pid, 0) would send CTRL_C_EVENT there
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True  # it exists, owned by another user
    return True


def remove_stale(
    folder: Path, pid_of: Callable[[str], int | None], max_age_s: float, *, now: float | None = None
) -> list[tuple[Path, int]]:
    """Delete the files in ``folder`` whose process is gone or that nobody wrote for ``max_age_s``.

    Args:
        folder: Where to look (not recursively); a missing folder has nothing to remove.
        pid_of: The process id a file name carries, or None for a file that is not a temporary one.
        max_age_s: A file untouched this long is stale even if its process id is in use (ids are
            reused).
        now: The current time (tests).

    Returns:
        ``(path, size in bytes)`` of every file removed.
    """
    if not folder.is_dir():
        return []
    now = time.time() if now is None else now
    removed: list[tuple[Path, int]] = []
    for path in sorted(folder.iterdir()):
        pid = pid_of(path.name)
        if pid is None or not path.is_file():
            continue
        try:
            stat = path.stat()
            if pid_running(pid) and now - stat.st_mtime < max_age_s:
                continue
            path.unlink()
        except FileNotFoundError:
            continue  # its own install finished (or failed) meanwhile
        removed.append((path, stat.st_size))
    return removed
