"""The ROS 2 node with real rclpy on loopback: plans, progress, errors, the queue, the timeout."""

from __future__ import annotations

import json
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from jsonschema import Draft202012Validator

from conceptbot.core.errors import ConceptBotError, ConfigError
from conceptbot.core.observe import Observer
from conceptbot.core.plan import Done, PickAndPlace, Plan, plan_schema
from conceptbot.core.scene import Scene
from conceptbot.ros2.client import send_request
from conceptbot.ros2.node import ConceptBotNode, NodeConfig
from tests.pipeline.fakes import properties_reply, urp_reply
from tests.ros2.harness import TINY_SCENE, wait_for

# The paper's pipeline without a graph on the fake backend: OPE per object (3), URP, then two
# voting steps of 5 completions. The fake cannot score options, so the goal planner is not used.
OPE = [properties_reply()] * 3
APPLE = "pick_and_place(apple, user)"


def _replies(action: str) -> list[str]:
    """One plan of three new objects (answers are cached by prompt: known objects ask nothing)."""
    return [*OPE, urp_reply([action]), *[action] * 5, *["done()"] * 5]


def _fake_config(tmp_path: Path, scene: Path, *actions: str) -> NodeConfig:
    """paper-nokg on a fake backend scripted for one plan per action, in order."""
    replies = tmp_path / "replies.json"
    replies.write_text(json.dumps([r for action in actions for r in _replies(action)]))
    return NodeConfig(system="paper-nokg", llm=f"fake:{replies}", scene=str(scene))


class HeldPlanner:
    """A planner double: each plan says it started, then waits for ``release`` (at most 20 s) and
    moves the first pickable object to the first destination, or raises what ``fail`` holds."""

    def __init__(self) -> None:
        self.release = threading.Event()
        self.started: list[str] = []
        self.fail: list[BaseException] = []

    def plan(
        self,
        request: str,
        scene: Scene,
        risk: bool = False,
        feedback: Any = None,
        observer: Observer | None = None,
    ) -> Plan:
        self.started.append(request)
        if observer is not None:
            observer.progress(f"thinking about {request}")
        if self.fail:
            raise self.fail.pop(0)
        self.release.wait(20)
        return Plan([PickAndPlace(scene.pickable[0], scene.destinations[0]), Done()])


def test_a_client_gets_progress_and_a_plan_that_fits_the_schema(
    start_node, tmp_path: Path, tiny_scene_file: Path
) -> None:
    running = start_node(_fake_config(tmp_path, tiny_scene_file, APPLE))
    progress: list[dict[str, Any]] = []
    # The real client (its own context, like another process) against the node.
    result = send_request(
        {"id": "r1", "request": "Bring me an apple"}, timeout_s=30, on_progress=progress.append
    )
    assert result["id"] == "r1" and result["ok"] is True
    Draft202012Validator(plan_schema()).validate(result["plan"])
    assert result["plan"]["plan"] == ["pick_and_place(apple, user)", "done()"]
    assert result["plan"]["trace"]["scene"] == "tiny"  # the node's default scene
    events = [p["module"] for p in progress if p["kind"] == "event"]
    assert events == ["ope", "urp", "step", "step"]
    ope = next(p["data"] for p in progress if p.get("module") == "ope")
    assert set(ope["objects"]) == {"apple", "sponge", "user"}
    messages = [p["message"] for p in progress if p["kind"] == "progress"]
    assert messages and all(isinstance(m, str) and m for m in messages)
    assert {p["id"] for p in progress} == {"r1"}
    # The node's own subscribers saw the same.
    assert running.wait_results(1)[0]["id"] == "r1"


