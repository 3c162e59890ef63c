"""The LLM protocol used by the whole product, and the data that crosses it.

Two operations, and one way to label calls:

* :meth:`LLM.chat` — chat completion with ``n`` choices, temperature, ``max_tokens``, stop strings
  and optional JSON-schema-constrained output.
* :meth:`LLM.score` — the log-probability of each candidate continuation after a prompt (SayCan-style
  option scoring, the Planner's one-pass scoring). Backends that cannot do this raise
  :class:`~conceptbot.core.errors.NotSupportedError`; check ``capabilities.scoring`` first.
* :meth:`LLM.with_module` — the same model, its calls labelled with a pipeline module's name (the
  cache wrapper writes the label to the call log; a plain backend returns itself).

Requests and responses are frozen dataclasses; no backend-specific (OpenAI-shaped) dicts leave a
backend.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, Protocol, runtime_checkable

from conceptbot.core.errors import ModelOutputError
from conceptbot.core.usage import Usage

Role = Literal["system", "user", "assistant"]


@dataclass(frozen=True)
class Message:
    """One chat message."""

    role: Role
    content: str


def _freeze_schema(schema: Mapping[str, Any] | str | None) -> str | None:
    if schema is None or isinstance(schema, str):
        return schema
    return json.dumps(schema, sort_keys=True, separators=(",", ":"))


@dataclass(frozen=True)
class ChatRequest:
    """A chat-completion request.

    Attributes:
        messages: The conversation, oldest first.
        n: Number of independent completions wanted.
        temperature: Sampling temperature (0 = greedy).
        max_tokens: Upper bound on generated tokens per completion.
        stop: Strings that end a completion (not included in the text).
        json_schema: A JSON schema (canonical JSON text) the reply must satisfy, or ``None``.
        seed: Base random seed; completion ``i`` uses ``seed + i`` where a backend loops.
    """

    messages: tuple[Message, ...]
    n: int = 1
    temperature: float = 0.0
    max_tokens: int = 256
    stop: tuple[str, ...] = ()
    json_schema: str | None = None
    seed: int = 0

    @classmethod
    def of(
        cls,
        messages: Sequence[Message] | str,
        *,
        system: str | None = None,
        json_schema: Mapping[str, Any] | str | None = None,
        stop: Sequence[str] = (),
        **params: Any,
    ) -> ChatRequest:
        """Build a request from a prompt string or messages, with an optional system message."""
        if isinstance(messages, str):
            messages = [Message("user", messages)]
        msgs = ([Message("system", system)] if system else []) + list(messages)
        return cls(messages=tuple(msgs), json_schema=_freeze_schema(json_schema), stop=tuple(stop), **params)

    def schema(self) -> dict[str, Any] | None:
        """The JSON schema as a dict, or ``None``."""
        return None if self.json_schema is None else json.loads(self.json_schema)

    def canonical(self) -> dict[str, Any]:
        """A JSON-able description of the request, used for cache keys (no secrets in it)."""
        return {
            "messages": [[m.role, m.content] for m in self.messages],
            "n": self.n,
            "temperature": self.temperature,
            "max_tokens": self.max_tokens,
            "stop": list(self.stop),
            "json_schema": self.json_schema,
            "seed": self.seed,
        }


@dataclass(frozen=True)
class ChatResponse:
    """The reply to a :class:`ChatRequest`.

    Attributes:
        choices: The ``n`` completion texts.
        usage: Tokens, latency and cost of producing them.
        backend: Backend name (``llamacpp``, ``openai``, ...).
        model: Model identifier as the backend knows it.
        cached: True when the reply came from the response cache.
        finish_reasons: Per choice, why generation stopped (``stop``, ``length``, ...).
    """

    choices: tuple[str, ...]
    usage: Usage
    backend: str
    model: str
    cached: bool = False
    finish_reasons: tuple[str, ...] = ()

    @property
    def text(self) -> str:
        """The first choice."""
        return self.choices[0]


@dataclass(frozen=True)
class ScoreRequest:
    """Score candidate continuations of one prompt by token log-probabilities.

    Exactly one of ``messages`` (rendered with the model's chat template, generation prompt added,
    then ``assistant_prefix``) or ``prompt`` (raw text, for completion-style prompts such as
    SayCan's) is given.

    Attributes:
        options: The candidate continuations, scored independently.
        messages: Chat messages that form the prompt.
        prompt: Raw prompt text.
        assistant_prefix: Text the assistant's reply starts with before the option.
        priors: Log-weights the caller will multiply the options' probabilities by (SayCan's
            affordances; ``-inf`` for an option it will never take), or None. A backend that
            scores every option exactly ignores them; one that scores only the best exactly (the
            HTTP ``search``) finds the best by probability times weight.
    """

    options: tuple[str, ...]
    messages: tuple[Message, ...] | None = None
    prompt: str | None = None
    assistant_prefix: str = ""
    priors: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        if (self.messages is None) == (self.prompt is None):
            raise ValueError("ScoreRequest needs exactly one of messages or prompt")
        if not self.options:
            raise ValueError("ScoreRequest needs at least one option")
        if self.priors is not None and len(self.priors) != len(self.options):
            raise ValueError("ScoreRequest needs one prior per option")

    def canonical(self, with_priors: bool = True) -> dict[str, Any]:
        """A JSON-able description of the request, used for cache keys (``with_priors=False``: for
        a backend that ignores them, so the same scores are one cache entry)."""
        out: dict[str, Any] = {
            "options": list(self.options),
            "messages": None if self.messages is None else [[m.role, m.content] for m in self.messages],
            "prompt": self.prompt,
            "assistant_prefix": self.assistant_prefix,
        }
        if with_priors and self.priors is not None:
            out["priors"] = [p if math.isfinite(p) else None for p in self.priors]  # JSON has no -inf
        return out


@dataclass(frozen=True)
class ScoreResponse:
    """Log-probabilities of each option (same order as the request).

    Attributes:
        logprobs: Sum of the option's token log-probabilities (natural log).
        token_counts: Number of tokens of each option.
        usage: Tokens and latency of scoring.
        backend: Backend name.
        model: Model identifier.
        cached: True when the result came from the cache.
        method: How the options were scored: ``logprob`` (exact, embedded), or over HTTP ``echo``,
            ``search``, ``chat-logprobs`` or ``vote`` (:mod:`conceptbot.models.http_scoring`).
    """

    logprobs: tuple[float, ...]
    token_counts: tuple[int, ...]
    usage: Usage
    backend: str
    model: str
    cached: bool = False
    method: str = "logprob"

    def __post_init__(self) -> None:
        # A NaN compares False with every threshold, so a risk check reading it would pass the move;
        # a non-finite score is the backend's error, raised where every scorer's answer arrives.
        bad = [lp for lp in self.logprobs if not math.isfinite(lp)]
        if bad:
            raise ModelOutputError(
                f"the {self.backend} backend ({self.model}) returned a non-finite log-probability "
                f"({bad[0]!r}) for {len(bad)} of {len(self.logprobs)} options",
                hint="the server's numbers overflowed or are broken (fp16?); try another model or "
                "CONCEPTBOT_SCORING=vote",
            )


@dataclass(frozen=True)
class Capabilities:
    """What a backend can do.

    Attributes:
        scoring: It scores options (:meth:`LLM.score`).
        exact_scoring: Every option's own token log-probabilities, as in the embedded backend; an
            HTTP backend may score many options only as a lettered choice (see
            :mod:`conceptbot.models.http_scoring`), which the paper's Planner should not prefer to
            its votes.
        json_schema: It constrains output to a JSON schema.
        native_n: It returns ``n`` completions in one call.
        extra: Anything backend-specific.
    """

    scoring: bool = False
    exact_scoring: bool = False
    json_schema: bool = False
    native_n: bool = False
    extra: Mapping[str, Any] = field(default_factory=dict)


@runtime_checkable
class LLM(Protocol):
    """A language model backend.

    Attributes:
        backend: Registry name of the backend (``llamacpp``, ``openai``, ``openai-compatible``, ``fake``).
        model: Model identifier.
        capabilities: What the backend supports.
    """

    backend: str
    model: str
    capabilities: Capabilities

    def chat(self, request: ChatRequest) -> ChatResponse:
        """Complete a chat.

        Raises:
            BackendUnavailableError: The backend cannot be reached or loaded.
            BackendRequestError: The backend refused the request.
        """
        ...

    def score(self, request: ScoreRequest) -> ScoreResponse:
        """Log-probability of each option after the prompt.

        Raises:
            NotSupportedError: The backend cannot return token log-probabilities.
        """
        ...

    def with_module(self, module: str) -> LLM:
        """The same model, with its calls labelled ``module`` (``ope``, ``urp``, ``planner``, ...).

        Every stage of a pipeline asks for its own labelled view, so the call log says which module
        spent the tokens. A backend without a call log returns itself; the cache wrapper
        (:class:`~conceptbot.models.caching.CachedLLM`) returns a view logging under the new name.

        Args:
            module: The label.

        Returns:
            An LLM answering exactly as this one does.
        """
        ...
