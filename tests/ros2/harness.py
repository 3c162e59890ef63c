"""Real rclpy in-process for tests: a ConceptBot node and a client node on a private ROS domain."""

from __future__ import annotations

import json
import random
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from std_msgs.msg import String

from conceptbot.core.config import Settings
from conceptbot.core.system import PlannerSystem
from conceptbot.ros2 import qos
from conceptbot.ros2.node import ConceptBotNode, NodeConfig

TINY_SCENE = {
    "name": "tiny",
    "objects": ["apple", "sponge", "user"],
    "pickable_objects": ["apple", "sponge"],
    "destinations": ["user"],
}


def isolate_ros(monkeypatch: pytest.MonkeyPatch) -> int:
    """A random ROS domain, discovery on this machine only: tests never see each other's nodes.

    Returns:
        The domain id (set in ``ROS_DOMAIN_ID``, which every context created afterwards reads).
    """
    domain = random.randint(1, 100)
    monkeypatch.setenv("ROS_DOMAIN_ID", str(domain))
    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    monkeypatch.delenv("ROS_STATIC_PEERS", raising=False)
    return domain


def wait_for(done: Callable[[], bool], timeout_s: float) -> bool:
    """Poll ``done()`` until it is true (True) or ``timeout_s`` passes (False)."""
    deadline = time.monotonic() + timeout_s
    while not done():
        if time.monotonic() >= deadline:
            return False
        time.sleep(0.02)
    return True


@dataclass
class Running:
    """A ConceptBot node and a client node spinning in a background thread.

    Attributes:
        node: The node under test.
        client: The client node (same context).
        publisher: The client's publisher on ``/conceptbot/request``.
        results: Every payload on ``/conceptbot/result``, in arrival order.
        progress: Every payload on ``/conceptbot/progress``, in arrival order.
    """

    node: ConceptBotNode
    client: Node
    publisher: Any
    results: list[dict[str, Any]] = field(default_factory=list)
    progress: list[dict[str, Any]] = field(default_factory=list)

    def send(self, payload: dict[str, Any] | str) -> None:
        """Publish one request (a dict is JSON-encoded; a string goes as it is)."""
        data = payload if isinstance(payload, str) else json.dumps(payload)
        self.publisher.publish(String(data=data))

    def wait_results(self, n: int, timeout_s: float = 20.0) -> list[dict[str, Any]]:
        """The first ``n`` results, waiting for them; fails the test when they do not come."""
        arrived = wait_for(lambda: len(self.results) >= n, timeout_s)
        assert arrived, f"{len(self.results)} of {n} results: {self.results}"
        return self.results[:n]


@contextmanager
def running_node(
    settings: Settings,
    config: NodeConfig,
    planner: PlannerSystem | None = None,
    ros_args: tuple[str, ...] = (),
) -> Iterator[Running]:
    """A node named ``conceptbot`` in a fresh context, and a client that records its replies.

    Waits until both sides have discovered each other; tears everything down on leaving.
    """
    context = Context()
    rclpy.init(args=["test", *ros_args], context=context)
    try:
        node = ConceptBotNode(settings, defaults=config, context=context, planner=planner)
        client = rclpy.create_node("test_client", context=context)
        running = Running(node, client, client.create_publisher(String, "/conceptbot/request", qos.REQUESTS))
        results = client.create_subscription(
            String, "/conceptbot/result", lambda m: running.results.append(json.loads(m.data)), qos.REPLIES
        )
        progress = client.create_subscription(
            String, "/conceptbot/progress", lambda m: running.progress.append(json.loads(m.data)), qos.REPLIES
        )
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        executor.add_node(client)
        thread = threading.Thread(target=executor.spin, daemon=True)
        thread.start()
        try:
            matched = wait_for(
                lambda: (
                    running.publisher.get_subscription_count() > 0
                    and results.get_publisher_count() > 0
                    and progress.get_publisher_count() > 0
                ),
                10.0,
            )
            assert matched, "the client and the node did not discover each other"
            yield running
        finally:
            executor.shutdown()
            thread.join(5)
            node.destroy_node()
            client.destroy_node()
    finally:
        context.try_shutdown()
