"""The node's Plan action with real rclpy on loopback: goals, feedback, cancel, the queue, the Answer
service, scenes from a detection topic and malformed scenes."""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Callable
from typing import Any

import pytest

from conceptbot.core.observe import Observer
from conceptbot.core.plan import Done, PickAndPlace, Plan
from conceptbot.core.scene import Scene
from conceptbot.ros2.node import NodeConfig
from tests.ros2.harness import Running, wait_for
from tests.ros2.test_asking import CHOOSE, AskingPlanner

action = pytest.importorskip("rclpy.action")
interfaces = pytest.importorskip("conceptbot_interfaces.action", reason="scripts/build_interfaces.sh not run")
from conceptbot_interfaces.action import Plan as PlanAction  # noqa: E402
from conceptbot_interfaces.msg import Detection  # noqa: E402
from conceptbot_interfaces.msg import Scene as SceneMsg  # noqa: E402
from conceptbot_interfaces.srv import Answer  # noqa: E402

SUCCEEDED, CANCELED, ABORTED = 4, 5, 6  # action_msgs/GoalStatus


class GatedPlanner:
    """Says "first", waits for ``release``, says "second" (where a cancel stops it), then moves the
    first pickable object to the first destination. ``ran`` lists the steps that ran to the end."""

    def __init__(self) -> None:
        self.release = threading.Event()
        self.ran: list[str] = []
        self.scenes: list[Scene] = []

    def plan(
        self,
        request: str,
        scene: Scene,
        risk: bool = False,
        feedback: Any = None,
        observer: Observer | None = None,
    ) -> Plan:
        self.scenes.append(scene)
        assert observer is not None
        observer.progress("first")
        self.ran.append(f"{request}: first")
        self.release.wait(20)
        observer.progress("second")
        self.ran.append(f"{request}: second")
        return Plan([PickAndPlace(scene.pickable[0], scene.destinations[0]), Done()], confidence=0.75)


class Goals:
    """An action client on the test's client node."""

    def __init__(self, running: Running) -> None:
        self.client = action.ActionClient(running.client, PlanAction, "/conceptbot/plan")
        assert self.client.wait_for_server(timeout_sec=10.0), "no Plan action server"
        self.feedback: list[Any] = []

    def send(self, goal: Any) -> Any:
        """Send ``goal``; its handle once accepted or rejected."""
        sent = self.client.send_goal_async(goal, feedback_callback=lambda m: self.feedback.append(m.feedback))
        assert wait_for(sent.done, 10.0), "the goal was neither accepted nor rejected"
        return sent.result()

    def result(self, handle: Any, timeout_s: float = 20.0) -> Any:
        """The goal's final (status, result)."""
        got = handle.get_result_async()
        assert wait_for(got.done, timeout_s), "no result"
        return got.result().status, got.result().result


def _goal(request: str = "give me the apple", **fields: Any) -> Any:
    return PlanAction.Goal(request=request, scene_name=fields.pop("scene_name", "toxic-1"), **fields)


def test_a_goal_gets_feedback_then_typed_actions(start_node: Callable[..., Running]) -> None:
    planner = GatedPlanner()
    planner.release.set()
    goals = Goals(start_node(NodeConfig(), planner=planner))
    handle = goals.send(_goal())
    assert handle.accepted
    status, result = goals.result(handle)
    assert status == SUCCEEDED and result.ok and not result.refused
    scene = planner.scenes[0]
    assert [(m.object, m.destination) for m in result.actions] == [(scene.pickable[0], scene.destinations[0])]
    assert result.confidence == pytest.approx(0.75)
    assert json.loads(result.plan_json)["plan"][0].startswith("pick_and_place(")
    assert wait_for(lambda: any(f.message == "second" for f in goals.feedback), 5.0)
    assert [f.message for f in goals.feedback][:2] == ["planning in toxic-1", "first"]


