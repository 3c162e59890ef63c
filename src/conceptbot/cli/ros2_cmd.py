"""``conceptbot ros2``: run the planner as a ROS 2 node, or send a node one request."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import click

from conceptbot.cli.context import AppContext, pass_app
from conceptbot.cli.params import FiniteFloatRange
from conceptbot.cli.progress import say
from conceptbot.core.limits import check_request
from conceptbot.core.text import safe_json_dumps
from conceptbot.ros2 import require_rclpy
from conceptbot.scenes import demo_scene_names, resolve_scene
from conceptbot.systems import SYSTEMS


@click.group("ros2")
def ros2() -> None:
    """ROS 2: a node that plans goals of the Plan action and requests on a topic (docs/ros2.md)."""


@ros2.command("node", context_settings={"ignore_unknown_options": True})
@click.option("--llm", "llm", metavar="SPEC", help="LLM backend (default: the settings').")
@click.option(
    "--scene",
    "scene_ref",
    default="kitchen",
    show_default=True,
    help="Scene of a request that sends none: a demo scene name or a scene file.",
)
@click.option(
    "--config", "system", type=click.Choice(SYSTEMS), default="conceptbot", show_default=True, help="System."
)
@click.option("--name", default="conceptbot", show_default=True, help="Node name (topics /NAME/...).")
@click.option(
    "--detections",
    "detections",
    default="",
    metavar="TOPIC",
    help="A conceptbot_interfaces/msg/Scene topic from the detector: goals without a scene use the latest.",
)
@click.option(
    "--detections-max-age",
    "max_age_s",
    default=5.0,
    show_default=True,
    type=FiniteFloatRange(min=0.001),
    help="Seconds the latest detections stay fresh enough to plan against.",
)
@click.argument("ros_args", nargs=-1, type=click.UNPROCESSED, metavar="[--ros-args ...]")
@pass_app
def node(
    app: AppContext,
    llm: str | None,
    scene_ref: str,
    system: str,
    name: str,
    detections: str,
    max_age_s: float,
    ros_args: tuple[str, ...],
) -> None:
    """Start a ROS 2 node: the Plan action on /NAME/plan, requests on /NAME/request; Ctrl-C stops it.

    The flags set the ROS parameters' defaults; `--ros-args -p queue_size:=8 -p plan_timeout_s:=120`
    sets any parameter (system, llm, scene, queue_size, plan_timeout_s, answer_timeout_s,
    detections, detections_max_age_s).
    """
    if ros_args and ros_args[0] != "--ros-args":
        raise click.UsageError(f"unexpected argument {ros_args[0]!r} (ROS arguments follow --ros-args)")
    require_rclpy()
    from conceptbot.ros2.node import NodeConfig, run_node

    defaults = NodeConfig(
        system=system,
        llm=llm or app.settings.llm,
        scene=scene_ref,
        detections=detections,
        detections_max_age_s=max_age_s,
    )
    run_node(app.settings, name=name, defaults=defaults, ros_args=ros_args)


@ros2.command("send")
@click.argument("request")
@click.option(
    "--scene",
    "scene_ref",
    help="A demo scene name or a scene file (sent in the request); default: the node's scene.",
)
@click.option("--name", default="conceptbot", show_default=True, help="The node's name.")
@click.option(
    "--timeout",
    "timeout_s",
    default=300.0,
    show_default=True,
    type=FiniteFloatRange(min=0.1),
    help="Seconds.",
)
@click.option(
    "--action",
    "use_action",
    is_flag=True,
    help="Send a Plan action goal (feedback; questions answered here; Ctrl-C cancels), not a topic request.",
)
def send(request: str, scene_ref: str | None, name: str, timeout_s: float, use_action: bool) -> None:
    """Send REQUEST to a running node; print its progress (stderr) and the result JSON (stdout)."""
    payload: dict[str, Any] = {"request": check_request(request)}
    if scene_ref is not None:
        payload["scene"] = _scene_payload(scene_ref)
    require_rclpy()
    if use_action:
        _send_goal(payload, name, timeout_s)
        return
    from conceptbot.ros2.client import send_request

    result = send_request(payload, node_name=name, timeout_s=timeout_s, on_progress=_show)
    click.echo(safe_json_dumps(result))  # the node's answer is untrusted text
    if not result.get("ok"):
        raise click.exceptions.Exit(1)


def _send_goal(payload: dict[str, Any], name: str, timeout_s: float) -> None:
    """``send --action``: the goal, its feedback on stderr, its questions asked on the terminal."""
    try:
        from conceptbot.ros2.action_client import send_goal
    except ImportError as exc:
        raise click.ClickException(
            f"the Plan action needs conceptbot_interfaces ({exc}): bash scripts/build_interfaces.sh"
        ) from None
    scene = payload.get("scene")
    interactive = sys.stdin.isatty()

    def answer(question: Any) -> str | None:
        options = f" [{' / '.join(question.options)}]" if question.options else ""
        return str(click.prompt(f"{question.text}{options}", err=True))

    result = send_goal(
        payload["request"],
        scene_name=scene if isinstance(scene, str) else "",
        scene_json=safe_json_dumps(scene) if isinstance(scene, dict) else "",
        node_name=name,
        timeout_s=timeout_s,
        on_feedback=lambda f: say(f"[{f.stage}] {f.message}"),
        answer=answer if interactive else None,
    )
    click.echo(safe_json_dumps(result))
    if not result["ok"]:
        raise click.exceptions.Exit(1)


def _scene_payload(ref: str) -> str | dict[str, Any]:
    """A demo scene goes by name; a file is read (and checked) here and sent whole."""
    if (
        not Path(ref).expanduser().is_file()
        and ref.strip().lower().removesuffix(".json") in demo_scene_names()
    ):
        return ref
    return resolve_scene(ref).to_dict()


def _show(payload: dict[str, Any]) -> None:
    """One progress payload as a dim line on stderr."""
    if payload.get("kind") == "event":
        say(f"[{payload.get('module')}] done")
    else:
        say(str(payload.get("message", "")))
