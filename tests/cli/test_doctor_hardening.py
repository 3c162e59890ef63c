"""Issue 19: ``conceptbot doctor`` contacts HTTP backends and never crashes."""

from __future__ import annotations

import importlib
import os
import random
import socket
import sqlite3
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

from conceptbot.cli.main import cli
from conceptbot.core.config import Settings, load_settings
from conceptbot.knowledge.sqlite_store import GraphBuilder
from tests.models.openai_stub import StubServer, completion, echo_reply, top_reply

# After cli.main: importing a command module first is a circular import (main registers them all).
doctor = importlib.import_module("conceptbot.cli.doctor")


def run(*args: str, home: Path, extra_env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    """``python -m conceptbot ARGS`` with an isolated home and no user keys."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("CONCEPTBOT_", "OPENAI_"))}
    env["CONCEPTBOT_HOME"] = str(home)
    env.update(extra_env or {})
    return subprocess.run(
        [sys.executable, "-m", "conceptbot", *args], capture_output=True, text=True, env=env, timeout=300
    )


def _build_graph(path: Path, extra: int = 0) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with GraphBuilder(path, "test") as builder:
        builder.add("knife", "UsedFor", "cut", 8.0, "omcs")
        builder.add("knife", "IsA", "weapon", 7.0, "omcs")
        for i in range(extra):  # enough rows that edges and concepts span many pages
            builder.add(f"thing {i}", "RelatedTo", f"other thing {i}", 1.0, "omcs")


@pytest.fixture
def home_with_graph(isolated_home: Path) -> Path:
    """An isolated home whose knowledge graph check passes."""
    _build_graph(load_settings().kg_path)
    return isolated_home


def _fail_lines(stdout: str) -> list[str]:
    return [line for line in stdout.splitlines() if line.startswith("[FAIL]")]


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


# -- 4. HTTP backends are contacted --------------------------------------------------------------
def test_doctor_reaches_the_openai_backend_and_times_it(home_with_graph: Path) -> None:
    replies = [
        completion(["OK"]),
        echo_reply("1, 2, 3, 4, 5, 6", [None, -10.9], [0, 14]),  # the scoring probe: echo unsound
        {"error": {"message": "This is a chat model"}},  # no completions: no search (top 20 ...)
        {"error": {"message": "This is a chat model"}},  # (... nor top 5)
        top_reply({"Yes": -0.1}),  # chat log-probabilities work
    ]
    statuses = [200, 200, 404, 404, 200]
    with StubServer(
        [lambda body, r=r, s=s: (s, r) for r, s in zip(replies, statuses, strict=True)]
    ) as server:
        result = run(
            "--llm",
            "openai:gpt-x",
            "--embedder",
            "fake",
            "doctor",
            home=home_with_graph,
            extra_env={"OPENAI_API_KEY": "sk-test-key-for-doctor", "OPENAI_BASE_URL": server.url},
        )
    assert "[ok  ] LLM server (openai): model 'gpt-x' answered in" in result.stdout, result.stdout
    assert "options scored by chat-logprobs" in result.stdout, result.stdout
    assert _fail_lines(result.stdout) == [] and result.returncode == 0, result.stdout + result.stderr
    assert len(server.bodies) == 5 and server.bodies[0]["max_tokens"] == 1


def test_doctor_fails_when_the_server_is_down(home_with_graph: Path) -> None:
    url = f"http://127.0.0.1:{_free_port()}/v1"
    result = run("--llm", f"openai-compatible:{url}#m", "--embedder", "fake", "doctor", home=home_with_graph)
    assert result.returncode == 1 and "Traceback" not in result.stderr
    assert _fail_lines(result.stdout) == [
        f"[FAIL] LLM server (openai-compatible): cannot connect to {url}"
        " (is the server running and the URL right?)"
    ]


def test_llm_server_check_reports_a_refused_key(settings: Settings) -> None:
    with StubServer([lambda body: (401, {"error": {"message": "invalid key"}})]) as server:
        check = doctor.check_llm_server(settings.with_overrides(llm=f"openai-compatible:{server.url}#m"))
    assert (check.ok, check.required) == (False, True)
    assert "refused the API key" in check.detail
    assert len(server.bodies) == 1  # no retries in a health check


def test_llm_server_check_skips_local_backends(settings: Settings) -> None:
    check = doctor.check_llm_server(settings.with_overrides(llm="fake"))
    assert check.ok and not check.required and "not used" in check.detail


# -- 5. doctor never crashes ---------------------------------------------------------------------
def _corrupt_all_but_small_tables(path: Path) -> None:
    """Overwrite every page except the header page and those of the meta/relations/sources tables,
    so the graph still opens and the first real lookup meets garbage."""
    conn = sqlite3.connect(path)
    page_size = conn.execute("PRAGMA page_size").fetchone()[0]
    keep = {1} | {
        int(r[0])
        for r in conn.execute(
            "SELECT rootpage FROM sqlite_master WHERE tbl_name IN ('meta', 'relations', 'sources')"
        )
    }
    pages = conn.execute("PRAGMA page_count").fetchone()[0]
    conn.close()
    assert pages > len(keep) + 4
    size = path.stat().st_size
    rng = random.Random(0)
    with open(path, "r+b") as handle:
        for page in range(1, pages + 1):
            if page not in keep:
                handle.seek((page - 1) * page_size)
                handle.write(rng.randbytes(page_size))
    assert path.stat().st_size == size


def test_doctor_reports_a_corrupt_graph_without_a_traceback(isolated_home: Path) -> None:
    path = load_settings().kg_path
    _build_graph(path, extra=3000)
    _corrupt_all_but_small_tables(path)
    result = run("--llm", "fake", "--embedder", "fake", "doctor", home=isolated_home)
    assert result.returncode == 1, result.stdout + result.stderr
    assert "Traceback" not in result.stderr + result.stdout
    fails = _fail_lines(result.stdout)
    assert len(fails) == 1 and fails[0].startswith("[FAIL] knowledge graph:"), result.stdout
    assert "[ok  ] cache database" in result.stdout  # the checks after it still ran


def test_an_unexpected_exception_in_a_check_is_a_failing_line(
    isolated_home: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def boom(settings: Any) -> doctor.Check:
        raise RuntimeError("kaput\nsecond line")

    ok = doctor.Check("after", True, "still checked")
    monkeypatch.setattr(doctor, "CHECKS", [("exploding check", boom), ("after", lambda s: ok)])
    result = CliRunner().invoke(cli, ["--llm", "fake", "doctor"])
    assert result.exit_code == 1, result.output
    assert "[FAIL] exploding check: unexpected RuntimeError: kaput second line" in result.output
    assert "[ok  ] after: still checked" in result.output


def test_doctor_header_hides_credentials_in_the_spec(
    isolated_home: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(doctor, "CHECKS", [])
    spec = "openai-compatible:http://u:pw-SECRET@127.0.0.1:1/v1?key=SECRET#m"
    result = CliRunner().invoke(cli, ["--llm", spec, "doctor"])
    assert result.exit_code == 0 and "SECRET" not in result.output
    assert "http://127.0.0.1:1/v1?key=***#m" in result.output


def test_ros2_check_reports_the_installed_rclpy() -> None:
    check = doctor.check_ros2()
    assert check.ok and not check.required
    assert check.detail.startswith("rclpy 9.1.2, Fast DDS ")


def test_a_missing_ros2_is_a_warning_with_the_install_hint(monkeypatch: pytest.MonkeyPatch) -> None:
    def no_ros(module: str) -> None:
        raise ImportError(f"No module named {module!r}")

    monkeypatch.setattr(doctor, "_import_silently", no_ros)
    monkeypatch.setattr(doctor, "CHECKS", [("ROS 2", lambda s: doctor.check_ros2())])
    result = CliRunner().invoke(cli, ["doctor"])
    assert result.exit_code == 0, result.output
    assert "[warn] ROS 2: not installed" in result.output and "conceptbot[ros2]" in result.output
