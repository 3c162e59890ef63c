"""Runs for the web page: one planning run at a time per server, streamed as events.

A run executes in a background thread: it plans (the pipeline reports ``status`` messages and each
module's results as ``ope``, ``urp`` and ``step`` events), then optionally executes the plan in the
simulator and renders pictures. Every event is kept, so a page that connects late (or reconnects)
replays the run from the start. The embedded model is one llama.cpp context shared by every page, so
while a run is going a new one is refused (:class:`BusyError`), whichever page or session asks:
a per-session limit let a client run many at once by fetching a fresh cookie for each.

A stream waits for events on the event loop (:meth:`Run.follow`), not in a worker thread: the sync
endpoints share anyio's 40 threads, and 45 streams that each held one stalled every other endpoint
for the 15 s keep-alive. A run also takes at most :data:`MAX_STREAMS` streams at once.
"""

from __future__ import annotations

import asyncio
import contextlib
import shutil
import tempfile
import threading
import traceback
import uuid
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from conceptbot.core.answers import AnswerSlot
from conceptbot.core.errors import ConceptBotError
from conceptbot.core.scene import Scene
from conceptbot.core.system import Ask
from conceptbot.core.trace import ClarifyingQuestion

# (what to run, emit(event type, data), folder for pictures, ask: the page asks, or None) -> None;
# raises ConceptBotError for errors a user can fix (shown on the page with their hint).
Worker = Callable[["RunSpec", Callable[[str, dict[str, Any]], None], Path, "Ask | None"], None]

MAX_STREAMS = 8
"""Event streams one run serves at once. The page opens one (and one more for a moment while it
reconnects); the cap bounds what a client holding the run's cookie can make the server keep open."""

ANSWER_WAIT_S = 300.0
"""Seconds a run waits for the page's answer to a question before it ends without a plan."""
KEEP_ALIVE_S = 15.0
"""Seconds of silence after which a stream sends a keep-alive (proxies close idle connections)."""


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
    ask: bool = True


@dataclass
class Run:
    """One run and everything it has reported so far.

    ``emit`` is called from the run's worker thread; the streams that follow the run live on the
    server's event loop, so each waiting stream leaves a thread-safe wake-up callback in ``_wakers``.
    """

    id: str
    session: str
    spec: RunSpec
    out_dir: Path
    events: list[dict[str, Any]] = field(default_factory=list)
    finished: bool = False
    lock: threading.Lock = field(default_factory=threading.Lock)
    streams: int = 0
    closing: bool = False
    _wakers: set[Callable[[], None]] = field(default_factory=set)
    # The open question and its answer slot (filled by the page through answer(); None: none open).
    _question: tuple[ClarifyingQuestion, AnswerSlot] | None = None

    def ask(self, question: ClarifyingQuestion, wait_s: float = ANSWER_WAIT_S) -> str:
        """Show ``question`` on the page (a ``question`` event) and wait for its answer.

        Raises:
            ConceptBotError: No answer within ``wait_s``: the run ends without a plan, never a guess.
        """
        slot = AnswerSlot()
        with self.lock:
            self._question = (question, slot)
        try:
            self.emit("question", {"question": question.to_dict()})
            answer = slot.wait(wait_s)
            if answer is None:
                raise ConceptBotError(
                    f"no answer to {question.text!r} within {wait_s:g} s",
                    hint="answer the question on the page, or plan again",
                )
            return answer
        finally:
            with self.lock:
                self._question = None

    def answer(self, value: str) -> str:
        """The page's answer to the open question: ``given``; ``closed`` when no question is open (or
        it has its answer); ``invalid`` when ``value`` does not answer it
        (:meth:`ClarifyingQuestion.read`)."""
        with self.lock:
            open_question = self._question
        if open_question is None:
            return "closed"
        question, slot = open_question
        chosen = question.read(value)
        if chosen is None:
            return "invalid"
        return "given" if slot.give(question.normalised(chosen)) else "closed"

    def emit(self, kind: str, data: dict[str, Any]) -> None:
        """Record an event and wake the streams."""
        with self.lock:
            self.events.append({"type": kind, **data})
            if kind in ("done", "error"):
                self.finished = True
            wakers = list(self._wakers)
        for wake in wakers:
            wake()

    def stop_streams(self) -> None:
        """End every stream of this run after what it has sent (the server is shutting down)."""
        with self.lock:
            self.closing = True
            wakers = list(self._wakers)
        for wake in wakers:
            wake()

    def open_stream(self) -> bool:
        """Count one more stream of this run; False (nothing counted) when :data:`MAX_STREAMS` are open."""
        with self.lock:
            if self.streams >= MAX_STREAMS:
                return False
            self.streams += 1
            return True

    def close_stream(self) -> None:
        """A stream counted by :meth:`open_stream` has ended."""
        with self.lock:
            self.streams -= 1

    async def follow(self, keep_alive_s: float = KEEP_ALIVE_S) -> AsyncIterator[dict[str, Any] | None]:
        """Every event from the first, waiting on the running event loop for new ones.

        Yields ``None`` after ``keep_alive_s`` seconds of silence (a keep-alive for the HTTP stream);
        ends after ``done`` or ``error``, or once :meth:`stop_streams` is called.
        """
        loop = asyncio.get_running_loop()
        index = 0
        while True:
            woken = asyncio.Event()

            def wake(woken: asyncio.Event = woken) -> None:
                # RuntimeError: the loop is closed, so nobody is listening any more.
                with contextlib.suppress(RuntimeError):
                    loop.call_soon_threadsafe(woken.set)

            with self.lock:
                new = self.events[index:]
                finished, closing = self.finished, self.closing
                if not new and not finished and not closing:
                    self._wakers.add(wake)
            index += len(new)
            for event in new:
                yield event
            # Every event before `finished` was set is in `new`: nothing is left to send.
            if finished or closing:
                return
            if new:
                continue
            try:
                await asyncio.wait_for(woken.wait(), keep_alive_s)
            except TimeoutError:
                yield None
            finally:
                with self.lock:
                    self._wakers.discard(wake)


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
            self.worker(run.spec, run.emit, run.out_dir, run.ask if run.spec.ask else None)
            run.emit("done", {})
        except ConceptBotError as exc:
            run.emit("error", {"message": exc.message, "hint": exc.hint or ""})
        except Exception as exc:  # the page must hear about a bug instead of waiting forever
            traceback.print_exc()
            run.emit("error", {"message": f"internal error: {type(exc).__name__}: {exc}", "hint": ""})
        finally:
            self._model.release()

    def stop_streams(self) -> None:
        """End every run's event streams, so that a server shutting down need not wait for them."""
        with self._lock:
            runs = list(self._runs.values())
        for run in runs:
            run.stop_streams()

    def close(self) -> None:
        """Remove every run's pictures."""
        shutil.rmtree(self._root, ignore_errors=True)
