"""The web page's and the ROS 2 node's event payloads are the JSON they have always been: the events
of two fixed plans (the paper's step pipeline, the goal planner), serialised at each edge, are
byte-identical to the files recorded before events became typed (``tests/golden/``)."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import pytest

from conceptbot.core.plan import Plan
from conceptbot.models.fake import FakeLLM
from conceptbot.ros2.protocol import event_payload, progress_payload
from conceptbot.web.worker import PageObserver
from tests.pipeline.fakes import risk_reply, spill_scene, urp_reply
from tests.pipeline.goal_planner.test_planner import NAMES, NEUTRAL, PRIOR, SAFE, SCENE, UNSAFE
from tests.pipeline.test_observe import _bot

GOLDEN = Path(__file__).parent / "golden"


class _TopicLike:
    """What the ROS 2 node's observer publishes, without a node: the payload texts."""

    def __init__(self) -> None:
        self.sent: list[str] = []

    def progress(self, message: str) -> None:
        self.sent.append(json.dumps(progress_payload("r1", message)))

    def event(self, name: str, part: Any) -> None:
        self.sent.append(json.dumps(event_payload("r1", name, part)))


def _step_plan(observer: Any) -> Plan:
    replies = [risk_reply(4, [("user", 3)]) if i == 2 else risk_reply(1) for i in range(5)]
    replies += [
        '{"keywords": ["chips", "spill"]}',
        urp_reply(["pick_and_place(chips, user)", "pick_and_place(sponge, user)"]),
    ]
    scores = [[-5.0] * 7 for _ in range(3)]
    scores[0][1], scores[1][3], scores[2][6] = 0.0, 0.0, 0.0
    return _bot(FakeLLM(replies, scores=scores), "conceptbot", "steps").plan(
        "Bring me chips and something to wipe a spill", spill_scene(), observer=observer
    )


def _goal_plan(observer: Any) -> Plan:
    scores = [NAMES, NEUTRAL, PRIOR, UNSAFE, PRIOR, SAFE, PRIOR, SAFE]
    bot = _bot(FakeLLM(scores=scores), "urp", "goal")
    return bot.plan("Give my son something to cut paper", SCENE, observer=observer)


def _web(run: Any) -> list[str]:
    sent: list[str] = []
    run(PageObserver(lambda name, data: sent.append(json.dumps({"event": name, **data}))))
    return sent


def _ros(run: Any) -> list[str]:
    topic = _TopicLike()
    run(topic)
    return topic.sent


@pytest.mark.parametrize("edge", ["web", "ros2"])
@pytest.mark.parametrize("plan", ["steps", "goal"])
def test_event_payloads_are_byte_identical_to_the_recorded_ones(edge: str, plan: str) -> None:
    run = {"steps": _step_plan, "goal": _goal_plan}[plan]
    sent = {"web": _web, "ros2": _ros}[edge](run)
    path = GOLDEN / f"events-{edge}-{plan}.txt"
    if os.environ.get("RECORD_GOLDEN"):
        path.write_text("\n".join(sent) + "\n", encoding="utf-8")
    assert "\n".join(sent) + "\n" == path.read_text(encoding="utf-8")
    assert len(sent) > 3


@pytest.mark.parametrize("plan", ["steps", "goal"])
def test_plan_json_is_byte_identical_to_the_recorded_one(plan: str) -> None:
    data = {"steps": _step_plan, "goal": _goal_plan}[plan](None).to_dict()
    for usage in data["usage"].values():
        usage["latency_s"] = 0.0  # wall time
    text = json.dumps(data, indent=2) + "\n"
    path = GOLDEN / f"plan-{plan}.json"
    if os.environ.get("RECORD_GOLDEN"):
        path.write_text(text, encoding="utf-8")
    assert text == path.read_text(encoding="utf-8")
