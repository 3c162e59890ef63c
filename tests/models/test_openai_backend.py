import socket

import pytest

from conceptbot.core.errors import BackendRequestError, BackendUnavailableError, NotSupportedError
from conceptbot.models.llm import ChatRequest, ScoreRequest
from conceptbot.models.openai_backend import OpenAILLM
from tests.models.openai_stub import StubServer, completion


def _llm(url: str, **kwargs) -> OpenAILLM:
    return OpenAILLM(
        "stub-model",
        backend="openai-compatible",
        base_url=url,
        api_key="sk-test-secret",
        timeout_s=5,
        max_retries=kwargs.pop("max_retries", 0),
        **kwargs,
    )


def test_chat_sends_parameters_and_reads_usage() -> None:
    with StubServer([lambda body: (200, completion(["pick_and_place(apple, user)"]))]) as server:
        response = _llm(server.url).chat(
            ChatRequest.of("Bring me a fruit", system="You are a robot.", max_tokens=40, stop=["\n"], seed=3)
        )
    assert response.text == "pick_and_place(apple, user)"
    assert (response.usage.prompt_tokens, response.usage.completion_tokens) == (7, 3)
    body = server.bodies[0]
    assert body["model"] == "stub-model" and body["max_tokens"] == 40 and body["stop"] == ["\n"]
    assert [m["role"] for m in body["messages"]] == ["system", "user"]
    assert server.headers[0]["authorization"] == "Bearer sk-test-secret"


def test_servers_that_ignore_n_are_asked_again_with_new_seeds() -> None:
    reply = lambda body: (200, completion([f"answer {body['seed']}"]))  # noqa: E731
    with StubServer([reply, reply, reply]) as server:
        response = _llm(server.url).chat(ChatRequest.of("q", n=3, temperature=0.7, seed=10))
    assert response.choices == ("answer 10", "answer 11", "answer 12")
    assert response.usage.calls == 3


def test_json_schema_falls_back_to_llama_cpp_server_style() -> None:
    schema = {"type": "object", "properties": {"a": {"type": "integer"}}}
    handlers = [
        lambda body: (422, {"detail": [{"msg": "Input should be 'text' or 'json_object'"}]}),
        lambda body: (200, completion(['{"a": 1}'])),
        lambda body: (200, completion(['{"a": 2}'])),
    ]
    with StubServer(handlers) as server:
        llm = _llm(server.url)
        llm.chat(ChatRequest.of("q", json_schema=schema))
        llm.chat(ChatRequest.of("q", json_schema=schema))
    assert server.bodies[0]["response_format"]["type"] == "json_schema"
    assert server.bodies[1]["response_format"] == {"type": "json_object", "schema": schema}
    assert server.bodies[2]["response_format"]["type"] == "json_object"  # remembered


def test_retries_are_bounded_and_succeed_after_a_server_error() -> None:
    handlers = [lambda body: (503, {"error": {"message": "busy"}}), lambda body: (200, completion(["ok"]))]
    with StubServer(handlers) as server:
        assert _llm(server.url, max_retries=2).chat(ChatRequest.of("q")).text == "ok"
    assert len(server.bodies) == 2


def test_persistent_server_error_is_a_clear_error() -> None:
    handlers = [lambda body: (500, {"error": {"message": "kaput"}})] * 2
    with StubServer(handlers) as server, pytest.raises(BackendRequestError, match="HTTP 500: kaput"):
        _llm(server.url, max_retries=1).chat(ChatRequest.of("q"))
    assert len(server.bodies) == 2


def test_bad_key_message_never_contains_the_key() -> None:
    handlers = [lambda body: (401, {"error": {"message": "bad key sk-test-secret"}})]
    with StubServer(handlers) as server, pytest.raises(BackendRequestError) as info:
        _llm(server.url).chat(ChatRequest.of("q"))
    assert "sk-test-secret" not in str(info.value)
    assert "refused the API key" in str(info.value)


def test_server_down_is_backend_unavailable() -> None:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    with pytest.raises(BackendUnavailableError, match="cannot connect"):
        _llm(f"http://127.0.0.1:{port}/v1").chat(ChatRequest.of("q"))


def test_scoring_is_reported_as_not_supported() -> None:
    llm = _llm("http://127.0.0.1:1/v1")
    assert llm.capabilities.scoring is False
    with pytest.raises(NotSupportedError, match="cannot score"):
        llm.score(ScoreRequest(options=("a",), prompt="p"))
