"""Byte-counting file reading for progress bars, for plain and gzip files."""

from __future__ import annotations

import gzip
import io
import shutil
import subprocess
from collections.abc import Callable, Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import BinaryIO

from conceptbot.core.errors import ImportDataError

Progress = Callable[[int], None]

#: gzip files at least this big are decompressed by a `gzip -dc` child process (in parallel).
CHILD_GZIP_MIN_BYTES = 50_000_000


class CountingReader(io.RawIOBase):
    """Wraps a binary file and reports each chunk's size to ``progress`` (compressed bytes)."""

    def __init__(self, raw: BinaryIO, progress: Progress | None) -> None:
        self._raw = raw
        self._progress = progress

    def readable(self) -> bool:
        return True

    def readinto(self, buffer: bytearray | memoryview) -> int:  # type: ignore[override]
        data = self._raw.read(len(buffer))
        n = len(data)
        buffer[:n] = data
        if self._progress and n:
            self._progress(n)
        return n


@contextmanager
def open_lines(path: Path, progress: Progress | None = None) -> Iterator[Iterator[bytes]]:
    """Iterate over the lines (bytes) of a plain or ``.gz`` file, reporting bytes of the file read.

    Large gzip files are decompressed by a ``gzip -dc`` child process when one is available, so
    decompression runs on another core while Python parses.

    Raises:
        ImportDataError: The file is missing, or a gzip file is truncated or corrupt.
    """
    path = Path(path)
    if not path.is_file():
        raise ImportDataError(f"no such file: {path}")
    with open(path, "rb") as raw:
        gz = raw.read(2) == b"\x1f\x8b"
        raw.seek(0)
        counted = io.BufferedReader(CountingReader(raw, progress), buffer_size=1 << 20)
        if not gz:
            yield iter(counted)
            return
        tool = shutil.which("gzip")
        if tool and path.stat().st_size >= CHILD_GZIP_MIN_BYTES:
            yield from _via_child(tool, counted, path)
            return
        stream = gzip.GzipFile(fileobj=counted)
        try:
            yield _checked(iter(stream), path)
        finally:
            stream.close()


def _checked(lines: Iterator[bytes], path: Path) -> Iterator[bytes]:
    try:
        yield from lines
    except (EOFError, gzip.BadGzipFile, OSError) as exc:
        raise ImportDataError(f"{path} is truncated or corrupt ({exc})") from None


def _via_child(tool: str, counted: io.BufferedReader, path: Path) -> Iterator[Iterator[bytes]]:
    import threading

    child = subprocess.Popen(
        [tool, "-dc"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE
    )
    assert child.stdin is not None and child.stdout is not None

    def feed() -> None:
        try:
            shutil.copyfileobj(counted, child.stdin, 1 << 20)
        except (BrokenPipeError, ValueError):
            pass  # the reader stopped early
        finally:
            with suppress(OSError):
                child.stdin.close()

    feeder = threading.Thread(target=feed, daemon=True)
    feeder.start()

    def lines() -> Iterator[bytes]:
        yield from io.BufferedReader(child.stdout, buffer_size=1 << 20)  # type: ignore[arg-type]
        feeder.join()
        code = child.wait()
        if code != 0:
            message = child.stderr.read().decode(errors="replace").strip() if child.stderr else ""
            raise ImportDataError(f"{path} is truncated or corrupt (gzip: {message or code})")

    try:
        yield lines()
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
