"""A web app over the real ConceptBot pipeline with a scripted LLM and an in-memory graph."""

from __future__ import annotations

import json
import threading
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from conceptbot.core.plan import valid_actions
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.pipeline.conceptbot import ConceptBot
from conceptbot.pipeline.retrieval import RelationRetriever
from conceptbot.scenes import load_demo_scene
from conceptbot.web.app import create_app
from conceptbot.web.runs import RunManager
from conceptbot.web.worker import make_worker
from tests.pipeline.fakes import DictGraph, risk_reply, urp_reply

REQUEST = "Give my son scissors to cut paper"


def held_worker(release: threading.Event) -> Callable[..., None]:
    """A worker whose run says it is thinking and then holds until ``release`` is set (at most 10 s)."""

    def worker(spec: Any, emit: Callable[..., None], out_dir: Path, ask: Any = None) -> None:
        emit("status", {"message": "thinking"})
        release.wait(10)

    return worker


def scripted_bot() -> ConceptBot:
    """ConceptBot on the scissors example (a knife and scissors: OPE uses the Risk Index): one risk
    reply per object, URP's keywords and commands, then the planner's scores for two steps."""
    scene = load_demo_scene("example-scissors")
    replies = [risk_reply(4 if o in ("scissors", "knife") else 1, []) for o in scene.names]
    replies += ['{"keywords": ["scissors", "son"]}', urp_reply(["pick_and_place(safety scissors, child)"])]
    actions = [str(a) for a in valid_actions(scene)]
    first, second = [-5.0] * len(actions), [-5.0] * len(actions)
    first[actions.index("pick_and_place(safety scissors, child)")] = 0.0
    second[actions.index("done()")] = 0.0
    llm = FakeLLM(replies, scores=[first, second])
    return ConceptBot(
        llm, RelationRetriever(DictGraph(), FakeEmbedder(), theta=0.1), "conceptbot", planner="steps"
    )


@pytest.fixture
def make_client(tmp_path: Path) -> Callable[..., TestClient]:
    managers: list[RunManager] = []

    def make(
        worker: Any = None,
        backends: list[str] | None = None,
        can_simulate: bool = False,
        allowed_hosts: Iterable[str] = ("testserver",),
        base_url: str = "http://testserver",
    ) -> TestClient:
        """A client with the session cookie. The app answers only ``allowed_hosts``: TestClient's
        own "testserver" unless a test gives the hosts of a real address (with its ``base_url``)."""
        worker = worker or make_worker(lambda config, backend: scripted_bot(), can_simulate=False)
        manager = RunManager(worker)
        managers.append(manager)
        app = create_app(
            manager,
            backends=backends or ["llamacpp:qwen2.5-coder-1.5b", "llamacpp:smollm2-135m"],
            results_dir=tmp_path / "results",
            can_simulate=can_simulate,
            allowed_hosts=allowed_hosts,
        )
        client = TestClient(app, base_url=base_url)
        assert client.get("/").status_code == 200  # the session cookie
        return client

    yield make
    for manager in managers:
        manager.close()


def events_of(client: TestClient, run_id: str) -> list[dict[str, Any]]:
    """Read a run's event stream to its end."""
    events = []
    with client.stream("GET", f"/api/runs/{run_id}/events") as response:
        assert response.headers["content-type"].startswith("text/event-stream")
        for line in response.iter_lines():
            if line.startswith("data: "):
                events.append(json.loads(line[6:]))
    return events
