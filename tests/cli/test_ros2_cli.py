"""`conceptbot ros2`: the install hint without ROS 2, and `send` against a running node."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from conceptbot.cli.main import cli, main
from conceptbot.core.config import Settings
from conceptbot.core.errors import ConceptBotError
from conceptbot.core.plan import Done, PickAndPlace, Plan
from conceptbot.core.scene import Scene
from conceptbot.core.trace import PlannerSummary
from conceptbot.ros2 import ROS2_MISSING
from conceptbot.ros2.client import send_request
from conceptbot.ros2.node import NodeConfig
from tests.pipeline.fakes import properties_reply, urp_reply
from tests.ros2.harness import TINY_SCENE, isolate_ros, running_node


@pytest.mark.parametrize("args", [["ros2", "node"], ["ros2", "send", "Bring me an apple"]])
def test_without_rclpy_the_commands_say_how_to_install_it(
    args: list[str], monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setitem(sys.modules, "rclpy", None)  # `import rclpy` raises ImportError
    monkeypatch.setattr(sys, "argv", ["conceptbot", *args])
    with pytest.raises(SystemExit) as caught:
        main()
    assert caught.value.code == 2
    err = capsys.readouterr().err
    assert ROS2_MISSING in err and "pip install 'conceptbot[ros2]'" in err and "Traceback" not in err


def test_node_refuses_stray_arguments() -> None:
    result = CliRunner().invoke(cli, ["ros2", "node", "extra"])
    assert result.exit_code == 2 and "ROS arguments follow --ros-args" in result.output


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--name", "my-node"], "bad node name 'my-node'"),
        (["--ros-args", "-p", "queue_size"], "bad ROS arguments"),
    ],
)
def test_bad_node_names_and_ros_arguments_are_one_error_line(
    args: list[str], message: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(sys, "argv", ["conceptbot", "ros2", "node", *args])
    with pytest.raises(SystemExit) as caught:
        main()
    err = capsys.readouterr().err
    assert caught.value.code == 2 and message in err and "Traceback" not in err


@pytest.mark.parametrize(
    ("name", "reason"),
    [
        ("bad name!", "must not contain characters other than alphanumerics"),
        ("1robot", "must not have a token that starts with a number"),
        ("robot//arm", "must not contain repeated '/'"),
    ],
)
def test_send_to_a_bad_node_name_is_one_error_line(
    name: str, reason: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    # As `ros2 node --name` answers a bad name: exit code 2, the reason, a hint; no rclpy traceback.
    monkeypatch.setattr(sys, "argv", ["conceptbot", "ros2", "send", "Bring me an apple", "--name", name])
    with pytest.raises(SystemExit) as caught:
        main()
    err = capsys.readouterr().err
    assert caught.value.code == 2 and "Traceback" not in err
    assert f"bad node name {name!r}: topic name {reason}" in err and "Hint:" in err


class Mover:
    """Plans moving the first pickable object to the first destination, and says so; a request
    that mentions a unicorn fails."""

    def plan(self, request: str, scene: Scene, risk: bool = False, feedback=None, observer=None) -> Plan:
        if "unicorn" in request:
            raise ConceptBotError("no unicorns here", hint="ask for something in the scene")
        if observer is not None:
            observer.progress(f"moving for {request!r}")
            observer.event("planner", PlannerSummary("decide", 1))
        return Plan([PickAndPlace(scene.pickable[0], scene.destinations[0]), Done()])


def test_send_prints_progress_and_the_result(
    settings: Settings, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    isolate_ros(monkeypatch)
    scene = tmp_path / "tiny.json"
    scene.write_text(json.dumps(TINY_SCENE))
    with running_node(settings, NodeConfig(scene="kitchen"), planner=Mover()) as running:
        ok = CliRunner().invoke(
            cli, ["ros2", "send", "Bring me an apple", "--scene", str(scene), "--timeout", "20"]
        )
        assert ok.exit_code == 0, ok.output
        result = json.loads(ok.stdout)
        assert result["ok"] is True and result["plan"]["plan"] == ["pick_and_place(apple, user)", "done()"]
        assert "moving for 'Bring me an apple'" in ok.stderr and "[planner] done" in ok.stderr
        # A demo scene goes by name (the node loads it); a failed plan: its error result, exit code 1.
        demo = CliRunner().invoke(cli, ["ros2", "send", "Bring me a drink", "--scene", "toxic-1"])
        assert demo.exit_code == 0 and json.loads(demo.stdout)["plan"]["plan"][-1] == "done()"
        failed = CliRunner().invoke(cli, ["ros2", "send", "Bring me a unicorn"])
        assert failed.exit_code == 1
        assert json.loads(failed.stdout)["error"] == {
            "code": "planner_error",
            "message": "no unicorns here",
            "hint": "ask for something in the scene",
        }
        assert [r["ok"] for r in running.results] == [True, True, False]
    bad = CliRunner().invoke(cli, ["ros2", "send", "   "])
    assert bad.exit_code != 0 and "the request is empty" in str(bad.exception)


def test_the_node_command_plans_for_a_client_and_stops_on_ctrl_c(
    isolated_home: Path, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    isolate_ros(monkeypatch)
    scene = tmp_path / "tiny.json"
    scene.write_text(json.dumps(TINY_SCENE))
    move = "pick_and_place(apple, user)"
    replies = tmp_path / "replies.json"
    replies.write_text(
        json.dumps([properties_reply()] * 3 + [urp_reply([move])] + [move] * 5 + ["done()"] * 5)
    )
    args = ["ros2", "node", "--llm", f"fake:{replies}", "--config", "paper-nokg", "--scene", str(scene)]
    node = subprocess.Popen(
        [sys.executable, "-m", "conceptbot", *args, "--ros-args", "-p", "queue_size:=2"],
        stderr=subprocess.PIPE,
        text=True,
        # A child of a non-interactive shell may inherit SIGINT ignored; a user's Ctrl-C is not.
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    try:
        result = send_request({"request": "Bring me an apple"}, timeout_s=60, discovery_s=60)
    finally:
        node.send_signal(signal.SIGINT)
        _, err = node.communicate(timeout=30)
    assert node.returncode == 0, err
    assert result["ok"] is True and result["plan"]["plan"] == [move, "done()"]
    assert "ready: paper-nokg on fake:" in err and f"1 action(s): {move}" in err and "Traceback" not in err


def test_send_action_prints_feedback_and_the_typed_result(
    settings: Settings, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    pytest.importorskip("conceptbot_interfaces.action", reason="scripts/build_interfaces.sh not run")
    isolate_ros(monkeypatch)
    scene = tmp_path / "tiny.json"
    scene.write_text(json.dumps(TINY_SCENE))
    with running_node(settings, NodeConfig(scene="kitchen"), planner=Mover()):
        ok = CliRunner().invoke(
            cli, ["ros2", "send", "--action", "Bring me an apple", "--scene", str(scene), "--timeout", "20"]
        )
        assert ok.exit_code == 0, ok.output
        result = json.loads(ok.stdout)
        assert result["status"] == "succeeded" and result["ok"] is True
        assert result["actions"] == [{"object": "apple", "destination": "user"}]
        assert result["plan"]["plan"] == ["pick_and_place(apple, user)", "done()"]
        assert (
            "[progress] moving for 'Bring me an apple'" in ok.stderr
            and "[planner] planner: done" in ok.stderr
        )
        failed = CliRunner().invoke(
            cli, ["ros2", "send", "--action", "Bring me a unicorn", "--scene", "toxic-1"]
        )
        assert failed.exit_code == 1
        assert json.loads(failed.stdout)["error"] == {
            "code": "planner_error",
            "message": "no unicorns here (ask for something in the scene)",
        }
