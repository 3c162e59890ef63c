"""The JSON payloads of the ROS 2 node: a request in, progress and a result out.

Every message is a ``std_msgs/msg/String`` whose ``data`` is one JSON object (docs/ros2.md says
why: custom interfaces need rosidl code generation with CMake and a compiler, which the installable
wheels do not carry). This module parses and validates a request and builds the outgoing payloads;
it imports no ROS, so it is unit-tested without ROS 2 and any client can follow it::

    {"id": "r1", "request": "Give me something to drink", "scene": "kitchen"}      # on ~/request
    {"id": "r1", "kind": "progress", "message": "Decide: ..."}                     # on ~/progress
    {"id": "r1", "kind": "event", "module": "decisions", "data": {...}}            # on ~/progress
    {"id": "r1", "ok": true, "plan": {...the plan --json object...}}               # on ~/result
    {"id": "r1", "ok": false, "error": {"code": "busy", "message": "...", "hint": "..."}}

``scene`` is a scene in the scene-file format (:mod:`conceptbot.core.scene`) or the name of a demo
scene; left out, the node's default scene. A name is looked up among the demo scenes only: a
request never makes the node read a file of its choosing.
"""

from __future__ import annotations

import json
import uuid
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from conceptbot.core.errors import ConceptBotError, ConfigError
from conceptbot.core.limits import (
    MAX_JSON_DEPTH,
    MAX_OBJECTS,
    MAX_SCENE_FILE_BYTES,
    check_request,
    json_depth,
)
from conceptbot.core.observe import EventPart
from conceptbot.core.plan import Plan
from conceptbot.core.scene import Scene, scene_from_dict
from conceptbot.core.trace import ClarifyingQuestion
from conceptbot.scenes import load_demo_scene

ERROR_CODES = ("bad_request", "unknown_object", "busy", "planner_error", "timeout", "no_answer")
"""What a failed result's ``error.code`` can be."""

MAX_PAYLOAD_BYTES = MAX_SCENE_FILE_BYTES + 4096
"""Size of one request message: one scene file's worth plus the request and its id."""
MAX_ID_CHARS = 100
"""Characters in a request id."""

QOS_DEPTH = 100
"""History depth of the node's topics (all reliable; the replies transient local, see ``qos``): a
plan sends a few dozen progress messages in a burst, and a reader that falls more than this far
behind loses the oldest."""

REQUEST_KEYS = ("id", "request", "scene")
"""The keys a request may have (others are refused, so a misspelt key is not silently ignored)."""


@dataclass(frozen=True)
class PlanRequest:
    """A validated request.

    Attributes:
        id: The client's id (echoed in every reply), or one generated for it.
        request: What the person asked for, stripped.
        scene: The scene to plan in: the one sent, or the node's default.
    """

    id: str
    request: str
    scene: Scene


class ProtocolError(ConceptBotError):
    """A request the node cannot plan; it becomes an error result on ``~/result``.

    Args:
        code: One of :data:`ERROR_CODES`.
        message: What went wrong.
        request_id: The request's id (a generated one when it had none or could not be read).
        hint: How to fix it, or None.
    """

    def __init__(self, code: str, message: str, request_id: str, *, hint: str | None = None) -> None:
        super().__init__(message, hint=hint)
        self.code = code
        self.request_id = request_id


def new_id() -> str:
    """An id for a request that came without one."""
    return f"req-{uuid.uuid4().hex[:12]}"


def parse_request(payload: str, default_scene: Scene) -> PlanRequest:
    """Read and validate one request message.

    Args:
        payload: The message's ``data``: a JSON object with ``request`` and optionally ``id`` and
            ``scene``.
        default_scene: The scene when the request names none.

    Returns:
        The request, its scene built and validated.

    Raises:
        ProtocolError: ``bad_request`` for anything malformed (not JSON, not an object, a missing or
            empty request, wrong types, an unknown key, over the size limits, an invalid scene or an
            unknown demo scene name); ``unknown_object`` when the scene gives a state or detection
            to an object it does not list. The message is the scene loader's where it found it.
    """
    request_id = new_id()
    if len(payload.encode("utf-8")) > MAX_PAYLOAD_BYTES:
        raise ProtocolError(
            "bad_request",
            f"the message is larger than {MAX_PAYLOAD_BYTES:,} bytes",
            request_id,
            hint=f"send a scene of at most {MAX_OBJECTS} objects",
        )
    try:
        data = json.loads(payload)
    except RecursionError:
        raise ProtocolError("bad_request", "the message is nested too deeply", request_id) from None
    except ValueError as exc:
        raise ProtocolError(
            "bad_request",
            f"the message is not valid JSON: {exc}",
            request_id,
            hint='send {"id": "r1", "request": "...", "scene": "kitchen"}',
        ) from None
    if not isinstance(data, dict):
        raise ProtocolError("bad_request", "the message must be a JSON object", request_id)
    request_id = _request_id(data.get("id"), request_id)
    unknown = sorted(k for k in data if k not in REQUEST_KEYS)
    if unknown:
        raise ProtocolError(
            "bad_request",
            f"unknown key(s) {', '.join(map(repr, unknown))}",
            request_id,
            hint=f"a request has the keys {', '.join(REQUEST_KEYS)}",
        )
    if json_depth(data) > MAX_JSON_DEPTH:
        raise ProtocolError(
            "bad_request", f"the message is nested more than {MAX_JSON_DEPTH} levels", request_id
        )
    if "request" not in data:
        raise ProtocolError(
            "bad_request", "the message has no 'request'", request_id, hint="say what the robot should do"
        )
    try:
        text = check_request(data["request"])
    except ConfigError as exc:
        raise ProtocolError("bad_request", exc.message, request_id, hint=exc.hint) from None
    return PlanRequest(request_id, text, _scene(data.get("scene"), default_scene, request_id))


