"""A Plan action client: send one goal to a ConceptBot node, follow its feedback, answer its
questions, cancel it on Ctrl-C. What ``conceptbot ros2 send --action`` runs, and the shape of any
client (a behaviour tree's action node does the same through its own library)::

    result = send_goal("Give me something to drink", scene_name="kitchen")
    result["ok"], result["actions"]
"""

from __future__ import annotations

import json
import uuid
from collections.abc import Callable
from typing import Any

import rclpy
from conceptbot_interfaces.action import Plan
from conceptbot_interfaces.srv import Answer
from rclpy.action import ActionClient
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.signals import SignalHandlerOptions

from conceptbot.core.errors import ConceptBotError
from conceptbot.ros2.client import DRAIN_S, spin_until, topic_base

STATUS = {4: "succeeded", 5: "canceled", 6: "aborted"}  # action_msgs/GoalStatus
CANCEL_WAIT_S = 60.0  # a cancel lets the model call in flight finish


def result_dict(status: int, result: Any) -> dict[str, Any]:
    """A Plan result as plain data (what ``send --action`` prints)."""
    return {
        "status": STATUS.get(status, str(status)),
        "ok": result.ok,
        "cancelled": result.cancelled,
        "refused": result.refused,
        "reason": result.reason,
        "confidence": result.confidence,
        "actions": [{"object": m.object, "destination": m.destination} for m in result.actions],
        "plan": json.loads(result.plan_json) if result.plan_json else None,
        "error": {"code": result.error_code, "message": result.error_message} if result.error_code else None,
    }


def send_goal(
    request: str,
    *,
    scene_name: str = "",
    scene_json: str = "",
    node_name: str = "conceptbot",
    timeout_s: float = 300.0,
    discovery_s: float = 10.0,
    on_feedback: Callable[[Any], None] | None = None,
    answer: Callable[[Any], str | None] | None = None,
) -> dict[str, Any]:
    """Send one Plan goal to the node ``node_name`` and return its result (:func:`result_dict`).

    Args:
        request: What the person asked for.
        scene_name: A demo scene's name, or "" (the node's detections or default scene).
        scene_json: A scene file's JSON, or "".
        timeout_s: Seconds to wait for the result once the goal is accepted.
        discovery_s: Seconds to wait for the node's action server.
        on_feedback: Called with each feedback message.
        answer: Where given, the goal asks for questions; called with each question (a
            ``conceptbot_interfaces/msg/Question``), its answer goes to the node (None: no answer).

    Raises:
        ConceptBotError: No action server, the goal rejected, or no result within ``timeout_s``.
        KeyboardInterrupt: A second Ctrl-C while the goal was being cancelled.
    """
    base = topic_base(node_name)
    context = Context()
    # No rclpy signal handler (it shuts the context down): Ctrl-C raises KeyboardInterrupt, which cancels.
    rclpy.init(context=context, signal_handler_options=SignalHandlerOptions.NO)
    try:
        node = rclpy.create_node(f"conceptbot_goal_{uuid.uuid4().hex[:8]}", context=context)
        client = ActionClient(node, Plan, f"{base}/plan")
        answers = node.create_client(Answer, f"{base}/answer_question")
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        try:
            if not spin_until(executor, client.server_is_ready, discovery_s):
                raise ConceptBotError(
                    f"no ConceptBot Plan action at {base}/plan",
                    hint="start one with `conceptbot ros2 node` (same ROS_DOMAIN_ID, same --name)",
                )
            pending: list[Any] = []

            def feedback(msg: Any) -> None:
                if on_feedback is not None:
                    on_feedback(msg.feedback)
                if msg.feedback.stage == "question" and answer is not None:
                    pending.append(msg.feedback.question)

            goal = Plan.Goal(
                request=request, scene_name=scene_name, scene_json=scene_json, ask=answer is not None
            )
            sent = client.send_goal_async(goal, feedback_callback=feedback)
            spin_until(executor, sent.done, discovery_s)
            handle = sent.result() if sent.done() else None
            if handle is None or not handle.accepted:
                raise ConceptBotError("the node rejected the goal", hint="its queue is full: try again later")
            goal_id = bytes(handle.goal_id.uuid).hex()
            got = handle.get_result_async()

            def done() -> bool:
                while pending and answer is not None:
                    said = answer(pending.pop(0))
                    if said is not None:
                        answers.call_async(Answer.Request(goal_id=goal_id, answer=said))
                return got.done()

            try:
                finished = spin_until(executor, done, timeout_s)
            except KeyboardInterrupt:
                handle.cancel_goal_async()
                finished = spin_until(executor, got.done, CANCEL_WAIT_S)
            if not finished:
                raise ConceptBotError(
                    f"no result for the goal within {timeout_s:g} s", hint="raise --timeout; the goal runs on"
                )
            # Feedback and result travel apart: take the feedback already on its way.
            spin_until(executor, lambda: False, DRAIN_S)
            return result_dict(got.result().status, got.result().result)
        finally:
            executor.shutdown()
            node.destroy_node()
    finally:
        context.try_shutdown()