def test_bad_requests_get_error_results_and_the_node_stays_up(
    start_node, tmp_path: Path, tiny_scene_file: Path
) -> None:
    running = start_node(_fake_config(tmp_path, tiny_scene_file, "pick_and_place(sponge, user)"))
    running.send("{not json")
    unknown = dict(TINY_SCENE, entity_states={"banana": "ripe"})
    running.send({"id": "u1", "request": "Bring me a banana", "scene": unknown})
    running.send({"id": "b1", "scene": "kitchen"})
    running.send({"id": "b2", "request": "hi", "scene": "no-such-scene"})
    running.send({"id": "ok", "request": "Bring me the sponge", "scene": TINY_SCENE})
    malformed, unknown_obj, missing, bad_scene, good = running.wait_results(5, timeout_s=30)
    assert malformed["ok"] is False and malformed["error"]["code"] == "bad_request"
    assert "not valid JSON" in malformed["error"]["message"] and malformed["id"].startswith("req-")
    assert unknown_obj["id"] == "u1" and unknown_obj["error"]["code"] == "unknown_object"
    assert "'banana' has a state or detection but is not in the scene" in unknown_obj["error"]["message"]
    assert (missing["id"], missing["error"]["code"]) == ("b1", "bad_request")
    assert "no 'request'" in missing["error"]["message"]
    assert (bad_scene["id"], bad_scene["error"]["code"]) == ("b2", "bad_request")
    assert "unknown demo scene 'no-such-scene'" in bad_scene["error"]["message"]
    assert "kitchen" in bad_scene["error"]["message"] and "scene itself" in bad_scene["error"]["hint"]
    assert good["id"] == "ok" and good["ok"] is True
    assert good["plan"]["plan"] == ["pick_and_place(sponge, user)", "done()"]
    assert {p["id"] for p in running.progress} == {"ok"}  # the bad ones were never planned


def test_two_requests_in_a_row_are_answered_in_order(
    start_node, tmp_path: Path, tiny_scene_file: Path
) -> None:
    config = _fake_config(tmp_path, tiny_scene_file, APPLE, "pick_and_place(cup, person)")
    running = start_node(config)
    running.send({"id": "first", "request": "Bring me an apple"})
    # Other objects: OPE asks about them (the first plan's answers are cached by prompt).
    cups = {"name": "cups", "pickable_objects": ["cup", "plate"], "destinations": ["person"]}
    running.send({"id": "second", "request": "Give the person a cup", "scene": cups})
    first, second = running.wait_results(2, timeout_s=30)
    assert (first["id"], second["id"]) == ("first", "second")
    assert first["plan"]["plan"] == [APPLE, "done()"]
    assert second["plan"]["plan"] == ["pick_and_place(cup, person)", "done()"]
    assert first["plan"]["trace"]["request"] == "Bring me an apple"
    assert second["plan"]["trace"]["scene"] == "cups"


def test_a_full_queue_answers_busy_at_once_and_the_queued_ones_in_order(start_node) -> None:
    planner = HeldPlanner()
    running = start_node(NodeConfig(scene="kitchen", queue_size=1), planner=planner)
    running.send({"id": "r1", "request": "one"})
    assert _until(lambda: planner.started == ["one"])  # r1 is being planned: the queue is empty
    running.send({"id": "r2", "request": "two"})  # waits in the queue
    running.send({"id": "r3", "request": "three"})  # finds it full
    busy = running.wait_results(1)[0]
    assert busy["id"] == "r3" and busy["error"]["code"] == "busy"
    assert "queue_size" in busy["error"]["hint"]
    planner.release.set()
    results = running.wait_results(3)
    assert [(r["id"], r["ok"]) for r in results] == [("r3", False), ("r1", True), ("r2", True)]
    assert planner.started == ["one", "two"]
    assert results[1]["plan"]["plan"][0].startswith("pick_and_place(")


def test_a_plan_over_the_timeout_is_answered_timeout_and_its_late_result_dropped(start_node) -> None:
    planner = HeldPlanner()
    running = start_node(NodeConfig(scene="kitchen", plan_timeout_s=0.3), planner=planner)
    running.send({"id": "slow", "request": "one"})
    late = running.wait_results(1)[0]
    assert late["id"] == "slow" and late["error"]["code"] == "timeout"
    assert "0.3 s" in late["error"]["message"]
    planner.release.set()  # the late plan finishes now, and is discarded
    running.send({"id": "next", "request": "two"})
    results = running.wait_results(2)
    assert [(r["id"], r["ok"]) for r in results] == [("slow", False), ("next", True)]
    assert not _until(lambda: len(running.results) > 2, timeout_s=0.5)  # no second answer for "slow"


