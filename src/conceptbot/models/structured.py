"""JSON replies that satisfy a schema, with one constrained retry before a clear error."""

from __future__ import annotations

import json
import re
from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import jsonschema

from conceptbot.core.errors import ModelOutputError
from conceptbot.models.llm import LLM, ChatRequest, ChatResponse, Message

_FENCE = re.compile(r"```(?:json)?\s*(.*?)```", re.DOTALL)


def parse_json(text: str) -> Any:
    """Parse a JSON value from a reply, tolerating code fences and prose around one object.

    Raises:
        ValueError: No JSON value could be parsed.
    """
    candidates = [text.strip()]
    candidates += [m.strip() for m in _FENCE.findall(text)]
    start, end = text.find("{"), text.rfind("}")
    if 0 <= start < end:
        candidates.append(text[start : end + 1])
    for candidate in candidates:
        try:
            return json.loads(candidate)
        except ValueError:
            continue
    raise ValueError("no JSON object in the reply")


def _check(text: str, schema: Mapping[str, Any]) -> tuple[Any, str | None]:
    try:
        value = parse_json(text)
    except ValueError as exc:
        return None, str(exc)
    try:
        jsonschema.validate(value, schema)
    except jsonschema.ValidationError as exc:
        return None, f"does not match the schema: {exc.message}"
    return value, None


def chat_json(llm: LLM, request: ChatRequest, schema: Mapping[str, Any]) -> tuple[Any, ChatResponse]:
    """Ask for a JSON reply matching ``schema``; return the parsed value of the first choice.

    The first attempt uses constrained decoding where the backend supports it. If the reply is not
    valid JSON for the schema (truncated, or the backend could not constrain it), one retry runs
    with constrained decoding, twice the token budget, a new seed and a reminder of the schema.

    Returns:
        The parsed value and the response it came from. After a retry, the response's usage is the
        sum of both attempts (the first call's tokens and seconds were spent too).

    Raises:
        ModelOutputError: Still no valid JSON after the retry (the message quotes the reply).
    """
    schema_text = json.dumps(schema, sort_keys=True, separators=(",", ":"))
    first = replace(request, json_schema=schema_text if llm.capabilities.json_schema else None)
    response = llm.chat(first)
    value, problem = _check(response.text, schema)
    if problem is None:
        return value, response
    reminder = Message(
        "user",
        "Your previous reply was not valid JSON for the required schema "
        f"({problem}). Reply with only a JSON object matching this schema:\n{schema_text}",
    )
    retry = replace(
        request,
        messages=(*request.messages, Message("assistant", response.text[:2000]), reminder),
        json_schema=schema_text,
        max_tokens=request.max_tokens * 2,
        seed=request.seed + 7919,
    )
    spent = response.usage
    response = llm.chat(retry)
    value, problem = _check(response.text, schema)
    if problem is None:
        return value, replace(response, usage=spent + response.usage)
    excerpt = response.text[:200].replace("\n", " ")
    raise ModelOutputError(
        f"{llm.backend}:{llm.model} did not return valid JSON after a constrained retry ({problem}); "
        f"reply began: {excerpt!r}",
        hint="try a larger model, or raise max_tokens if the reply was cut off",
    )
