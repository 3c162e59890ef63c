"""HTTP backends through the official ``openai`` SDK: OpenAI itself and any OpenAI-compatible server
(vLLM, Ollama, llama.cpp's server, LM Studio, ...).

Time-outs and bounded retries with exponential backoff come from the SDK (``timeout``,
``max_retries``). API keys are only handed to the SDK client; they are never logged, cached or put
in error messages, and URLs in messages are redacted (:func:`conceptbot.core.urls.redact_url`).
A server's own error text is quoted with this backend's key, base-URL password (and its ``Basic``
form) and query values masked by value (:class:`conceptbot.core.urls.Redactor`): servers echo keys
in forms no pattern knows. A key that cannot go into an HTTP header (a line break, a non-ASCII
character) is a :class:`ConfigError` when the backend is built, not a failed request.

A base URL with a query string (``http://h/v1?api_key=X``) works: the query is sent with every
request (the SDK's ``default_query``) instead of being left where the SDK would append the endpoint
path after it.

Key routing: the registry gives ``openai`` the user's OPENAI_API_KEY and ``openai-compatible`` only
CONCEPTBOT_API_KEY. Without a key this backend sends no ``Authorization`` header at all, and it
never lets the SDK fill in OPENAI_API_KEY, OPENAI_ORG_ID or OPENAI_PROJECT_ID from the environment
for a third-party server.

A server that answers 200 with something other than OpenAI-style JSON (an HTML page because the
base URL is a web UI, a proxy's error text) is a :class:`BackendRequestError` naming the likely
cause, not a stack trace.

JSON-schema output: OpenAI and vLLM take ``response_format={"type": "json_schema", ...}``;
llama.cpp's server only takes ``{"type": "json_object", "schema": ...}``. For ``openai-compatible``
the first form is tried and, if the server rejects it, the second is used from then on.

Scoring (:meth:`OpenAILLM.score`): by the best method the server supports, found once
(:mod:`conceptbot.models.http_scoring`: ``echo`` or ``search`` on completions, ``chat-logprobs``,
``vote``), or the one configured (``CONCEPTBOT_SCORING``). The method used is on every :class:`ScoreResponse`.
"""

from __future__ import annotations

import json
import time
from typing import Any

from conceptbot.core.config import API_KEY_HINT, api_key_problem
from conceptbot.core.errors import BackendRequestError, BackendUnavailableError, ConfigError
from conceptbot.core.urls import Redactor, check_http_url, redact_url, split_query
from conceptbot.core.usage import Usage
from conceptbot.models.http_scoring import EchoTokens, HTTPScorer
from conceptbot.models.llm import (
    Capabilities,
    ChatRequest,
    ChatResponse,
    Message,
    ScoreRequest,
    ScoreResponse,
)


def validate_base_url(url: str) -> str:
    """An OpenAI-compatible base URL, checked (see :func:`conceptbot.core.urls.check_http_url`)."""
    return check_http_url(url, "base URL", "http://127.0.0.1:8000/v1")


def check_api_key(api_key: str | None, variable: str) -> None:
    """Refuse a key the HTTP client could not send (checked before any request is made).

    Args:
        api_key: The key, or ``None``.
        variable: The environment variable it usually comes from, for the message.

    Raises:
        ConfigError: The key holds a line break, a control or a non-ASCII character (the message
            says which, never the key).
    """
    problem = api_key_problem(api_key) if api_key else None
    if problem:
        raise ConfigError(f"the API key ({variable}) {problem} (the key is not shown)", hint=API_KEY_HINT)


def sdk_url_options(base_url: str | None) -> dict[str, Any]:
    """``base_url`` and ``default_query`` for ``openai.OpenAI``: the URL without its query, the
    query's fields sent with every request (see :func:`conceptbot.core.urls.split_query`)."""
    if base_url is None:
        return {"base_url": None}
    base, query = split_query(base_url)
    return {"base_url": base, "default_query": query} if query else {"base_url": base}


def not_openai_reply(where: str, got: str) -> BackendRequestError:
    """The error for a 200 reply that is not OpenAI-style JSON (``got`` says what it was)."""
    return BackendRequestError(
        f"{where} answered with something that is not an OpenAI-style JSON reply ({got})",
        hint="is the base URL the API root, e.g. http://127.0.0.1:8000/v1?",
    )


