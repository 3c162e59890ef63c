"""SIGTERM as an exception, so that a command stopped by systemd, docker or ``kill`` cleans up.

Python's default SIGTERM action ends the process on the spot: no ``finally`` block, no context
manager's exit, so temporary files (a half-built graph database, the web server's pictures) stay
behind. Inside :func:`sigterm_raises` SIGTERM raises :class:`Terminated` instead, which unwinds the
stack like Ctrl-C's ``KeyboardInterrupt`` does.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType


class Terminated(SystemExit):
    """The process got SIGTERM.

    A ``SystemExit`` (so a ``BaseException``): ``except Exception`` blocks on the way do not swallow
    it, and left uncaught it ends the process quietly with the shell's code for SIGTERM (143).
    """

    def __init__(self) -> None:
        super().__init__(128 + signal.SIGTERM)


def _raise_terminated(signum: int, frame: FrameType | None) -> None:
    raise Terminated


@contextmanager
def sigterm_raises() -> Iterator[None]:
    """Within the block, SIGTERM raises :class:`Terminated` in the main thread.

    The previous handler comes back when the block ends. Outside the main thread (where Python
    cannot set handlers) the block runs unchanged.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