def test_planner_failures_become_error_results(start_node) -> None:
    planner = HeldPlanner()
    planner.fail = [ConceptBotError("the model is gone", hint="install it"), RuntimeError("boom")]
    planner.release.set()
    running = start_node(NodeConfig(scene="kitchen"), planner=planner)
    running.send({"id": "a", "request": "one"})
    running.send({"id": "b", "request": "two"})
    running.send({"request": "three"})
    known, unexpected, fine = running.wait_results(3)
    assert known["error"] == {"code": "planner_error", "message": "the model is gone", "hint": "install it"}
    assert unexpected["error"]["code"] == "planner_error" and "boom" in unexpected["error"]["message"]
    assert fine["ok"] is True and fine["id"].startswith("req-")  # no id sent: one generated


def test_ros_parameters_override_the_defaults_and_are_checked(start_node) -> None:
    args = ("--ros-args", "-p", "scene:=toxic-1", "-p", "queue_size:=2", "-p", "plan_timeout_s:=5")
    running = start_node(NodeConfig(scene="kitchen"), planner=HeldPlanner(), ros_args=args)
    config = running.node.config
    assert (config.scene, config.queue_size, config.plan_timeout_s) == ("toxic-1", 2, 5.0)
    assert running.node.default_scene.name == "toxic-1"
    with pytest.raises(ConfigError, match="'queue_size' must be a whole number >= 1"):
        start_node(NodeConfig(queue_size=0), planner=HeldPlanner())
    with pytest.raises(ConfigError, match="unknown system 'gpt'"):
        start_node(NodeConfig(system="gpt"))


def test_shutting_down_answers_the_queued_requests(start_node) -> None:
    planner = HeldPlanner()
    running = start_node(NodeConfig(scene="kitchen"), planner=planner)
    running.send({"id": "r1", "request": "one"})
    assert _until(lambda: planner.started == ["one"])
    running.send({"id": "r2", "request": "two"})
    assert _until(lambda: running.node._queue.qsize() == 1)
    running.node.close()
    results = running.wait_results(2)
    assert {r["id"]: r["error"]["code"] for r in results} == {"r1": "planner_error", "r2": "planner_error"}
    assert "shut down" in results[0]["error"]["message"]
    planner.release.set()


def _until(done: Callable[[], bool], timeout_s: float = 10.0) -> bool:
    return wait_for(done, timeout_s)


def test_node_config_defaults_match_the_docs() -> None:
    assert NodeConfig() == NodeConfig("conceptbot", "", "kitchen", 4, 0.0)
    assert ConceptBotNode.__init__.__kwdefaults__["name"] == "conceptbot"


@pytest.mark.slow
def test_the_embedded_model_plans_a_request_through_the_node(
    start_node, smollm2_path: Path, tiny_scene_file: Path
) -> None:
    # The goal planner without a graph (no knowledge graph or embedder to install): the real
    # SmolLM2-135M scores its questions; which plan it makes is its business, the contract is ours.
    start_node(NodeConfig(system="nokg", llm=f"llamacpp:{smollm2_path}", scene=str(tiny_scene_file)))
    progress: list[dict[str, Any]] = []
    result = send_request(
        {"id": "real", "request": "Bring me an apple"}, timeout_s=600, on_progress=progress.append
    )
    assert result["id"] == "real" and result["ok"] is True, result
    plan = result["plan"]
    Draft202012Validator(plan_schema()).validate(plan)
    assert plan["plan"][-1] == "done()"
    assert set(plan["plan"]) <= {"pick_and_place(apple, user)", "pick_and_place(sponge, user)", "done()"}
    assert plan["trace"]["planner_kind"] == "goal" and plan["trace"]["goal"]["targets"][0]["named"] == [
        "apple"
    ]
    events = [p["module"] for p in progress if p["kind"] == "event"]
    assert events[:3] == ["goal", "decisions", "risk"] and events[3:] == ["step"] * len(plan["steps"])
    assert plan["usage"]["total"]["prompt_tokens"] > 0
