"""JSON replies that satisfy a schema, with one constrained retry before a clear error.

Schemas may come from a user (``conceptbot llm --schema FILE``), so :func:`compile_schema` checks
one before any model is called, and validation never leaves the schema: references are resolved
inside the document only, through a registry that refuses every retrieval (jsonschema's default
would fetch an ``http://`` ``$ref``, letting a schema file make the machine send requests).
"""

from __future__ import annotations

import functools
import json
import re
from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import jsonschema
import jsonschema.exceptions
import jsonschema.protocols
import referencing
import referencing.exceptions

from conceptbot.core.errors import ConfigError, ModelOutputError
from conceptbot.core.limits import MAX_SCHEMA_DEPTH, json_depth
from conceptbot.models.llm import LLM, ChatRequest, ChatResponse, Message

_FENCE = re.compile(r"```(?:json)?\s*(.*?)```", re.DOTALL)

MAX_REPLY_DEPTH = 64
"""Containers nested in a model's JSON reply. Validation recurses once per level (measured: a
200-level reply still validates against a recursive schema, 300 overflows the stack), so a deeper
reply is refused as malformed rather than crashing the validator."""

_REFERENCES = ("$ref", "$dynamicRef", "$recursiveRef")
# Keywords whose values are instance data, not schemas: a "$ref" key inside them is just data.
_DATA_KEYWORDS = frozenset({"const", "enum", "default", "examples"})
# Keywords whose values map names to schemas: there a key named "default" is a property's name.
_NAME_MAPS = frozenset({"properties", "patternProperties", "$defs", "definitions", "dependentSchemas"})
# A schema that makes every instance loop (``{"$ref": "#"}``) is found by validating these.
_PROBES: tuple[Any, ...] = (None, {}, [], "", 0)


def _never_retrieve(uri: str) -> referencing.Resource[Any]:
    raise referencing.exceptions.NoSuchResource(ref=uri)


_LOCAL_ONLY: referencing.Registry[Any] = referencing.Registry(retrieve=_never_retrieve)


def _outside_references(schema: Mapping[str, Any]) -> list[str]:
    """References that do not point inside the document (anything but ``#...``); iterative."""
    found: list[str] = []
    stack: list[tuple[Any, bool]] = [(schema, False)]  # (node, whether its keys are names)
    while stack:
        node, names = stack.pop()
        if isinstance(node, list):
            stack.extend((item, False) for item in node)
        elif isinstance(node, dict) and names:
            stack.extend((value, False) for value in node.values())
        elif isinstance(node, dict):
            for key, value in node.items():
                if key in _REFERENCES and isinstance(value, str) and not value.startswith("#"):
                    found.append(value)
                elif key not in _DATA_KEYWORDS:
                    stack.append((value, key in _NAME_MAPS))
    return found


def _check_shape(schema: object, where: str) -> None:
    if not isinstance(schema, Mapping):
        raise ConfigError(f"{where} must be a JSON object (a JSON Schema), not {type(schema).__name__}")
    depth = json_depth(dict(schema))
    if depth > MAX_SCHEMA_DEPTH:
        raise ConfigError(f"{where} is nested {depth} levels deep; the limit is {MAX_SCHEMA_DEPTH}")


def compile_schema(schema: object, where: str = "the schema") -> jsonschema.protocols.Validator:
    """A validator for ``schema``, after checking that it can be used safely.

    Args:
        schema: A parsed JSON Schema (any draft jsonschema knows; 2020-12 when ``$schema`` is absent).
        where: How messages name the schema (e.g. its file name).

    Returns:
        A validator whose references resolve inside the schema only; nothing is ever fetched.

    Raises:
        ConfigError: Not a JSON object, nested deeper than :data:`MAX_SCHEMA_DEPTH`, a reference
            outside the document (``http://...``, another file), not a valid schema for its draft,
            a reference that resolves nowhere, or one that refers to itself without end.
    """
    _check_shape(schema, where)
    outside = _outside_references(schema)
    if outside:
        raise ConfigError(
            f"{where} refers to {outside[0]!r}, outside itself; references are never fetched",
            hint="put the referenced schema under $defs and refer to it as '#/$defs/NAME'",
        )
    cls = jsonschema.validators.validator_for(schema, default=jsonschema.Draft202012Validator)
    try:
        cls.check_schema(schema)
    except jsonschema.exceptions.SchemaError as exc:
        raise ConfigError(f"{where} is not a valid JSON Schema: {exc.message}") from None
    validator = cls(schema, registry=_LOCAL_ONLY)
    for probe in _PROBES:
        _validate(validator, probe, where)
    return validator


def _validate(validator: jsonschema.protocols.Validator, value: Any, where: str) -> str | None:
    """The best validation error's message for ``value``, or None when it matches.

    Raises:
        ConfigError: The schema's references loop or resolve nowhere (the schema's fault, not the
            reply's: the reply's depth is bounded before it gets here).
    """
    try:
        error = jsonschema.exceptions.best_match(validator.iter_errors(value))
    except RecursionError:
        raise ConfigError(f"{where} refers to itself without end (e.g. {{'$ref': '#'}})") from None
    except referencing.exceptions.Unresolvable as exc:
        raise ConfigError(f"{where} has a reference that resolves nowhere: {exc}") from None
    return None if error is None else error.message


@functools.lru_cache(maxsize=256)
def _compiled(schema_text: str) -> jsonschema.protocols.Validator:
    # Checking a schema against its metaschema costs more than validating a reply; OPE asks with
    # the same few schemas for every object.
    return compile_schema(json.loads(schema_text))


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
        except (ValueError, RecursionError):  # the C decoder recurses: "[[[[..." past ~1000 levels
            continue
    raise ValueError("no JSON object in the reply")


def _check(text: str, validator: jsonschema.protocols.Validator) -> tuple[Any, str | None]:
    try:
        value = parse_json(text)
    except ValueError as exc:
        return None, str(exc)
    depth = json_depth(value)
    if depth > MAX_REPLY_DEPTH:
        return None, f"the JSON is nested {depth} levels deep (at most {MAX_REPLY_DEPTH})"
    problem = _validate(validator, value, "the schema")
    if problem is not None:
        return None, f"does not match the schema: {problem}"
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
        ConfigError: ``schema`` cannot be used (see :func:`compile_schema`); raised before any call.
        ModelOutputError: Still no valid JSON after the retry (the message quotes the reply).
    """
    _check_shape(schema, "the schema")  # before json.dumps, which recurses
    schema_text = json.dumps(schema, sort_keys=True, separators=(",", ":"))
    validator = _compiled(schema_text)
    first = replace(request, json_schema=schema_text if llm.capabilities.json_schema else None)
    response = llm.chat(first)
    value, problem = _check(response.text, validator)
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
    value, problem = _check(response.text, validator)
    if problem is None:
        return value, replace(response, usage=spent + response.usage)
    excerpt = response.text[:200].replace("\n", " ")
    raise ModelOutputError(
        f"{llm.backend}:{llm.model} did not return valid JSON after a constrained retry ({problem}); "
        f"reply began: {excerpt!r}",
        hint="try a larger model, or raise max_tokens if the reply was cut off",
    )
