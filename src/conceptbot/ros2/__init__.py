"""ConceptBot on ROS 2: a node that plans requests arriving on a topic (``conceptbot ros2 node``).

``protocol`` is pure Python (the JSON payloads the node reads and writes, validated; no ROS
import), so it is tested and used without ROS 2 installed. ``node`` (the rclpy node) and
``client`` (the small ``conceptbot ros2 send`` client) import rclpy, which is the optional extra
``conceptbot[ros2]``: call :func:`require_rclpy` before importing them. docs/ros2.md has the
message flow and the payloads.
"""

from __future__ import annotations

from conceptbot.core.errors import ConfigError

ROS2_MISSING = "ROS 2 is not installed: pip install 'conceptbot[ros2]' (or bash scripts/install.sh)"
"""The message when rclpy cannot be imported."""


def require_rclpy() -> None:
    """Import rclpy, or say how to install it.

    Raises:
        ConfigError: rclpy cannot be imported (the extra is not installed, or a library it loads is
            missing: the hint carries the import error).
    """
    try:
        import rclpy  # noqa: F401
    except ImportError as exc:
        raise ConfigError(
            ROS2_MISSING,
            hint=f"importing rclpy failed ({exc}); the ROS 2 wheels are for CPython 3.11 on Linux x86_64",
        ) from None
