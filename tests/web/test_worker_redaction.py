"""Issue 32, item 7: a run's events never carry the backend spec's credentials."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from conceptbot.scenes import load_demo_scene
from conceptbot.web.runs import RunSpec
from conceptbot.web.worker import make_worker


class StopRunError(Exception):
    """Ends the run once the first event is out (no system needs to be built)."""


def test_the_loading_event_shows_the_backend_redacted(tmp_path: Path) -> None:
    events: list[tuple[str, dict[str, Any]]] = []

    def systems(config: str, backend: str) -> Any:
        assert "urlsecret77" in backend  # the system itself gets the real spec
        raise StopRunError

    spec = RunSpec(
        request="hand me the apple",
        scene=load_demo_scene("example-scissors"),
        config="conceptbot",
        backend="openai-compatible:http://bob:pw-secret-9@127.0.0.1:9/v1?token=urlsecret77#m",
    )
    with pytest.raises(StopRunError):
        make_worker(systems, can_simulate=False)(
            spec, lambda kind, data: events.append((kind, data)), tmp_path
        )
    assert events == [
        ("status", {"message": "loading conceptbot on openai-compatible:http://127.0.0.1:9/v1?token=***#m"})
    ]
