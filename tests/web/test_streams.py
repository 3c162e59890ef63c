"""Event streams on a real server: many open streams of one run leave the other endpoints free, a
run takes a bounded number of them, and they end when the server stops."""

from __future__ import annotations

import asyncio
import json
import threading
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx
import pytest
import uvicorn

from conceptbot.scenes import load_demo_scene
from conceptbot.web import runs
from conceptbot.web.app import create_app, local_hosts
from conceptbot.web.runs import RunManager
from conceptbot.web.server import bind

RUN = {"request": "Give my son scissors to cut paper", "scene": "example-scissors"}
SPEC = runs.RunSpec(RUN["request"], load_demo_scene("example-scissors"), "conceptbot", "fake")
# Generous: an answer comes in milliseconds when nothing blocks it. A stream that held a worker
# thread kept it until its 15 s keep-alive, so with more streams than threads this did not answer.
TIMEOUT_S = 10.0


def held_worker(release: threading.Event) -> runs.Worker:
    """A worker whose run says it is thinking and then holds until ``release`` is set (at most
    60 s: longer than any time-out here, so a run never ends by itself during a test)."""

    def worker(
        spec: runs.RunSpec, emit: Callable[[str, dict[str, Any]], None], out_dir: Path, ask=None
    ) -> None:
        emit("status", {"message": "thinking"})
        release.wait(60)

    return worker


@dataclass
class Live:
    """A server on a free port of 127.0.0.1 whose runs hold until ``release`` is set."""

    url: str
    manager: RunManager
    release: threading.Event

    @contextmanager
    def client(self) -> Iterator[httpx.Client]:
        """A client with the page's session cookie (many connections allowed)."""
        limits = httpx.Limits(max_connections=200, max_keepalive_connections=0)
        with httpx.Client(base_url=self.url, timeout=TIMEOUT_S, limits=limits) as client:
            assert client.get("/").status_code == 200
            yield client


@contextmanager
def live_server(tmp_path: Path) -> Iterator[Live]:
    """Serve the app with uvicorn in a thread (not the main one: uvicorn leaves signals alone)."""
    release = threading.Event()
    manager = RunManager(held_worker(release))
    sock = bind("127.0.0.1", 0)
    port = sock.getsockname()[1]
    app = create_app(
        manager,
        backends=["fake"],
        results_dir=tmp_path / "results",
        can_simulate=False,
        allowed_hosts=local_hosts("127.0.0.1", port),
    )
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning", timeout_graceful_shutdown=2))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    try:
        for _ in range(200):
            if server.started:
                break
            threading.Event().wait(0.05)
        assert server.started
        yield Live(f"http://127.0.0.1:{port}", manager, release)
    finally:
        release.set()
        server.should_exit = True
        thread.join(10)
        manager.close()


@dataclass
class Stream:
    """An open event stream and what is left of its lines."""

    status_code: int
    lines: Iterator[str]

    def events(self) -> list[dict]:
        """The rest of the stream's events, to its end."""
        return [json.loads(line[6:]) for line in self.lines if line.startswith("data: ")]


def open_stream(stack: ExitStack, client: httpx.Client, run_id: str) -> Stream:
    """Open the run's event stream; once open, read up to its first event (the run is under way)."""
    response = stack.enter_context(client.stream("GET", f"/api/runs/{run_id}/events"))
    lines = response.iter_lines()
    if response.status_code == 200:
        first = next(line for line in lines if line.startswith("data: "))
        assert json.loads(first[6:]) == {"type": "status", "message": "thinking"}
    return Stream(response.status_code, lines)


def test_many_streams_of_a_run_leave_the_other_endpoints_free(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # More streams than anyio's 40 worker threads, and no cap in the way: what is tested is that
    # a waiting stream holds no thread.
    monkeypatch.setattr(runs, "MAX_STREAMS", 100, raising=False)
    with live_server(tmp_path) as live, live.client() as client, ExitStack() as streams:
        run_id = client.post("/api/runs", json=RUN).json()["id"]
        opened = [open_stream(streams, client, run_id) for _ in range(50)]
        assert [r.status_code for r in opened] == [200] * 50
        # While all 50 are open and waiting, every other endpoint answers.
        assert client.get("/api/options").json()["backends"] == ["fake"]
        assert client.get("/").status_code == 200
        assert client.post("/api/runs", json=RUN).status_code == 409  # the run is still going
        assert not live.manager.get(run_id).finished
        live.release.set()
        # ... and the streams still get the rest of the run.
        assert opened[0].events() == [{"type": "done"}]


def test_a_run_serves_a_bounded_number_of_streams(tmp_path: Path) -> None:
    with live_server(tmp_path) as live, live.client() as client:
        run_id = client.post("/api/runs", json=RUN).json()["id"]
        with ExitStack() as streams:
            opened = [open_stream(streams, client, run_id) for _ in range(runs.MAX_STREAMS)]
            assert all(r.status_code == 200 for r in opened)
            refused = client.get(f"/api/runs/{run_id}/events")
            assert refused.status_code == 429
            assert "event streams of this run are open already" in refused.json()["detail"]
            assert client.get("/api/options").status_code == 200
        # The streams closed by the client are counted off again (the server notices them go).
        for _ in range(100):
            if live.manager.get(run_id).streams == 0:
                break
            threading.Event().wait(0.05)
        with ExitStack() as streams:
            assert open_stream(streams, client, run_id).status_code == 200


def test_stop_streams_ends_the_waiting_streams() -> None:
    """What a stopping server calls first, so that it need not wait for a run to finish."""
    manager = RunManager(held_worker(threading.Event()))
    try:
        run = manager.start("session", SPEC)

        async def follow() -> list[dict | None]:
            seen: list[dict | None] = []
            async for event in run.follow(keep_alive_s=30):
                seen.append(event)
                if len(seen) == 1:
                    # From another thread, as a signal-driven shutdown or a worker would.
                    threading.Thread(target=manager.stop_streams).start()
            return seen

        seen = asyncio.run(asyncio.wait_for(follow(), TIMEOUT_S))
        assert seen == [{"type": "status", "message": "thinking"}]
        assert not run.finished  # the run itself goes on; only its streams ended
    finally:
        manager.close()


def test_follow_sends_keep_alives_while_a_run_is_silent() -> None:
    release = threading.Event()
    manager = RunManager(held_worker(release))
    try:
        run = manager.start("session", SPEC)

        async def follow() -> list[dict | None]:
            seen: list[dict | None] = []
            async for event in run.follow(keep_alive_s=0.05):
                seen.append(event)
                if event is None:
                    release.set()  # one keep-alive is enough: let the run finish
            return seen

        seen = asyncio.run(asyncio.wait_for(follow(), TIMEOUT_S))
        assert seen[0] == {"type": "status", "message": "thinking"} and None in seen
        assert seen[-1] == {"type": "done"}
    finally:
        manager.close()
