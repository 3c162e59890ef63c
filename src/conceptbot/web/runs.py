"""Runs for the web page: one planning run at a time per server, streamed as events.

A run executes in a background thread: it plans (the pipeline reports ``status`` messages and each
module's results as ``ope``, ``urp`` and ``step`` events), then optionally executes the plan in the
simulator and renders pictures. Every event is kept, so a page that connects late (or reconnects)
replays the run from the start. The embedded model is one llama.cpp context shared by every page, so
while a run is going a new one is refused (:class:`BusyError`), whichever page or session asks:
a per-session limit let a client run many at once by fetching a fresh cookie for each.
"""

from __future__ import annotations

import shutil
import tempfile
import threading
import traceback
import uuid
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from conceptbot.core.errors import ConceptBotError
from conceptbot.core.scene import Scene

# (what to run, emit(event type, data), folder for pictures) -> None; raises ConceptBotError for
# errors a user can fix (shown on the page with their hint).
Worker = Callable[["RunSpec", Callable[[str, dict[str, Any]], None], Path], None]


class BusyError(Exception):
    """A run is already in progress on this server (this session's or another's)."""


@dataclass(frozen=True)
class RunSpec:
    """What to run."""

    request: str
    scene: Scene
    config: str
    backend: str
    risk: bool = False
    simulate: bool = False


@dataclass
class Run:
    """One run and everything it has reported so far."""

    id: str
    session: str
    spec: RunSpec
    out_dir: Path
    events: list[dict[str, Any]] = field(default_factory=list)
    finished: bool = False
    changed: threading.Condition = field(default_factory=threading.Condition)

    def emit(self, kind: str, data: dict[str, Any]) -> None:
        """Record an event and wake the streams."""
        with self.changed:
            self.events.append({"type": kind, **data})
            if kind in ("done", "error"):
                self.finished = True
            self.changed.notify_all()

    def stream(self, timeout: float = 15.0) -> Iterator[dict[str, Any] | None]:
        """Every event from the first, waiting for new ones; ``None`` after ``timeout`` seconds of
        silence (a keep-alive for the HTTP stream); ends after ``done`` or ``error``."""
        index = 0
        while True:
            with self.changed:
                if index >= len(self.events) and not self.finished:
                    self.changed.wait(timeout)
                new = self.events[index:]
                finished = self.finished
            index += len(new)
            if not new and not finished:
                yield None
            yield from new
            if finished and index >= len(self.events):
                return


class RunManager:
    """Starts runs, one at a time per server, and finds them again.

    Args:
        worker: Does the work of a run (plans, simulates), reporting through ``emit``.
        keep: Finished runs kept (their pictures live in temporary folders, removed with them).
    """

    def __init__(self, worker: Worker, keep: int = 20) -> None:
        self.worker = worker
        self.keep = keep
        self._runs: dict[str, Run] = {}
        self._lock = threading.Lock()
        self._model = threading.Lock()  # one planning run at a time in this process
        self._root = Path(tempfile.mkdtemp(prefix="conceptbot-web-"))

    def active(self, session: str) -> Run | None:
        """The session's unfinished run, if any."""
        with self._lock:
            return next((r for r in self._runs.values() if r.session == session and not r.finished), None)

    def get(self, run_id: str) -> Run | None:
        """A run by id."""
        with self._lock:
            return self._runs.get(run_id)

    def start(self, session: str, spec: RunSpec) -> Run:
        """Start a run for ``session``.

        Raises:
            BusyError: A run (this session's or another's) is still in progress.
        """
        with self._lock:
            going = next((r for r in self._runs.values() if not r.finished), None)
            if going is not None and going.session == session:
                raise BusyError("a run is already in progress for this page")
            if going is not None:
                raise BusyError(
                    "another run is already in progress on this server (one at a time: the model is "
                    "shared); try again when it has finished"
                )
            run_id = uuid.uuid4().hex[:12]
            out_dir = self._root / run_id
            out_dir.mkdir()
            run = Run(run_id, session, spec, out_dir)
            self._runs[run_id] = run
            self._forget_old()
        threading.Thread(target=self._execute, args=(run,), daemon=True, name=f"run-{run_id}").start()
        return run

    def _forget_old(self) -> None:
        finished = [r for r in self._runs.values() if r.finished]
        for run in finished[: max(0, len(finished) - self.keep)]:
            del self._runs[run.id]
            shutil.rmtree(run.out_dir, ignore_errors=True)

    def _execute(self, run: Run) -> None:
        # start() lets a run begin once the previous one is marked finished, a moment before that
        # one's thread lets go of the model: the lock makes the new run wait out that moment.
        self._model.acquire()
        try:
            self.worker(run.spec, run.emit, run.out_dir)
            run.emit("done", {})
        except ConceptBotError as exc:
            run.emit("error", {"message": exc.message, "hint": exc.hint or ""})
        except Exception as exc:  # the page must hear about a bug instead of waiting forever
            traceback.print_exc()
            run.emit("error", {"message": f"internal error: {type(exc).__name__}: {exc}", "hint": ""})
        finally:
            self._model.release()

    def close(self) -> None:
        """Remove every run's pictures."""
        shutil.rmtree(self._root, ignore_errors=True)
