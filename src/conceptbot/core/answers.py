"""One open question's answer, handed from the thread that receives it (a web request, a ROS 2
callback) to the planning thread that waits for it. The web page and the ROS 2 node both ask
through one."""

from __future__ import annotations

import threading


class AnswerSlot:
    """Where the answer to one question arrives; the first answer counts."""

    def __init__(self) -> None:
        self._given = threading.Event()
        self._lock = threading.Lock()
        self._answer: str | None = None

    def give(self, answer: str) -> bool:
        """Hand the answer over; False when the question has its answer already."""
        with self._lock:
            if self._answer is not None:
                return False
            self._answer = answer
        self._given.set()
        return True

    def wait(self, timeout_s: float) -> str | None:
        """The answer, waiting at most ``timeout_s``; None when none came."""
        return self._answer if self._given.wait(timeout_s) else None
