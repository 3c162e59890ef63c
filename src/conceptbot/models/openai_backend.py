"""HTTP backends through the official ``openai`` SDK: OpenAI itself and any OpenAI-compatible server
(vLLM, Ollama, llama.cpp's server, LM Studio, ...).

Time-outs and bounded retries with exponential backoff come from the SDK (``timeout``,
``max_retries``). API keys are only handed to the SDK client; they are never logged, cached or put
in error messages.

JSON-schema output: OpenAI and vLLM take ``response_format={"type": "json_schema", ...}``;
llama.cpp's server only takes ``{"type": "json_object", "schema": ...}``. For ``openai-compatible``
the first form is tried and, if the server rejects it, the second is used from then on.

Scoring: the chat API returns log-probabilities of generated tokens only, not of arbitrary
continuations, so :meth:`OpenAILLM.score` raises :class:`NotSupportedError`.
"""

from __future__ import annotations

import time
from typing import Any
from urllib.parse import urlsplit

from conceptbot.core.errors import (
    BackendRequestError,
    BackendUnavailableError,
    ConfigError,
    NotSupportedError,
)
from conceptbot.core.urls import check_http_url
from conceptbot.core.usage import Usage
from conceptbot.models.llm import Capabilities, ChatRequest, ChatResponse, ScoreRequest, ScoreResponse


def validate_base_url(url: str) -> str:
    """An OpenAI-compatible base URL, checked (see :func:`conceptbot.core.urls.check_http_url`)."""
    return check_http_url(url, "base URL", "http://127.0.0.1:8000/v1")


def _redact(url: str) -> str:
    parts = urlsplit(url)
    if parts.username or parts.password:
        return url.replace(parts.netloc, parts.hostname or "", 1)
    return url


