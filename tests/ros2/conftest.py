"""Fixtures for the ROS 2 tests: a private ROS domain per test, and nodes started in it."""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator
from contextlib import ExitStack
from pathlib import Path

import pytest

from conceptbot.core.config import Settings
from tests.ros2.harness import TINY_SCENE, Running, isolate_ros, running_node


@pytest.fixture
def ros_domain(monkeypatch: pytest.MonkeyPatch) -> int:
    """A random ROS domain on loopback for this test."""
    return isolate_ros(monkeypatch)


@pytest.fixture
def start_node(ros_domain: int, settings: Settings) -> Iterator[Callable[..., Running]]:
    """``start_node(config, planner=None, ros_args=())``: a running node and a client (see
    :func:`~tests.ros2.harness.running_node`), torn down after the test."""
    with ExitStack() as stack:
        yield lambda config, planner=None, ros_args=(): stack.enter_context(
            running_node(settings, config, planner, ros_args)
        )


@pytest.fixture
def tiny_scene_file(tmp_path: Path) -> Path:
    """The tiny scene as a file (the node's ``scene`` parameter)."""
    path = tmp_path / "tiny.json"
    path.write_text(json.dumps(TINY_SCENE))
    return path