def describe_reply(out: Any) -> str:
    """What a parsed reply was, for :func:`not_openai_reply` (the SDK returns the body as text when
    the server's Content-Type is not JSON)."""
    if isinstance(out, str):
        head = out.lstrip()[:200].lower()
        if head.startswith(("<!doctype html", "<html")) or "<html" in head:
            return "an HTML page"
        return "text, not JSON" if out.strip() else "an empty body"
    return "JSON without the expected fields"


def client_options(backend: str, api_key: str | None) -> dict[str, Any]:
    """Keyword arguments for ``openai.OpenAI`` that send ``api_key`` and nothing else of the user's.

    The SDK fills any argument left ``None`` from OPENAI_API_KEY, OPENAI_ORG_ID and
    OPENAI_PROJECT_ID; for a third-party server those must not be sent, so the key is never
    ``None`` and the organization and project headers are omitted.
    """
    import openai

    if backend == "openai":
        return {"api_key": api_key}
    omit = openai.Omit()
    # Without a key a placeholder, not None (None means "read OPENAI_API_KEY"); the header it would
    # make is dropped on every request (see request_headers), so the placeholder is never sent.
    return {
        "api_key": api_key or "unused",
        "default_headers": {"OpenAI-Organization": omit, "OpenAI-Project": omit},
    }


def request_headers(backend: str, api_key: str | None) -> dict[str, Any]:
    """Per-request headers: no ``Authorization`` at all for a key-less ``openai-compatible`` server.

    The SDK accepts an omitted ``Authorization`` only per request, not as a client default.
    """
    if backend == "openai" or api_key:
        return {}
    import openai

    return {"Authorization": openai.Omit()}