def _request_id(value: object, generated: str) -> str:
    """The client's id, or ``generated`` when it sent none."""
    if value is None:
        return generated
    if not isinstance(value, str) or not value.strip():
        raise ProtocolError("bad_request", "'id' must be a non-empty string", generated)
    if len(value) > MAX_ID_CHARS or not value.isprintable():
        raise ProtocolError(
            "bad_request",
            f"'id' must be printable and at most {MAX_ID_CHARS} characters",
            generated,
        )
    return value


def _scene(value: object, default: Scene, request_id: str) -> Scene:
    """The request's scene: a scene dict, a demo scene name, or (None) the default."""
    if value is None:
        return default
    if isinstance(value, str):
        try:
            return load_demo_scene(value)
        except ConfigError as exc:
            # The loader's hint offers a file path too; a request cannot name a file.
            raise ProtocolError(
                "bad_request", exc.message, request_id, hint="send a demo scene's name or the scene itself"
            ) from None
    if not isinstance(value, Mapping):
        raise ProtocolError(
            "bad_request",
            "'scene' must be a scene object or the name of a demo scene",
            request_id,
            hint='e.g. "scene": {"pickable_objects": ["apple"], "destinations": ["user"]}',
        )
    try:
        return scene_from_dict(value, where="scene")
    except ConfigError as exc:
        code = "unknown_object" if _unlisted_names(value) else "bad_request"
        raise ProtocolError(code, exc.message, request_id, hint=exc.hint) from None


def _unlisted_names(data: Mapping[str, Any]) -> list[str]:
    """Names that have a state or detection but are not listed as objects (the loader's check,
    repeated here only to tell this error apart from a malformed scene)."""
    listed: set[str] = set()
    for key in ("objects", "pickable_objects", "destinations"):
        names = data.get(key)
        if isinstance(names, list):
            listed |= {n.strip() for n in names if isinstance(n, str)}
    named: list[str] = []
    for key in ("entity_states", "detections"):
        part = data.get(key)
        if isinstance(part, Mapping):
            named += [n for n in part if isinstance(n, str)]
    return [n for n in named if n not in listed]


def progress_payload(request_id: str, message: str) -> dict[str, Any]:
    """A progress message of the plan for ``request_id`` (a piece of work starts)."""
    return {"id": request_id, "kind": "progress", "message": message}


def event_payload(request_id: str, module: str, part: EventPart) -> dict[str, Any]:
    """A module of the plan for ``request_id`` finished; ``part`` is its part of the trace (serialised
    here, at the node's edge)."""
    return {"id": request_id, "kind": "event", "module": module, "data": part.to_dict()}


def question_payload(request_id: str, question: ClarifyingQuestion) -> dict[str, Any]:
    """A question of the plan for ``request_id``, where the planner is unsure; answer it on
    ``~/answer`` with :func:`parse_answer`'s form."""
    return {"id": request_id, "kind": "question", "question": question.to_dict()}


MAX_ANSWER = 4000  # characters: the longest answer names every option of a choose question


def parse_answer(payload: str) -> tuple[str, str]:
    """``(request id, answer)`` from an ``~/answer`` message ``{"id": ..., "answer": ...}``; the node
    checks the answer against the open question (:meth:`ClarifyingQuestion.read`: ``yes`` or ``no``,
    or for a ``choose`` question the objects that go joined by ", ", or ``none``).

    Raises:
        ProtocolError: Not JSON, no id, or an answer that is not a non-empty string of at most
            :data:`MAX_ANSWER` characters (``bad_request``).
    """
    try:
        data = json.loads(payload)
    except (json.JSONDecodeError, RecursionError):
        raise ProtocolError("bad_request", "an answer must be a JSON object", "?") from None
    if not isinstance(data, dict) or not isinstance(data.get("id"), str) or not data["id"]:
        raise ProtocolError("bad_request", 'an answer is {"id": <request id>, "answer": <text>}', "?")
    answer = data.get("answer")
    if not isinstance(answer, str) or not answer.strip() or len(answer) > MAX_ANSWER:
        raise ProtocolError(
            "bad_request",
            f"an answer is yes, no, or the objects that go, or none; got {answer!r:.80}",
            data["id"],
        )
    return data["id"], answer.strip()


def result_payload(request_id: str, plan: Plan) -> dict[str, Any]:
    """The plan for ``request_id``: ``plan`` is the ``conceptbot plan --json`` object."""
    return {"id": request_id, "ok": True, "plan": plan.to_dict()}


def error_payload(request_id: str, code: str, message: str, hint: str | None = None) -> dict[str, Any]:
    """A failed request.

    Args:
        request_id: The request's id.
        code: One of :data:`ERROR_CODES`.
        message: What went wrong.
        hint: How to fix it, or None.

    Returns:
        ``{"id", "ok": false, "error": {"code", "message", "hint"}}``.

    Raises:
        ValueError: ``code`` is not one of :data:`ERROR_CODES` (a bug in the node, not the client).
    """
    if code not in ERROR_CODES:
        raise ValueError(f"unknown error code {code!r}")
    return {"id": request_id, "ok": False, "error": {"code": code, "message": message, "hint": hint}}


def encode(payload: Mapping[str, Any]) -> str:
    """One payload as the ``data`` of a String message (UTF-8 JSON, no ASCII escaping)."""
    return json.dumps(payload, ensure_ascii=False)
