import json

import pytest

from conceptbot.core.errors import ModelOutputError
from conceptbot.models.fake import FakeLLM
from conceptbot.models.llm import ChatRequest
from conceptbot.models.structured import chat_json, parse_json

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
