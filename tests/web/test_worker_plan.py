"""The page's plan event: what the goal planner's plan carries to the page, from a real system."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from conceptbot.core.scene import scene_from_dict
from conceptbot.models.fake import FakeLLM
from conceptbot.pipeline.conceptbot import ConceptBot
from conceptbot.web.runs import RunSpec
from conceptbot.web.worker import make_worker

SCENE = {"name": "tiny", "objects": ["apple", "sponge", "user"], "pickable_objects": ["apple", "sponge"]}


def test_the_plan_event_says_whose_conformal_thresholds_it_asked_by(tmp_path: Path) -> None:
    events: list[tuple[str, dict[str, Any]]] = []
    prior, yes, no = [-1.0, -1.0], [-0.1, -3.0], [-3.0, -0.1]
    names, neutral = [-1.0, -3.0], [-2.0, -2.0]  # the name ranking (apple, sponge), then neutral
    llm = FakeLLM(scores=[prior, yes, no, names, neutral, prior, no, prior, yes], model="my-model")

    def systems(config: str, backend: str) -> Any:
        return ConceptBot(llm, None, "urp", planner="goal")

    scene = scene_from_dict({**SCENE, "destinations": ["user"]})
    spec = RunSpec(request="Bring me something to eat", scene=scene, config="urp", backend="fake")
    make_worker(systems, can_simulate=False)(spec, lambda kind, data: events.append((kind, data)), tmp_path)
    plans = [data for kind, data in events if kind == "plan"]
    assert len(plans) == 1 and plans[0]["plan"][-1] == "done()"
    assert isinstance(plans[0]["confidence"], float)
    assert plans[0]["calibration"] == {
        "coverage": 0.9,
        "model": "fake:my-model",
        "fitted_for": "qwen2.5-coder-1.5b",
        "source": "shipped",
        "own": False,
    }
