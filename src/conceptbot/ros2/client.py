"""A small ROS 2 client: publish one request to a ConceptBot node and wait for its result.

What ``conceptbot ros2 send`` runs, and the shape of any client: subscribe to the node's
``progress`` and ``result`` topics, wait until the node is discovered (a message published before
that reaches nobody), publish the request, keep the replies that carry its id::

    result = send_request({"request": "Give me something to drink", "scene": "kitchen"})
    result["ok"], result["plan"]["plan"]
"""

from __future__ import annotations

import json
import time
import uuid
from collections.abc import Callable
from typing import Any

import rclpy
from rclpy.context import Context
from rclpy.exceptions import NameValidationException
from rclpy.executors import SingleThreadedExecutor
from rclpy.validate_full_topic_name import validate_full_topic_name
from std_msgs.msg import String

from conceptbot.core.errors import ConceptBotError, ConfigError
from conceptbot.ros2 import qos
from conceptbot.ros2.protocol import encode

DRAIN_S = 0.2
"""Seconds to keep taking progress messages after the result came (they are already queued)."""


def send_request(
    payload: dict[str, Any],
    *,
    node_name: str = "conceptbot",
    timeout_s: float = 300.0,
    discovery_s: float = 10.0,
    on_progress: Callable[[dict[str, Any]], None] | None = None,
) -> dict[str, Any]:
    """Send one request to the node ``node_name`` and return its result payload.

    Args:
        payload: The request (``request``, optionally ``scene`` and ``id``; an id is added when
            missing, to pick this request's replies out of the topics).
        node_name: The node's name (its topics are ``/<node_name>/request`` and so on).
        timeout_s: Seconds to wait for the result once the request is sent.
        discovery_s: Seconds to wait for the node to be discovered.
        on_progress: Called with each progress payload of this request (messages and events).

    Returns:
        The result payload: ``{"id", "ok": true, "plan"}`` or ``{"id", "ok": false, "error"}``.

    Raises:
        ConfigError: ``node_name`` cannot name a node's topics (``bad name!``).
        ConceptBotError: No node is found on the topics, or no result comes within ``timeout_s``.
    """
    base = topic_base(node_name)
    payload = {"id": f"send-{uuid.uuid4().hex[:12]}", **payload}
    context = Context()
    rclpy.init(context=context)
    try:
        node = rclpy.create_node(f"conceptbot_client_{uuid.uuid4().hex[:8]}", context=context)
        results: list[dict[str, Any]] = []

        def on_result(msg: String) -> None:
            data = _decode(msg)
            if data.get("id") == payload["id"]:
                results.append(data)

        def on_progress_msg(msg: String) -> None:
            data = _decode(msg)
            if on_progress is not None and data.get("id") == payload["id"]:
                on_progress(data)

        publisher = node.create_publisher(String, f"{base}/request", qos.REQUESTS)
        progress_sub = node.create_subscription(String, f"{base}/progress", on_progress_msg, qos.REPLIES)
        result_sub = node.create_subscription(String, f"{base}/result", on_result, qos.REPLIES)
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        try:
            found = spin_until(
                executor,
                lambda: (
                    publisher.get_subscription_count() > 0
                    and result_sub.get_publisher_count() > 0
                    and progress_sub.get_publisher_count() > 0
                ),
                discovery_s,
            )
            if not found:
                raise ConceptBotError(
                    f"no ConceptBot node answers on {base}/request",
                    hint="start one with `conceptbot ros2 node` (same ROS_DOMAIN_ID, same --name)",
                )
            publisher.publish(String(data=encode(payload)))
            if not spin_until(executor, lambda: bool(results), timeout_s):
                raise ConceptBotError(
                    f"no result for request {payload['id']} within {timeout_s:g} s",
                    hint="the node may be busy with a long plan; raise --timeout",
                )
            # The node publishes a result once its progress is acknowledged: it is queued here.
            spin_until(executor, lambda: False, DRAIN_S)
            return results[0]
        finally:
            executor.shutdown()
            node.destroy_node()
    finally:
        context.try_shutdown()


def topic_base(node_name: str) -> str:
    """The prefix of the node's topics, ``/<node_name>``, checked as ROS 2 checks topic names.

    Checked here, before any ROS 2 call: rclpy's own check fails inside ``create_publisher`` with a
    traceback. A namespaced node is ``NAMESPACE/NAME`` (its topics are ``/NAMESPACE/NAME/...``).

    Raises:
        ConfigError: The name has characters ROS 2 refuses (a space, ``-``, ``!``), an empty part,
            or a part that starts with a digit.
    """
    base = "/" + node_name.strip("/")
    try:
        validate_full_topic_name(f"{base}/request")
    except NameValidationException as exc:
        reason = str(exc).splitlines()[0].rstrip(":").removeprefix("Invalid topic name: ")
        raise ConfigError(
            f"bad node name {node_name!r}: {reason}",
            hint="give the name the node was started with (letters, digits and '_', e.g. conceptbot_arm)",
        ) from None
    return base


def _decode(msg: String) -> dict[str, Any]:
    """A reply's JSON object; an empty dict for anything else (another publisher on the topic)."""
    try:
        data = json.loads(msg.data)
    except ValueError:
        return {}
    return data if isinstance(data, dict) else {}


def spin_until(executor: SingleThreadedExecutor, done: Callable[[], bool], timeout_s: float) -> bool:
    """Spin until ``done()`` or ``timeout_s`` passes; whether it got done (the action client too)."""
    deadline = time.monotonic() + timeout_s
    while not done():
        if time.monotonic() >= deadline:
            return False
        executor.spin_once(timeout_sec=0.05)
    return True
