"""Issue 19: key routing, credentials in URLs, non-JSON replies, stale install files."""

from __future__ import annotations

import hashlib
import os
import socket
import sqlite3
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

from conceptbot.core.config import load_settings
from conceptbot.core.errors import BackendRequestError, BackendUnavailableError, ConfigError
from conceptbot.core.urls import redact_secrets, redact_url
from conceptbot.models import weights
from conceptbot.models.cache_db import CacheStore
from conceptbot.models.caching import CachedLLM
from conceptbot.models.llm import ChatRequest
from conceptbot.models.openai_backend import OpenAILLM
from conceptbot.models.openai_embedder import OpenAIEmbedder
from conceptbot.models.registry import create_embedder, create_llm
from tests.loopback import LoopbackServer, Request
from tests.models.openai_stub import StubServer, completion

OPENAI_KEY = "sk-user-openai-key-0123456789abcdef"
SECRET = "SECRET123query"


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def _embeddings(body: dict[str, Any]) -> tuple[int, dict[str, Any]]:
    data = [
        {"object": "embedding", "index": i, "embedding": [1.0, 0.0, 0.0]} for i in range(len(body["input"]))
    ]
    return 200, {
        "object": "list",
        "data": data,
        "model": "emb",
        "usage": {"prompt_tokens": 1, "total_tokens": 1},
    }


class RawServer(LoopbackServer):
    """Answers every request with the same status, body bytes and Content-Type."""

    def __init__(self, status: int, body: bytes, content_type: str) -> None:
        super().__init__()
        self.status, self.body, self.content_type = status, body, content_type

    def respond(self, request: Request) -> tuple[int, bytes]:
        return self.status, self.body

    @property
    def url(self) -> str:
        return f"{self.base_url}/v1"