def test_a_cancelled_goal_stops_between_pieces_of_work(start_node: Callable[..., Running]) -> None:
    planner = GatedPlanner()
    goals = Goals(start_node(NodeConfig(), planner=planner))
    handle = goals.send(_goal("cancel me"))
    assert wait_for(lambda: planner.ran == ["cancel me: first"], 10.0)
    cancelling = handle.cancel_goal_async()
    assert wait_for(cancelling.done, 10.0) and cancelling.result().goals_canceling
    planner.release.set()  # the piece of work in flight finishes; nothing after it runs
    status, result = goals.result(handle)
    assert status == CANCELED and result.cancelled and not result.actions
    assert planner.ran == ["cancel me: first"]


def test_a_second_goal_waits_and_one_beyond_the_queue_is_rejected(start_node: Callable[..., Running]) -> None:
    planner = GatedPlanner()
    goals = Goals(start_node(NodeConfig(queue_size=1), planner=planner))
    first = goals.send(_goal("one"))
    assert wait_for(lambda: planner.ran == ["one: first"], 10.0)
    second = goals.send(_goal("two"))
    third = goals.send(_goal("three"))
    assert first.accepted and second.accepted and not third.accepted
    planner.release.set()
    assert goals.result(first)[0] == SUCCEEDED and goals.result(second)[0] == SUCCEEDED
    assert planner.ran == ["one: first", "one: second", "two: first", "two: second"]


def test_a_question_is_answered_through_the_service(start_node: Callable[..., Running]) -> None:
    running = start_node(NodeConfig(), planner=AskingPlanner(CHOOSE))
    goals = Goals(running)
    answer = running.client.create_client(Answer, "/conceptbot/answer_question")
    assert answer.wait_for_service(timeout_sec=10.0)
    handle = goals.send(_goal("something to wipe a spill", ask=True))
    assert wait_for(lambda: any(f.stage == "question" for f in goals.feedback), 10.0)
    asked = next(f for f in goals.feedback if f.stage == "question").question
    assert asked.kind == "choose" and list(asked.options) == ["sponge", "towel"]
    goal_id = bytes(handle.goal_id.uuid).hex()

    def call(text: str) -> Any:
        reply = answer.call_async(Answer.Request(goal_id=goal_id, answer=text))
        assert wait_for(reply.done, 10.0)
        return reply.result()

    assert call("the kettle").error_code == "bad_answer"  # dropped; the question stays open
    assert call("sponge").accepted
    status, result = goals.result(handle)
    assert status == SUCCEEDED
    assert [m.object for m in result.actions] == ["apple", "sponge"]
    assert call("yes").error_code == "no_question"  # the goal has ended: no question is open


def _scene_msg(stamp_s: float | None = None) -> Any:
    msg = SceneMsg(
        detections=[
            Detection(name="red mug", confidence=0.9, box_px=[10.0, 10.0, 60.0, 70.0]),
            Detection(name="tray", confidence=0.8),
        ],
        destinations=["tray", "user"],
    )
    if stamp_s is not None:
        msg.stamp.sec, msg.stamp.nanosec = int(stamp_s), int((stamp_s % 1) * 1e9)
    return msg


def test_goals_without_a_scene_use_the_latest_detections(start_node: Callable[..., Running]) -> None:
    planner = GatedPlanner()
    planner.release.set()
    running = start_node(NodeConfig(detections="/detector/scene", detections_max_age_s=3.0), planner=planner)
    goals = Goals(running)
    _, result = goals.result(goals.send(_goal(scene_name="")))
    assert result.error_code == "bad_goal" and "no detections" in result.error_message
    publisher = running.client.create_publisher(SceneMsg, "/detector/scene", 10)
    assert wait_for(lambda: publisher.get_subscription_count() > 0, 10.0)
    publisher.publish(_scene_msg())
    assert wait_for(lambda: running.node.latest is not None and running.node.latest._latest is not None, 10.0)
    status, result = goals.result(goals.send(_goal("the mug to the tray", scene_name="")))
    assert status == SUCCEEDED
    assert [(m.object, m.destination) for m in result.actions] == [("red mug", "tray")]
    found = planner.scenes[-1].get("red mug")
    assert found is not None and found.confidence == pytest.approx(0.9) and found.bbox_px == (10, 10, 60, 70)
    publisher.publish(_scene_msg(stamp_s=time.time() - 60))
    assert wait_for(lambda: "old" in _error(goals), 10.0)


