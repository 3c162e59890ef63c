"""The CLI as a user runs it: a real subprocess, exit codes and messages."""

from __future__ import annotations

import json
import os
import shutil
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from conceptbot.models import weights


def run(
    *args: str, home: Path, check_exit: int | None = 0, extra_env: dict[str, str] | None = None
) -> subprocess.CompletedProcess[str]:
    """Run ``python -m conceptbot ARGS`` with an isolated home; check the exit code."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("CONCEPTBOT_", "OPENAI_"))}
    env["CONCEPTBOT_HOME"] = str(home)
    env.update(extra_env or {})
    result = subprocess.run(
        [sys.executable, "-m", "conceptbot", *args], capture_output=True, text=True, env=env, timeout=600
    )
    if check_exit is not None:
        assert result.returncode == check_exit, result.stdout + result.stderr
    return result


@pytest.fixture
def replies(tmp_path: Path):
    def write(*texts: str) -> Path:
        path = tmp_path / "replies.json"
        path.write_text(json.dumps(list(texts)))
        return path

    return write


def test_help_lists_the_commands(isolated_home: Path) -> None:
    out = run("--help", home=isolated_home).stdout
    for command in ("doctor", "llm", "models"):
        assert command in out


def test_llm_prints_reply_tokens_and_time_and_caches(isolated_home: Path, replies) -> None:
    path = replies("A hollandaise needs eggs and butter.")
    first = run("--llm", f"fake:{path}", "llm", "What is in hollandaise?", home=isolated_home)
    assert "eggs and butter" in first.stdout
    assert "tokens:" in first.stderr and "fresh" in first.stderr
    replies("a different reply")  # a cached request must not reach the backend again
    second = run("--llm", f"fake:{path}", "llm", "What is in hollandaise?", home=isolated_home)
    assert "eggs and butter" in second.stdout and "cached" in second.stderr
    third = run("--no-cache", "--llm", f"fake:{path}", "llm", "What is in hollandaise?", home=isolated_home)
    assert "a different reply" in third.stdout


def test_llm_json_output(isolated_home: Path, replies) -> None:
    path = replies('{"dangerous": 4}')
    schema = isolated_home.parent / "schema.json"
    schema.write_text(
        json.dumps(
            {"type": "object", "properties": {"dangerous": {"type": "integer"}}, "required": ["dangerous"]}
        )
    )
    out = run("--llm", f"fake:{path}", "llm", "knife?", "--schema", str(schema), "--json", home=isolated_home)
    data = json.loads(out.stdout)
    assert data["parsed"] == {"dangerous": 4} and data["backend"] == "fake"
    assert data["usage"]["prompt_tokens"] > 0


def test_malformed_json_from_the_model_is_a_clear_error(isolated_home: Path, replies) -> None:
    path = replies("not json", "still not json")
    schema = isolated_home.parent / "schema.json"
    schema.write_text('{"type": "object"}')
    result = run(
        "--llm", f"fake:{path}", "llm", "q", "--schema", str(schema), home=isolated_home, check_exit=1
    )
    assert "did not return valid JSON" in result.stderr and "Traceback" not in result.stderr


@pytest.mark.parametrize(
    ("spec", "code", "message"),
    [
        ("gpt5:turbo", 2, "unknown LLM backend 'gpt5'"),
        ("openai-compatible:127.0.0.1:8000/v1#m", 2, "malformed base URL"),
        ("openai:gpt-4o-mini", 2, "needs an API key"),
        ("llamacpp:qwen2.5-coder-0.5b", 1, "conceptbot models install qwen2.5-coder-0.5b"),
    ],
)
def test_bad_backends_give_a_message_and_exit_code(
    isolated_home: Path, spec: str, code: int, message: str
) -> None:
    result = run("--llm", spec, "llm", "hi", home=isolated_home, check_exit=code)
    assert message in result.stderr and "Traceback" not in result.stderr


def test_server_down(isolated_home: Path) -> None:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    env_spec = f"openai-compatible:http://127.0.0.1:{port}/v1#m"
    result = run("--llm", env_spec, "llm", "hi", home=isolated_home, check_exit=1)
    assert "cannot connect" in result.stderr and "Traceback" not in result.stderr


def test_corrupt_model_names_the_fix(isolated_home: Path) -> None:
    entry = weights.get_entry("qwen2.5-coder-0.5b")
    (isolated_home / "models").mkdir(parents=True)
    (isolated_home / "models" / entry.filename).write_bytes(b"\0" * 1024)
    result = run("--llm", "llamacpp:qwen2.5-coder-0.5b", "llm", "hi", home=isolated_home, check_exit=1)
    assert "corrupt" in result.stderr and "models install qwen2.5-coder-0.5b --force" in result.stderr


def test_unknown_model_install(isolated_home: Path) -> None:
    result = run("models", "install", "llama-900b", home=isolated_home, check_exit=2)
    assert "unknown model" in result.stderr


def test_models_install_and_list(isolated_home: Path) -> None:
    assert "not installed" in run("models", "list", home=isolated_home).stdout
    out = run("models", "install", "smollm2-135m", home=isolated_home).stdout
    assert "installed and verified" in out
    listing = run("models", "list", home=isolated_home).stdout
    assert any(
        "smollm2-135m" in line and "installed" in line and "not" not in line for line in listing.splitlines()
    )
    leftovers = [p.name for p in (isolated_home / "models").iterdir() if "partial" in p.name]
    assert leftovers == []


def test_doctor_fails_when_the_default_model_is_missing(isolated_home: Path) -> None:
    result = run("--embedder", "fake", "doctor", home=isolated_home, check_exit=1)
    assert "[FAIL] model qwen2.5-coder-1.5b" in result.stdout
    assert "conceptbot models install qwen2.5-coder-1.5b" in result.stdout
    assert "[ok  ] pybullet" in result.stdout


@pytest.mark.slow
def test_doctor_is_green_with_a_real_model_and_embedder(
    isolated_home: Path, smollm2_path: Path, omcs_file: Path, wordnet_dir: Path
) -> None:
    entry = weights.get_entry("smollm2-135m")
    (isolated_home / "models").mkdir(parents=True)
    shutil.copy(smollm2_path, isolated_home / "models" / entry.filename)
    assert (
        "[FAIL] knowledge graph"
        in run("--embedder", "fake", "doctor", home=isolated_home, check_exit=1).stdout
    )
    run("kg", "install", "--file", str(omcs_file), "--wordnet-dir", str(wordnet_dir), home=isolated_home)
    result = run("--llm", "llamacpp:smollm2-135m", "doctor", home=isolated_home)
    assert "[ok  ] model smollm2-135m: sha256 ok" in result.stdout
    assert "[ok  ] knowledge graph" in result.stdout and "omcs" in result.stdout
    assert "[ok  ] embedder" in result.stdout and "dim 384" in result.stdout
    assert "[FAIL]" not in result.stdout
    answer = run(
        "--llm", "llamacpp:smollm2-135m", "llm", "Name one fruit.", "--max-tokens", "8", home=isolated_home
    )
    assert answer.stdout.strip() and "llamacpp:smollm2-135m" in answer.stderr