# -- 1. key routing --------------------------------------------------------------------------------
def test_openai_compatible_never_sends_the_openai_key(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", OPENAI_KEY)
    monkeypatch.setenv("OPENAI_ORG_ID", "org-user")
    monkeypatch.setenv("OPENAI_PROJECT_ID", "proj-user")
    settings = load_settings()
    with StubServer([lambda body: (200, completion(["ok"]))]) as server:
        assert (
            create_llm(f"openai-compatible:{server.url}#m", settings).chat(ChatRequest.of("q")).text == "ok"
        )
    headers = server.headers[0]
    assert "authorization" not in headers
    assert "openai-organization" not in headers and "openai-project" not in headers
    assert not any(OPENAI_KEY in value for value in headers.values())


def test_openai_compatible_sends_conceptbot_api_key(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", OPENAI_KEY)
    monkeypatch.setenv("CONCEPTBOT_API_KEY", "cb-server-key")
    with StubServer([lambda body: (200, completion(["ok"]))]) as server:
        create_llm(f"openai-compatible:{server.url}#m", load_settings()).chat(ChatRequest.of("q"))
    assert server.headers[0]["authorization"] == "Bearer cb-server-key"


def test_openai_backends_send_the_openai_key_to_openai_base_url(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", OPENAI_KEY)
    with StubServer([lambda body: (200, completion(["ok"])), _embeddings]) as server:
        monkeypatch.setenv("OPENAI_BASE_URL", server.url)
        settings = load_settings()
        assert create_llm("openai:gpt-x", settings).chat(ChatRequest.of("q")).text == "ok"
        assert create_embedder("openai:emb", settings).embed(["a", "b"]).shape == (2, 3)
    assert [h["authorization"] for h in server.headers] == [f"Bearer {OPENAI_KEY}"] * 2


# -- 2. credentials in URLs ------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("url", "expected"),
    [
        ("http://127.0.0.1:8000/v1", "http://127.0.0.1:8000/v1"),
        ("http://h/v1?key=S&x=1#m", "http://h/v1?key=***&x=***#m"),
        ("https://user:pw@h:8443/v1", "https://h:8443/v1"),
        ("http://tok@[::1]:8000/v1?SECRETONLY", "http://[::1]:8000/v1?***"),
        ("http://u:p@h:abc/v1", "http://h:abc/v1"),  # unparseable port: userinfo still dropped
    ],
)
def test_redact_url(url: str, expected: str) -> None:
    assert redact_url(url) == expected
    assert redact_url(expected) == expected


def test_redact_secrets_masks_urls_tokens_and_keys() -> None:
    text = (
        f"POST 'http://u:pw@h/v1?api_key={SECRET}#m' failed; Authorization: Bearer abc.def "
        f"with {OPENAI_KEY}, token={SECRET}; sk-learn and max_tokens=40 are fine"
    )
    out = redact_secrets(text)
    for secret in (SECRET, "pw@", "abc.def", OPENAI_KEY):
        assert secret not in out
    assert "http://h/v1?api_key=***#m" in out and "sk-learn" in out and "max_tokens=40" in out


def test_malformed_url_message_is_redacted(settings: Any) -> None:
    with pytest.raises(ConfigError, match="malformed base URL") as info:
        create_llm(f"openai-compatible:ftp://u:{SECRET}@h/v1?key={SECRET}#m", settings)
    assert SECRET not in str(info.value)


def test_messages_and_call_log_hide_url_credentials(tmp_path: Path) -> None:
    url_seen: list[str] = []

    def echo(body: dict[str, Any]) -> tuple[int, dict[str, Any]]:
        return 400, {"error": {"message": f"bad request to {url_seen[0]}"}}  # proxies do echo URLs

    with StubServer([echo]) as server:
        url = f"http://user:{SECRET}pw@127.0.0.1:{server.server.server_address[1]}/v1?key={SECRET}"
        url_seen.append(url)
        db = CacheStore(tmp_path / "cache.db")
        llm = CachedLLM(OpenAILLM("m", backend="openai-compatible", base_url=url, max_retries=0), db)
        with pytest.raises(BackendRequestError) as info:
            llm.chat(ChatRequest.of("q"))
    assert SECRET not in str(info.value) and "key=***" in str(info.value)
    errors = [row[0] for row in sqlite3.connect(db.path).execute("SELECT error FROM calls")]
    assert errors and errors[0] and SECRET not in errors[0] and "rejected the request" in errors[0]


def test_call_log_masks_errors_from_any_writer(tmp_path: Path) -> None:
    from conceptbot.models.cache_db import CallRecord

    db = CacheStore(tmp_path / "cache.db")
    db.log_call(
        CallRecord("chat", "m", "b", "x", 0, 0, 0.0, None, False, error=f"GET http://h/?key={SECRET}")
    )
    assert db.calls()[0].error == "GET http://h/?key=***"


def _run_cli(*args: str, home: Path) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("CONCEPTBOT_", "OPENAI_"))}
    env["CONCEPTBOT_HOME"] = str(home)
    return subprocess.run(
        [sys.executable, "-m", "conceptbot", *args], capture_output=True, text=True, env=env, timeout=120
    )


def test_cli_error_and_cache_db_never_show_a_key_in_the_url(isolated_home: Path) -> None:
    spec = f"openai-compatible:http://127.0.0.1:{_free_port()}/v1?key={SECRET}#m"
    result = _run_cli("--llm", spec, "llm", "hi", home=isolated_home)
    assert result.returncode == 1, result.stderr
    assert "cannot connect" in result.stderr and "key=***" in result.stderr
    assert SECRET not in result.stdout + result.stderr and "Traceback" not in result.stderr
    errors = [r[0] for r in sqlite3.connect(isolated_home / "cache.db").execute("SELECT error FROM calls")]
    assert errors and all(e and SECRET not in e for e in errors)


# -- 3. replies that are not OpenAI JSON -----------------------------------------------------------
HTML = b"<!DOCTYPE html><html><head><title>Open WebUI</title></head><body>app</body></html>"