def _error(goals: Goals) -> str:
    return goals.result(goals.send(_goal(scene_name="")))[1].error_message


def test_a_malformed_scene_is_one_clear_error_and_the_next_goal_is_served(
    start_node: Callable[..., Running],
) -> None:
    planner = GatedPlanner()
    planner.release.set()
    goals = Goals(start_node(NodeConfig(), planner=planner))
    bad = [
        _goal(scene_name="", scene_json="{not json"),
        _goal(scene_name="no-such-scene"),
        PlanAction.Goal(request="x", scene=SceneMsg(detections=[Detection(name="cup", confidence=3.0)])),
        _goal(request="   "),
        _goal(config="saycan"),
    ]
    for goal in bad:
        status, result = goals.result(goals.send(goal))
        assert status == ABORTED and not result.ok and result.error_code == "bad_goal", result
        assert result.error_message and "Traceback" not in result.error_message
    status, result = goals.result(goals.send(_goal()))
    assert status == SUCCEEDED and result.ok


@pytest.mark.slow
def test_the_embedded_model_plans_a_goal_and_a_cancel_stops_it(
    start_node: Callable[..., Running], smollm2_path: Any, tiny_scene_file: Any
) -> None:
    # The goal planner without a graph on the real SmolLM2-135M (as the topic test): the plan is the
    # model's business, the action's contract is ours.
    config = NodeConfig(system="nokg", llm=f"llamacpp:{smollm2_path}", scene=str(tiny_scene_file))
    goals = Goals(start_node(config))
    handle = goals.send(PlanAction.Goal(request="Bring me an apple"))
    status, result = goals.result(handle, timeout_s=600)
    assert status == SUCCEEDED and result.ok, result
    assert {(m.object, m.destination) for m in result.actions} <= {("apple", "user"), ("sponge", "user")}
    assert json.loads(result.plan_json)["trace"]["planner_kind"] == "goal"
    stages = [f.stage for f in goals.feedback]
    assert {"goal", "decisions", "risk"} <= set(stages)

    goals.feedback.clear()
    handle = goals.send(PlanAction.Goal(request="Bring me the sponge"))
    assert wait_for(lambda: any(f.stage == "goal" for f in goals.feedback), 600)
    handle.cancel_goal_async()
    status, result = goals.result(handle, timeout_s=600)
    assert status == CANCELED and result.cancelled and not result.actions
    assert "risk" not in [f.stage for f in goals.feedback]  # nothing after the cancel ran


def test_a_queued_goal_that_is_cancelled_is_never_planned(start_node: Callable[..., Running]) -> None:
    planner = GatedPlanner()
    goals = Goals(start_node(NodeConfig(), planner=planner))
    first = goals.send(_goal("one"))
    assert wait_for(lambda: planner.ran == ["one: first"], 10.0)
    queued = goals.send(_goal("two"))
    cancelling = queued.cancel_goal_async()
    assert wait_for(cancelling.done, 10.0) and cancelling.result().goals_canceling
    planner.release.set()
    assert goals.result(first)[0] == SUCCEEDED
    status, result = goals.result(queued)
    assert status == CANCELED and result.cancelled
    assert planner.ran == ["one: first", "one: second"]  # "two" never started
    assert goals.result(goals.send(_goal("three")))[0] == SUCCEEDED  # the worker is still there
