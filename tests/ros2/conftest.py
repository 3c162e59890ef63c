"""Real rclpy in-process: each test gets its own ROS domain on loopback, a node and a client node."""

from __future__ import annotations

import json
import random
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from std_msgs.msg import String

from conceptbot.core.config import Settings
from conceptbot.ros2 import qos
from conceptbot.ros2.node import ConceptBotNode, NodeConfig
from conceptbot.systems import PlannerSystem

TINY_SCENE = {
    "name": "tiny",
    "objects": ["apple", "sponge", "user"],
    "pickable_objects": ["apple", "sponge"],
    "destinations": ["user"],
}


@pytest.fixture
def ros_domain(monkeypatch: pytest.MonkeyPatch) -> int:
    """A random ROS domain, discovery on this machine only: tests never see each other's nodes."""
    domain = random.randint(1, 100)
    monkeypatch.setenv("ROS_DOMAIN_ID", str(domain))
    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    monkeypatch.delenv("ROS_STATIC_PEERS", raising=False)
    return domain


@dataclass
class Running:
    """A ConceptBot node and a client node spinning in a background thread.

    Attributes:
        node: The node under test.
        results: Every payload on ``/<name>/result``, in arrival order.
        progress: Every payload on ``/<name>/progress``, in arrival order.
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
        assert wait_for(lambda: len(self.results) >= n, timeout_s), (
            f"{len(self.results)} of {n} results: {self.results}"
        )
        return self.results[:n]


def wait_for(done: Callable[[], bool], timeout_s: float) -> bool:
    """Poll ``done()`` until it is true (True) or ``timeout_s`` passes (False)."""
    deadline = time.monotonic() + timeout_s
    while not done():
        if time.monotonic() >= deadline:
            return False
        time.sleep(0.02)
    return True


@pytest.fixture
def start_node(ros_domain: int, settings: Settings) -> Iterator[Callable[..., Running]]:
    """``start_node(config, planner=None, ros_args=(), settings=None)``: a node in a fresh context,
    and a client.

    The client publishes on the node's request topic and records its progress and results; the
    fixture waits until both sides have discovered each other, and tears everything down after.
    """
    teardown: list[Callable[[], None]] = []

    def start(
        config: NodeConfig,
        planner: PlannerSystem | None = None,
        ros_args: tuple[str, ...] = (),
        settings: Settings = settings,
    ) -> Running:
        context = Context()
        rclpy.init(args=["test", *ros_args], context=context)
        teardown.append(context.try_shutdown)
        node = ConceptBotNode(settings, defaults=config, context=context, planner=planner)
        client = rclpy.create_node("test_client", context=context)
        publisher = client.create_publisher(String, "/conceptbot/request", qos.REQUESTS)
        running = Running(node, client, publisher)
        result_sub = client.create_subscription(
            String, "/conceptbot/result", lambda m: running.results.append(json.loads(m.data)), qos.REPLIES
        )
        progress_sub = client.create_subscription(
            String, "/conceptbot/progress", lambda m: running.progress.append(json.loads(m.data)), qos.REPLIES
        )
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        executor.add_node(client)
        thread = threading.Thread(target=executor.spin, daemon=True)
        thread.start()

        def stop() -> None:
            executor.shutdown()
            thread.join(5)
            node.destroy_node()
            client.destroy_node()

        teardown.append(stop)
        matched = wait_for(
            lambda: (
                running.publisher.get_subscription_count() > 0
                and result_sub.get_publisher_count() > 0
                and progress_sub.get_publisher_count() > 0
            ),
            10.0,
        )
        assert matched, "the client and the node did not discover each other"
        return running

    yield start
    for step in reversed(teardown):
        step()


@pytest.fixture
def tiny_scene_file(tmp_path: Path) -> Path:
    """The tiny scene as a file (the node's ``scene`` parameter)."""
    path = tmp_path / "tiny.json"
    path.write_text(json.dumps(TINY_SCENE))
    return path
