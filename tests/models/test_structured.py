import json
from typing import Any

import pytest

from conceptbot.core.errors import ConfigError, ModelOutputError
from conceptbot.models.fake import FakeLLM
from conceptbot.models.llm import ChatRequest
from conceptbot.models.structured import chat_json, parse_json
from tests.loopback import LoopbackServer, Request

SCHEMA = {
    "type": "object",
    "properties": {"dangerous": {"type": "integer", "minimum": 1, "maximum": 5}},
    "required": ["dangerous"],
}


def test_valid_reply_is_parsed_with_the_schema_attached() -> None:
    llm = FakeLLM(['{"dangerous": 4}'])
    value, _response = chat_json(llm, ChatRequest.of("knife?"), SCHEMA)
    assert value == {"dangerous": 4}
    assert json.loads(llm.requests[0].json_schema or "null") == SCHEMA


def test_malformed_reply_is_retried_with_constrained_decoding() -> None:
    llm = FakeLLM(['{"dangerous": ', '{"dangerous": 2}'])
    value, _ = chat_json(llm, ChatRequest.of("knife?", max_tokens=50), SCHEMA)
    assert value == {"dangerous": 2}
    retry = llm.requests[1]
    assert retry.json_schema is not None and retry.max_tokens == 100
    assert "not valid JSON" in retry.messages[-1].content


def test_schema_violation_counts_as_malformed() -> None:
    llm = FakeLLM(['{"dangerous": 9}', '{"dangerous": 9}'])
    with pytest.raises(ModelOutputError, match="does not match the schema"):
        chat_json(llm, ChatRequest.of("knife?"), SCHEMA)


def test_still_malformed_after_retry_is_a_clear_error() -> None:
    llm = FakeLLM(["I think it is dangerous", "Sorry, very dangerous"])
    with pytest.raises(ModelOutputError, match="did not return valid JSON") as info:
        chat_json(llm, ChatRequest.of("knife?"), SCHEMA)
    assert "Sorry, very dangerous" in str(info.value)


def test_parse_json_tolerates_fences_and_prose() -> None:
    assert parse_json('Here:\n```json\n{"a": 1}\n```') == {"a": 1}
    assert parse_json('The answer is {"a": [1, 2]} as asked.') == {"a": [1, 2]}
    with pytest.raises(ValueError):
        parse_json("no json here")


def test_usage_after_a_retry_counts_both_calls() -> None:
    llm = FakeLLM(['{"dangerous": ', '{"dangerous": 2}'])
    _, response = chat_json(llm, ChatRequest.of("is a knife dangerous?"), SCHEMA)
    # The fake counts words: the first reply is one, the second two; both prompts were read.
    assert response.usage.calls == 2
    assert response.usage.completion_tokens == 1 + 2
    both_prompts = sum(len(m.content.split()) for r in llm.requests for m in r.messages)
    assert response.usage.prompt_tokens == both_prompts


def _nested(depth: int) -> dict[str, Any]:
    schema: dict[str, Any] = {"type": "object"}
    for _ in range(depth):
        schema = {"type": "object", "properties": {"a": schema}}
    return schema


class _SchemaHost(LoopbackServer):
    """Serves a schema to whoever asks: a validator that fetches remote references would."""

    def respond(self, request: Request) -> tuple[int, dict[str, Any]]:
        return 200, {"type": "integer"}


@pytest.mark.parametrize(
    ("schema", "message"),
    [
        ([1, 2], "must be a JSON object"),
        ({"type": 12}, "not a valid JSON Schema"),
        ({"$ref": "#"}, "refers to itself without end"),
        ({"allOf": [{"$ref": "#/$defs/a"}], "$defs": {"a": {"$ref": "#"}}}, "refers to itself"),
        ({"$ref": "#/$defs/missing"}, "resolves nowhere"),
        (_nested(1500), "nested 3001 levels deep; the limit is 64"),
        ({"$ref": "other.json"}, "refers to 'other.json', outside itself"),
    ],
)
def test_unusable_schemas_are_one_clear_error_before_any_call(schema: Any, message: str) -> None:
    llm = FakeLLM(['{"a": 1}'])
    with pytest.raises(ConfigError, match=message):
        chat_json(llm, ChatRequest.of("q"), schema)
    assert llm.requests == []  # refused before the model was asked


@pytest.mark.parametrize("where", ["a", "default"])  # a property may be named like a data keyword
def test_a_remote_reference_is_refused_and_never_fetched(where: str) -> None:
    with _SchemaHost() as host:
        schema = {"type": "object", "properties": {where: {"$ref": f"{host.base_url}/x"}}}
        with pytest.raises(ConfigError, match="outside itself; references are never fetched"):
            chat_json(FakeLLM([f'{{"{where}": 1}}']), ChatRequest.of("q"), schema)
        assert host.received == []


def test_a_remote_reference_behind_an_id_is_not_fetched_either() -> None:
    # "#..." is local, but a validator resolving it against a remote $id must still not fetch.
    from conceptbot.models.structured import compile_schema  # new; imported here so the rest runs on old code

    with _SchemaHost() as host:
        validator = compile_schema({"$id": f"{host.base_url}/root", "$ref": "#/$defs/n", "$defs": {"n": {}}})
        assert validator.is_valid({"a": 1})
        assert host.received == []


def test_local_references_and_recursive_schemas_work() -> None:
    tree = {
        "$defs": {"node": {"type": "object", "properties": {"child": {"$ref": "#/$defs/node"}}}},
        "$ref": "#/$defs/node",
    }
    value, _ = chat_json(FakeLLM(['{"child": {"child": {}}}']), ChatRequest.of("q"), tree)
    assert value == {"child": {"child": {}}}
    # Data that looks like a reference is data, not a reference.
    from conceptbot.models.structured import compile_schema

    assert compile_schema({"const": {"$ref": "http://example.com/x"}}).is_valid(
        {"$ref": "http://example.com/x"}
    )


def test_a_reply_nested_past_the_limit_is_malformed_not_a_crash() -> None:
    deep = "[" * 5000 + "]" * 5000  # past the JSON decoder's recursion limit
    rather_deep = json.dumps(_nested_value(200))  # parses, but validating it would recurse 200 deep
    llm = FakeLLM([deep, rather_deep])
    with pytest.raises(ModelOutputError, match="nested 201 levels deep"):
        chat_json(llm, ChatRequest.of("q"), {"$defs": {}, "type": "object"})
    with pytest.raises(ValueError, match="no JSON object"):
        parse_json(deep)


def _nested_value(depth: int) -> dict[str, Any]:
    value: dict[str, Any] = {}
    for _ in range(depth):
        value = {"a": value}
    return value
