"""A loopback OpenAI-style server that misbehaves on demand, in the real wire format.

The first part of the request path picks the behaviour, so one server serves every case:
``{server.base_url}/MODE/v1`` is an OpenAI-compatible base URL. Modes:

* ``ok``: chat completions answer "Yes" (with top log-probabilities when asked); a JSON-schema
  request gets an instance of the schema (integers 1, strings "x"); ``/models`` lists model ``m``.
* ``lp_nan``, ``lp_neginf``, ``lp_posinf``: like ``ok``, but every log-probability is NaN, -inf or
  +inf (written as the bare tokens ``NaN`` and ``-1e999``/``1e999`` that Python's and most servers'
  JSON writers emit); JSON-schema requests get a Risk Index answer rating the object 1.
* ``e500raw``: HTTP 500 whose message echoes the request's ``Authorization`` value without
  ``Bearer `` ("boom for key ck-456"); ``e400raw``: 400 with "key=K token K".
* ``ansi``: HTTP 500 whose message holds terminal escapes (OSC title, clear screen, colour) and
  Rich markup.
* ``slow/SECONDS``: waits, then answers like ``ok``.

Every request is recorded (:attr:`LoopbackServer.received`).
"""

from __future__ import annotations

import json
import time
from typing import Any

from tests.loopback import LoopbackServer, Request

ANSI = "\x1b]0;pwned\x07\x1b[2J\x1b[31mevil [/x] [bold]"
RISK_ONE = {"object": "x", "dangerous": 1, "dangerous_with": [], "reason": "harmless"}
NON_FINITE = {"lp_nan": "NaN", "lp_neginf": "-1e999", "lp_posinf": "1e999"}


def _instance(schema: dict[str, Any]) -> Any:
    if "enum" in schema:
        return schema["enum"][0]
    kind = schema.get("type")
    if kind == "object":
        return {k: _instance(v) for k, v in schema.get("properties", {}).items()}
    return {"array": [], "integer": 1, "number": 0.5, "boolean": False}.get(str(kind), "x")


def _completion(model: str, content: str, n: int = 1, logprob: str | None = None) -> str:
    """A chat.completion body as text; ``logprob`` (a JSON number token) makes a logprobs block."""
    choices = []
    for i in range(n):
        choice: dict[str, Any] = {
            "index": i,
            "message": {"role": "assistant", "content": content},
            "finish_reason": "stop",
        }
        if logprob is not None:
            top = [{"token": t, "logprob": "@LP@", "bytes": None} for t in ("Yes", "No")]
            choice["logprobs"] = {
                "content": [{"token": "Yes", "logprob": "@LP@", "bytes": None, "top_logprobs": top}]
            }
        choices.append(choice)
    body = {
        "id": "x",
        "object": "chat.completion",
        "created": 1,
        "model": model,
        "choices": choices,
        "usage": {"prompt_tokens": 5, "completion_tokens": 1, "total_tokens": 6},
    }
    return json.dumps(body).replace('"@LP@"', logprob or "-0.1")


class MisbehavingServer(LoopbackServer):
    """Answers by the path's first part (see the module docstring)."""

    def url(self, mode: str) -> str:
        """The OpenAI-style base URL of one behaviour (``url("lp_nan")``)."""
        return f"{self.base_url}/{mode}/v1"

    def respond(self, request: Request) -> tuple[int, bytes | dict[str, Any]]:
        """The reply for ``request`` (see the module docstring)."""
        parts = request.path.strip("/").split("/")
        mode = parts[0] if parts else ""
        try:
            body = json.loads(request.body or b"{}")
        except ValueError:
            body = {}
        model = str(body.get("model", "m"))
        key = request.headers.get("authorization", "none").replace("Bearer ", "")
        if mode == "slow":
            time.sleep(float(parts[1]) if len(parts) > 1 else 30.0)
            mode = "ok"
        if mode == "e500raw":
            return 500, {"error": {"message": f"boom for key {key}"}}
        if mode == "e400raw":
            return 400, {"error": {"message": f"bad request from key={key} token {key}"}}
        if mode == "ansi":
            return 500, {"error": {"message": ANSI}}
        if mode not in ("ok", *NON_FINITE):
            return 404, {"error": {"message": f"unknown mode {mode}"}}
        if request.path.endswith("/models"):
            return 200, {
                "object": "list",
                "data": [{"id": "m", "object": "model", "created": 1, "owned_by": "x"}],
            }
        if request.path.endswith("/completions") and "chat" not in request.path:
            return 404, {"error": {"message": "no completions endpoint"}}
        if body.get("response_format"):
            fmt = body["response_format"]
            schema = (fmt.get("json_schema") or {}).get("schema") or fmt.get("schema") or {}
            answer = _instance(schema) if mode == "ok" else RISK_ONE
            return 200, _completion(model, json.dumps(answer)).encode()
        logprob = None
        if body.get("logprobs"):
            logprob = NON_FINITE.get(mode, "-0.1")
        return 200, _completion(model, "Yes", int(body.get("n") or 1), logprob).encode()