class OpenAILLM:
    """Chat through the OpenAI API or an OpenAI-compatible server.

    Args:
        model: Model name as the server knows it.
        backend: ``openai`` or ``openai-compatible``.
        base_url: Server URL (required for ``openai-compatible``).
        api_key: Secret key (required for ``openai``; without one, ``openai-compatible`` requests
            carry no ``Authorization`` header).
        timeout_s: Per-request time-out.
        max_retries: Retries with exponential backoff on connection errors, 408/409/429/5xx.
        client: A pre-built ``openai.OpenAI`` client (tests).
        scoring: How options are scored (:data:`conceptbot.models.http_scoring.METHODS`).
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
        scoring: str = "auto",
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
        check_api_key(api_key, "OPENAI_API_KEY" if backend == "openai" else "CONCEPTBOT_API_KEY")
        self.backend = backend
        self.model = model
        self.base_url = validate_base_url(base_url) if base_url else None
        self._redact = Redactor(keys=(api_key,), urls=(self.base_url,))
        self.capabilities = Capabilities(scoring=True, json_schema=True, native_n=backend == "openai")
        self.scorer = HTTPScorer(self, scoring)
        self._json_mode = "json_schema"
        self._headers = request_headers(backend, api_key) if client is None else {}
        if client is None:
            import openai

            client = openai.OpenAI(
                timeout=timeout_s,
                max_retries=max_retries,
                **sdk_url_options(self.base_url),
                **client_options(backend, api_key),
            )
        self._client = client

    def _where(self) -> str:
        return redact_url(self.base_url) if self.base_url else "the OpenAI API"

    def _response_format(self, request: ChatRequest) -> dict[str, Any] | None:
        if request.json_schema is None:
            return None
        if self._json_mode == "json_object":
            return {"type": "json_object", "schema": request.schema()}
        return {"type": "json_schema", "json_schema": {"name": "reply", "schema": request.schema()}}

    def _create(self, request: ChatRequest, n: int, seed: int) -> Any:
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
        if self._headers:
            kwargs["extra_headers"] = self._headers

        def on_status(exc: Any) -> Any:
            if (
                fmt is not None
                and self.backend == "openai-compatible"
                and self._json_mode == "json_schema"
                and _rejects_json_schema(exc)
            ):
                self._json_mode = "json_object"  # llama.cpp-server style; remember for later calls
                return self._create(request, n, seed)
            raise self._status_error(exc) from None

        return self._call(lambda: self._client.chat.completions.create(**kwargs), on_status)

    def _status_error(self, exc: Any) -> BackendRequestError:
        import openai

        if isinstance(exc, openai.AuthenticationError):
            return BackendRequestError(
                f"{self._where()} refused the API key", hint="check OPENAI_API_KEY / CONCEPTBOT_API_KEY"
            )
        if isinstance(exc, openai.NotFoundError):
            return BackendRequestError(
                f"{self._where()} does not know model {self.model!r} or the URL path is wrong: "
                f"{self._message(exc)}"
            )
        if isinstance(exc, (openai.BadRequestError, openai.UnprocessableEntityError)):
            return BackendRequestError(f"{self._where()} rejected the request: {self._message(exc)}")
        return BackendRequestError(f"{self._where()} answered HTTP {exc.status_code}: {self._message(exc)}")

    def _message(self, exc: Any) -> str:
        """The server's error message with this backend's secrets and every recognisable
        credential masked (before the cut, so a cut cannot leave half a key)."""
        return self._redact(_raw_message(exc))[:300]

    def with_module(self, module: str) -> OpenAILLM:
        """This backend itself: it keeps no call log to label (see :meth:`LLM.with_module`)."""
        return self

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
            got, used = self._read(out, want)
            for text, reason in got:
                choices.append(text)
                reasons.append(reason)
            prompt_tokens += used[0]
            completion_tokens += used[1]
        usage = Usage(prompt_tokens, completion_tokens, time.perf_counter() - started, 0.0, calls)
        return ChatResponse(
            choices=tuple(choices),
            usage=usage,
            backend=self.backend,
            model=self.model,
            finish_reasons=tuple(reasons),
        )

    def _read(self, out: Any, want: int) -> tuple[list[tuple[str, str]], tuple[int, int]]:
        """``[(text, finish_reason)]`` and ``(prompt, completion)`` tokens of one reply.

        Raises:
            BackendRequestError: The reply is not a chat completion, or has no choices.
        """
        try:
            if not isinstance(out.choices, (list, tuple)):  # None when the JSON has no "choices"
                raise TypeError("no choices list")
            if not out.choices:
                raise BackendRequestError(f"{self._where()} returned no choices")
            got = []
            for choice in out.choices[:want]:
                content = choice.message.content
                if content is not None and not isinstance(content, str):
                    raise TypeError("message content is not text")
                got.append((content or "", str(choice.finish_reason or "stop")))
            usage = out.usage
            used = (
                (0, 0)
                if usage is None
                else (int(usage.prompt_tokens or 0), int(usage.completion_tokens or 0))
            )
        except (AttributeError, TypeError, ValueError, KeyError, IndexError):
            # The SDK builds its reply objects without validation: any JSON (or a text body) gets here.
            raise not_openai_reply(self._where(), describe_reply(out)) from None
        return got, used

    def score(self, request: ScoreRequest) -> ScoreResponse:
        """Log-probability of each option (see :mod:`conceptbot.models.http_scoring`); the
        response's ``method`` says which way."""
        logprobs, counts, usage, method = self.scorer.score(request)
        return ScoreResponse(tuple(logprobs), tuple(counts), usage, self.backend, self.model, method=method)

    def _call(self, make: Any, on_status: Any = None) -> Any:
        """One SDK call with this backend's error mapping (``on_status`` may answer an HTTP error
        status itself, e.g. by retrying in another form)."""
        import openai

        try:
            return make()
        except openai.APIStatusError as exc:
            if on_status is not None:
                return on_status(exc)
            raise self._status_error(exc) from None
        except openai.APIResponseValidationError:
            raise not_openai_reply(self._where(), "a body the SDK could not read") from None
        except json.JSONDecodeError:  # a 200 with a JSON Content-Type whose body is not JSON
            raise not_openai_reply(self._where(), "invalid JSON") from None
        except openai.APITimeoutError:
            raise BackendUnavailableError(
                f"{self._where()} did not answer in time", hint="raise CONCEPTBOT_TIMEOUT or check the server"
            ) from None
        except openai.APIConnectionError:
            raise BackendUnavailableError(
                f"cannot connect to {self._where()}", hint="is the server running and the URL right?"
            ) from None

    def echo(self, prompt: str) -> EchoTokens:
        """Completions with ``echo`` and ``logprobs`` (the ``echo`` scoring method)."""
        extra = {"extra_headers": self._headers} if self._headers else {}
        out = self._call(
            lambda: self._client.completions.create(
                model=self.model, prompt=prompt, max_tokens=1, echo=True, logprobs=1, temperature=0, **extra
            )
        )
        try:
            found = out.choices[0].logprobs
            offsets = tuple(int(o) for o in found.text_offset)
            logprobs = tuple(None if lp is None else float(lp) for lp in found.token_logprobs)
            # The generated token comes last; only the prompt's are wanted.
            echoed = [i for i, off in enumerate(offsets) if off < len(prompt)]
            keep = (echoed[-1] + 1) if echoed else 0
            used = int(out.usage.prompt_tokens) if out.usage is not None else keep
        except (AttributeError, TypeError, ValueError, IndexError):
            raise BackendRequestError(f"{self._where()} returned no prompt log-probabilities") from None
        return EchoTokens(offsets[:keep], logprobs[:keep], used)

    def next_tokens(self, prompt: str, top: int) -> tuple[dict[str, float], int]:
        """Completions for one token with ``logprobs=top`` (the ``search`` scoring method): the
        generated token's top log-probabilities."""
        extra = {"extra_headers": self._headers} if self._headers else {}
        out = self._call(
            lambda: self._client.completions.create(
                model=self.model, prompt=prompt, max_tokens=1, logprobs=top, temperature=0, **extra
            )
        )
        try:
            entry = out.choices[0].logprobs.top_logprobs[0]
            found = {str(t): float(lp) for t, lp in entry.items()}
            used = int(out.usage.prompt_tokens) if out.usage is not None else 0
        except (AttributeError, TypeError, ValueError, IndexError):
            raise BackendRequestError(f"{self._where()} returned no completion log-probabilities") from None
        return found, used

    def _chat_kwargs(self, messages: Any, **more: Any) -> dict[str, Any]:
        kwargs = {"model": self.model, "messages": [{"role": m.role, "content": m.content} for m in messages]}
        if self._headers:
            kwargs["extra_headers"] = self._headers
        return {**kwargs, **more}

    def first_token(self, messages: Any, top: int) -> tuple[dict[str, float], int]:
        """The top log-probabilities of the reply's first token (``chat-logprobs``)."""
        kwargs = self._chat_kwargs(messages, max_tokens=1, temperature=0, logprobs=True, top_logprobs=top)
        out = self._call(lambda: self._client.chat.completions.create(**kwargs))
        try:
            entry = out.choices[0].logprobs.content[0]
            found = {str(t.token): float(t.logprob) for t in entry.top_logprobs}
            used = int(out.usage.prompt_tokens) if out.usage is not None else 0
        except (AttributeError, TypeError, ValueError, IndexError):
            raise BackendRequestError(f"{self._where()} returned no log-probabilities for chat") from None
        return found, used

    def sample(self, messages: Any, n: int) -> tuple[list[str], int]:
        """``n`` one-token answers at temperature 1 (``vote``)."""
        request = ChatRequest(
            messages=tuple(Message(m.role, m.content) for m in messages), n=n, temperature=1.0, max_tokens=2
        )
        reply = self.chat(request)
        return list(reply.choices), reply.usage.prompt_tokens


def _rejects_json_schema(exc: Any) -> bool:
    """Whether an HTTP error says the server does not take ``response_format.type=json_schema``.

    vLLM-style servers answer 400/422; llama.cpp's server answers 500 with a validation message.
    """
    message = _raw_message(exc)  # only searched, never shown
    if exc.status_code in (400, 422):
        return True
    return "json_schema" in message or "response_format" in message


# Far beyond the 300 characters shown: a key cut in half at this bound could not be masked by value,
# but it also lies far past the part that is kept after masking.
_RAW_CHARS = 100_000


def _raw_message(exc: Any) -> str:
    body = getattr(exc, "body", None)
    if isinstance(body, dict):
        error = body.get("error", body)
        if isinstance(error, dict) and error.get("message"):
            return str(error["message"])[:_RAW_CHARS]
        if isinstance(body.get("detail"), (str, list)):
            return str(body["detail"])[:_RAW_CHARS]
    return str(getattr(exc, "message", exc))[:_RAW_CHARS]