class OpenAILLM:
    """Chat through the OpenAI API or an OpenAI-compatible server.

    Args:
        model: Model name as the server knows it.
        backend: ``openai`` or ``openai-compatible``.
        base_url: Server URL (required for ``openai-compatible``).
        api_key: Secret key (required for ``openai``; servers that need none get a placeholder).
        timeout_s: Per-request time-out.
        max_retries: Retries with exponential backoff on connection errors, 408/409/429/5xx.
        client: A pre-built ``openai.OpenAI`` client (tests).
    """

    def __init__(
        self,
        model: str,
        *,
        backend: str = "openai",
        base_url: str | None = None,
        api_key: str | None = None,
        timeout_s: float = 60.0,
        max_retries: int = 3,
        client: Any = None,
    ) -> None:
        if backend not in ("openai", "openai-compatible"):
            raise ConfigError(f"OpenAILLM backend must be openai or openai-compatible, not {backend!r}")
        if not model:
            raise ConfigError(f"the {backend} backend needs a model name")
        if backend == "openai" and not api_key and client is None:
            raise ConfigError(
                "the openai backend needs an API key", hint="set OPENAI_API_KEY in the environment"
            )
        if backend == "openai-compatible" and not base_url:
            raise ConfigError(
                "the openai-compatible backend needs a base URL",
                hint="use a spec like openai-compatible:http://127.0.0.1:8000/v1#MODEL",
            )
        self.backend = backend
        self.model = model
        self.base_url = validate_base_url(base_url) if base_url else None
        self.capabilities = Capabilities(scoring=False, json_schema=True, native_n=backend == "openai")
        self._json_mode = "json_schema"
        if client is None:
            import openai

            client = openai.OpenAI(
                api_key=api_key or "not-needed",
                base_url=self.base_url,
                timeout=timeout_s,
                max_retries=max_retries,
            )
        self._client = client

    def _where(self) -> str:
        return _redact(self.base_url) if self.base_url else "the OpenAI API"

    def _response_format(self, request: ChatRequest) -> dict[str, Any] | None:
        if request.json_schema is None:
            return None
        if self._json_mode == "json_object":
            return {"type": "json_object", "schema": request.schema()}
        return {"type": "json_schema", "json_schema": {"name": "reply", "schema": request.schema()}}

    def _create(self, request: ChatRequest, n: int, seed: int) -> Any:
        import openai

        kwargs: dict[str, Any] = {
            "model": self.model,
            "messages": [{"role": m.role, "content": m.content} for m in request.messages],
            "temperature": request.temperature,
            "max_tokens": request.max_tokens,
            "seed": seed,
        }
        if n > 1:
            kwargs["n"] = n
        if request.stop:
            kwargs["stop"] = list(request.stop)
        fmt = self._response_format(request)
        if fmt is not None:
            kwargs["response_format"] = fmt
        try:
            return self._client.chat.completions.create(**kwargs)
        except openai.APIStatusError as exc:
            if (
                fmt is not None
                and self.backend == "openai-compatible"
                and self._json_mode == "json_schema"
                and _rejects_json_schema(exc)
            ):
                self._json_mode = "json_object"  # llama.cpp-server style; remember for later calls
                return self._create(request, n, seed)
            raise self._status_error(exc) from None
        except openai.APITimeoutError:
            raise BackendUnavailableError(
                f"{self._where()} did not answer in time", hint="raise CONCEPTBOT_TIMEOUT or check the server"
            ) from None
        except openai.APIConnectionError:
            raise BackendUnavailableError(
                f"cannot connect to {self._where()}", hint="is the server running and the URL right?"
            ) from None

    def _status_error(self, exc: Any) -> BackendRequestError:
        import openai

        if isinstance(exc, openai.AuthenticationError):
            return BackendRequestError(
                f"{self._where()} refused the API key", hint="check OPENAI_API_KEY / CONCEPTBOT_API_KEY"
            )
        if isinstance(exc, openai.NotFoundError):
            return BackendRequestError(
                f"{self._where()} does not know model {self.model!r} or the URL path is wrong: "
                f"{_message(exc)}"
            )
        if isinstance(exc, (openai.BadRequestError, openai.UnprocessableEntityError)):
            return BackendRequestError(f"{self._where()} rejected the request: {_message(exc)}")
        return BackendRequestError(f"{self._where()} answered HTTP {exc.status_code}: {_message(exc)}")

    def chat(self, request: ChatRequest) -> ChatResponse:
        """Chat completion; see :meth:`conceptbot.models.llm.LLM.chat`.

        Servers that ignore ``n`` are asked again (with the next seeds) until ``n`` choices exist.
        """
        started = time.perf_counter()
        choices: list[str] = []
        reasons: list[str] = []
        prompt_tokens = completion_tokens = calls = 0
        while len(choices) < request.n:
            want = request.n - len(choices)
            out = self._create(request, want, request.seed + len(choices))
            calls += 1
            if not out.choices:
                raise BackendRequestError(f"{self._where()} returned no choices")
            for choice in out.choices[:want]:
                choices.append(choice.message.content or "")
                reasons.append(choice.finish_reason or "stop")
            if out.usage is not None:
                prompt_tokens += out.usage.prompt_tokens or 0
                completion_tokens += out.usage.completion_tokens or 0
        usage = Usage(prompt_tokens, completion_tokens, time.perf_counter() - started, 0.0, calls)
        return ChatResponse(
            choices=tuple(choices),
            usage=usage,
            backend=self.backend,
            model=self.model,
            finish_reasons=tuple(reasons),
        )

    def score(self, request: ScoreRequest) -> ScoreResponse:
        """Not supported: chat APIs do not return log-probabilities of given continuations."""
        raise NotSupportedError(
            f"the {self.backend} backend cannot score options by log-probability",
            hint="use the llamacpp backend for log-probability scoring, or the vote-based planner",
        )


def _rejects_json_schema(exc: Any) -> bool:
    """Whether an HTTP error says the server does not take ``response_format.type=json_schema``.

    vLLM-style servers answer 400/422; llama.cpp's server answers 500 with a validation message.
    """
    message = _message(exc)
    if exc.status_code in (400, 422):
        return True
    return "json_schema" in message or "response_format" in message


def _message(exc: Any) -> str:
    body = getattr(exc, "body", None)
    if isinstance(body, dict):
        error = body.get("error", body)
        if isinstance(error, dict) and error.get("message"):
            return str(error["message"])[:300]
        if isinstance(body.get("detail"), (str, list)):
            return str(body["detail"])[:300]
    return str(getattr(exc, "message", exc))[:300]
