"""Issue 32, items 6, 8 and 10: configured secrets are masked by value in every backend error and in
the call log, base URLs with a query string reach the right path, and keys an HTTP header cannot
carry are a configuration error that does not print them. Real HTTP against loopback servers."""

from __future__ import annotations

import base64
import sqlite3
from pathlib import Path
from typing import Any

import pytest

from conceptbot.core.config import load_settings
from conceptbot.core.errors import BackendRequestError, ConfigError
from conceptbot.models.cache_db import CacheStore
from conceptbot.models.caching import CachedLLM
from conceptbot.models.llm import ChatRequest
from conceptbot.models.openai_backend import OpenAILLM
from conceptbot.models.openai_embedder import OpenAIEmbedder
from conceptbot.models.registry import create_llm
from tests.misbehaving import MisbehavingServer
from tests.models.openai_stub import StubServer

KEY = "ck-456"  # looks like nothing a pattern knows: only its value can find it


def _failing_call(url: str, db: CacheStore, api_key: str | None) -> str:
    """The error text of one chat through the cache wrapper (as `conceptbot llm` makes it)."""
    inner = OpenAILLM("m", backend="openai-compatible", base_url=url, api_key=api_key, max_retries=0)
    with pytest.raises(BackendRequestError) as info:
        CachedLLM(inner, db).chat(ChatRequest.of("hi"))
    return str(info.value)


def _logged_errors(db: CacheStore) -> list[str]:
    return [row[0] for row in sqlite3.connect(db.path).execute("SELECT error FROM calls")]


@pytest.mark.parametrize(("mode", "says"), [("e500raw", "boom for key ***"), ("e400raw", "token ***")])
def test_a_key_the_server_echoes_is_masked_in_the_message_and_the_call_log(
    tmp_path: Path, mode: str, says: str
) -> None:
    db = CacheStore(tmp_path / "cache.db")
    with MisbehavingServer() as server:
        message = _failing_call(server.url(mode), db, KEY)
        assert server.received[0].headers["authorization"] == f"Bearer {KEY}"  # the key was sent
    errors = _logged_errors(db)
    assert KEY not in message and says in message
    assert len(errors) == 1 and KEY not in errors[0] and says in errors[0]


def test_the_basic_credential_made_from_the_url_password_is_masked(tmp_path: Path) -> None:
    basic = base64.b64encode(b"alice:hunter2pw").decode()
    db = CacheStore(tmp_path / "cache.db")
    with MisbehavingServer() as server:
        url = server.url("e500raw").replace("http://", "http://alice:hunter2pw@")
        message = _failing_call(url, db, None)
        assert server.received[0].headers["authorization"] == f"Basic {basic}"  # what gets echoed
    errors = _logged_errors(db)
    for text in (message, errors[0]):
        assert basic not in text and "hunter2pw" not in text and "boom for key Basic ***" in text


def test_a_base_url_query_is_sent_as_a_query_on_the_endpoint_path(settings: Any) -> None:
    with MisbehavingServer() as server:
        llm = create_llm(f"openai-compatible:{server.url('ok')}?api_key=X&v=2#m", settings)
        reply = llm.chat(ChatRequest.of("hi"))
        seen = [r.path for r in server.received]
    assert reply.choices == ("Yes",)
    assert seen == ["/ok/v1/chat/completions?api_key=X&v=2"]


def test_a_base_url_query_value_echoed_back_is_masked(tmp_path: Path) -> None:
    def echo(body: dict[str, Any]) -> tuple[int, dict[str, Any]]:
        return 500, {"error": {"message": "quota used up for tenant Q-SECRET-77"}}

    with StubServer([echo]) as server:
        message = _failing_call(f"{server.url}?tenant=Q-SECRET-77", CacheStore(tmp_path / "c.db"), None)
    assert "Q-SECRET-77" not in message and "quota used up for tenant ***" in message
    assert "?tenant=***" in message  # which URL failed is still said


def test_the_embedder_sends_a_base_url_query_too() -> None:
    def embeddings(body: dict[str, Any]) -> tuple[int, dict[str, Any]]:
        data = [
            {"object": "embedding", "index": i, "embedding": [1.0, 0.0]} for i in range(len(body["input"]))
        ]
        return 200, {
            "object": "list",
            "data": data,
            "model": "e",
            "usage": {"prompt_tokens": 1, "total_tokens": 1},
        }

    with StubServer([embeddings]) as server:
        embedder = OpenAIEmbedder("e", api_key="sk-x", base_url=f"{server.url}?deployment=d1", max_retries=0)
        vectors = embedder.embed(["a"])
        path = server.received[0].path
    assert vectors.shape == (1, 2) and path == "/v1/embeddings?deployment=d1"


def test_a_query_parameter_named_twice_is_refused_without_its_values() -> None:
    with pytest.raises(ConfigError, match="names query parameter 'k' twice") as info:
        OpenAILLM("m", backend="openai-compatible", base_url="http://h/v1?k=S3CR3T1&k=S3CR3T2")
    assert "S3CR3T" not in str(info.value)


BAD_KEYS = [("ck-ünïcode", "non-ASCII character"), ("ck-abc\r\nX-Evil: 1", "line break")]


@pytest.mark.parametrize(("key", "problem"), BAD_KEYS)
def test_a_key_a_header_cannot_carry_is_refused_when_the_backend_is_built(key: str, problem: str) -> None:
    with MisbehavingServer() as server:
        with pytest.raises(ConfigError) as info:
            OpenAILLM("m", backend="openai-compatible", base_url=server.url("ok"), api_key=key)
        assert server.received == []  # refused before any request
    text = str(info.value)
    assert "CONCEPTBOT_API_KEY" in text and problem in text and key not in text and "ck-" not in text


@pytest.mark.parametrize(("key", "problem"), BAD_KEYS)
def test_the_embedder_refuses_such_a_key_too(key: str, problem: str) -> None:
    with pytest.raises(ConfigError, match=problem) as info:
        OpenAIEmbedder("e", api_key=key, base_url="http://127.0.0.1:9/v1")
    assert "OPENAI_API_KEY" in str(info.value) and "ck-" not in str(info.value)


@pytest.mark.parametrize(("key", "problem"), BAD_KEYS)
@pytest.mark.parametrize("var", ["CONCEPTBOT_API_KEY", "OPENAI_API_KEY"])
def test_such_a_key_in_the_environment_is_named_by_its_variable(
    isolated_home: Path, var: str, key: str, problem: str
) -> None:
    with pytest.raises(ConfigError) as info:
        load_settings(env={"CONCEPTBOT_HOME": str(isolated_home), var: key})
    text = str(info.value)
    assert f"environment variable {var}" in text and problem in text and "ck-" not in text