@pytest.mark.parametrize(
    ("body", "content_type", "what"),
    [
        (HTML, "text/html; charset=utf-8", "an HTML page"),
        (b'{"choices": [', "application/json", "invalid JSON"),
        (b'{"status": "ok"}', "application/json", "JSON without the expected fields"),
        (b"[1, 2]", "application/json", "JSON without the expected fields"),
    ],
)
def test_non_openai_reply_is_a_clear_error(body: bytes, content_type: str, what: str) -> None:
    with RawServer(200, body, content_type) as server:
        llm = OpenAILLM("m", backend="openai-compatible", base_url=server.url, max_retries=0)
        with pytest.raises(BackendRequestError, match="not an OpenAI-style JSON reply") as info:
            llm.chat(ChatRequest.of("q"))
        embedder = OpenAIEmbedder("e", api_key="k", base_url=server.url, max_retries=0)
        with pytest.raises(BackendRequestError, match="not an OpenAI-style JSON reply") as embed_info:
            embedder.embed(["a"])
    assert what in str(info.value) and what in str(embed_info.value)
    assert "/v1" in (info.value.hint or "")


def test_embedder_errors_name_the_redacted_server() -> None:
    url = f"http://127.0.0.1:{_free_port()}/v1?key={SECRET}"
    with pytest.raises(BackendUnavailableError, match="cannot connect") as info:
        OpenAIEmbedder("e", api_key="k", base_url=url, max_retries=0).embed(["a"])
    assert SECRET not in str(info.value) and "127.0.0.1" in str(info.value)


# -- 6. stale temporary files of interrupted installs ----------------------------------------------
def _dead_pid() -> int:
    pid = 4_000_000
    while True:  # a pid above the kernel's usual pid_max, checked anyway
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return pid
        except OSError:
            pass
        pid += 1


def test_clean_stale_files_keeps_live_installs(tmp_path: Path) -> None:
    dead, live = _dead_pid(), os.getpid()
    stale = tmp_path / f".model.gguf.{dead}.partial"
    stale_stamp = tmp_path / f"model.gguf.verified.{dead}.tmp"
    running = tmp_path / f".other.gguf.{live}.partial"
    abandoned = tmp_path / f".old.gguf.{live}.partial"  # pid reused, file untouched for days
    keep = tmp_path / "model.gguf"
    for path in (stale, stale_stamp, running, abandoned, keep):
        path.write_bytes(b"x" * 10)
    os.utime(abandoned, (time.time() - 3 * 86400,) * 2)
    removed = weights.clean_stale_files(tmp_path)
    assert sorted(p.name for p, _ in removed) == sorted([stale.name, stale_stamp.name, abandoned.name])
    assert all(size == 10 for _, size in removed)
    assert running.exists() and keep.exists() and not stale.exists() and not abandoned.exists()
    assert weights.clean_stale_files(tmp_path / "absent") == []


@pytest.fixture
def tiny_model(monkeypatch: pytest.MonkeyPatch) -> str:
    """A catalogue entry whose one 'part' is a small file inside the installed package."""
    source = Path(weights.__file__).with_name("prices.toml")
    data = source.read_bytes()
    entry = weights.ModelEntry(
        name="tiny",
        description="test",
        filename="tiny.gguf",
        size=len(data),
        sha256=hashlib.sha256(data).hexdigest(),
        license="MIT",
        source={"type": "package_file", "module": "conceptbot.models", "path": "prices.toml"},
    )
    real = weights.catalogue
    monkeypatch.setattr(weights, "catalogue", lambda: {**real(), "tiny": entry})
    return "tiny"


def test_models_install_removes_partial_files_and_says_so(tiny_model: str, isolated_home: Path) -> None:
    from conceptbot.cli.main import cli

    models_dir = isolated_home / "models"
    models_dir.mkdir(parents=True)
    stale = models_dir / f".qwen2.5-coder-1.5b-instruct-q8_0.gguf.{_dead_pid()}.partial"
    stale.write_bytes(b"\0" * 2_000_000)
    result = CliRunner().invoke(cli, ["models", "install", tiny_model])
    assert result.exit_code == 0, result.output
    assert not stale.exists() and (models_dir / "tiny.gguf").is_file()
    assert f"removed {stale.name} (2.0 MB), left by an interrupted install" in result.output
    assert "installed and verified" in result.output
