"""A small OpenAI-format HTTP server on loopback for backend tests (real HTTP, scripted replies)."""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

from tests.loopback import LoopbackServer, Request

Handler = Callable[[dict[str, Any]], tuple[int, dict[str, Any]]]


def completion(texts: list[str], prompt_tokens: int = 7, completion_tokens: int = 3) -> dict[str, Any]:
    """A chat.completion body with the given choices."""
    return {
        "id": "chatcmpl-1",
        "object": "chat.completion",
        "created": 0,
        "model": "stub",
        "choices": [
            {"index": i, "message": {"role": "assistant", "content": t}, "finish_reason": "stop"}
            for i, t in enumerate(texts)
        ],
        "usage": {
            "prompt_tokens": prompt_tokens,
            "completion_tokens": completion_tokens,
            "total_tokens": prompt_tokens + completion_tokens,
        },
    }


def text_completion(text: str, logprobs: dict[str, Any], prompt_tokens: int) -> dict[str, Any]:
    """A text_completion body with one choice and its ``logprobs`` block."""
    return {
        "id": "cmpl-1",
        "object": "text_completion",
        "created": 0,
        "model": "stub",
        "choices": [{"index": 0, "text": text, "finish_reason": "length", "logprobs": logprobs}],
        "usage": {"prompt_tokens": prompt_tokens, "completion_tokens": 1, "total_tokens": prompt_tokens + 1},
    }


def echo_reply(prompt: str, logprobs: list[float | None], offsets: list[int]) -> dict:
    """A text_completion body echoing ``prompt`` as tokens at ``offsets`` (one token generated)."""
    block = {
        "tokens": ["t"] * (len(offsets) + 1),
        "text_offset": [*offsets, len(prompt)],
        "token_logprobs": [*logprobs, -0.5],
        "top_logprobs": None,
    }
    return text_completion(prompt + "!", block, len(offsets))


def top_reply(tokens: dict[str, float]) -> dict:
    """A chat.completion body whose first token has ``tokens`` as its top log-probabilities."""
    body = completion([max(tokens, key=tokens.get)])
    entries = [{"token": t, "logprob": lp, "bytes": None, "top_logprobs": []} for t, lp in tokens.items()]
    body["choices"][0]["logprobs"] = {"content": [{**entries[0], "top_logprobs": entries}]}
    return body


def next_reply(tokens: dict[str, float]) -> dict:
    """A text_completion body (no echo) whose one generated token has ``tokens`` as its top
    log-probabilities, as llama.cpp and vLLM servers answer ``logprobs: N``."""
    best = max(tokens, key=tokens.get) if tokens else ""
    block = {
        "tokens": [best],
        "text_offset": [0],
        "token_logprobs": [tokens.get(best)],
        "top_logprobs": [tokens],
    }
    return text_completion(best, block, 9)


class StubServer(LoopbackServer):
    """Serves POST /v1/chat/completions from a queue of handlers; records request bodies and headers."""

    def __init__(self, handlers: list[Handler]) -> None:
        super().__init__()
        self.handlers = list(handlers)
        self.bodies: list[dict[str, Any]] = []
        self.headers: list[dict[str, str]] = []

    def respond(self, request: Request) -> tuple[int, bytes | dict[str, Any]]:
        """The next scripted handler's answer to the JSON body (500 when none is left)."""
        body = json.loads(request.body or b"{}")
        self.bodies.append(body)
        self.headers.append(request.headers)
        return self.handlers.pop(0)(body) if self.handlers else (500, {"error": {"message": "no more"}})

    @property
    def url(self) -> str:
        """The stub's OpenAI-style base URL."""
        return f"{self.base_url}/v1"
