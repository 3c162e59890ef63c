"""OpenAI embeddings (``text-embedding-ada-002`` as in the paper, or newer models).

This is an ``openai`` backend: it uses OPENAI_API_KEY, sent to the official API or to
OPENAI_BASE_URL when the user set one. URLs in its messages are redacted, and its messages never
quote the server's text (so a key the server echoes cannot reach them). A base URL's query string is
sent with every request, as for the chat backend (:func:`conceptbot.models.openai_backend.sdk_url_options`).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any

import numpy as np

from conceptbot.core.errors import BackendRequestError, BackendUnavailableError, ConfigError
from conceptbot.core.urls import redact_url
from conceptbot.models.embedder import normalise
from conceptbot.models.openai_backend import (
    check_api_key,
    describe_reply,
    not_openai_reply,
    sdk_url_options,
    validate_base_url,
)

BATCH = 512


class OpenAIEmbedder:
    """Embeds through the OpenAI embeddings endpoint (or a compatible server via ``base_url``).

    Args:
        model: Embedding model name.
        api_key: Secret key (never logged).
        base_url: Optional server URL.
        timeout_s: Per-request time-out.
        max_retries: Bounded retries with exponential backoff.
        client: A pre-built ``openai.OpenAI`` client (tests).
    """

    backend = "openai"

    def __init__(
        self,
        model: str = "text-embedding-ada-002",
        *,
        api_key: str | None = None,
        base_url: str | None = None,
        timeout_s: float = 60.0,
        max_retries: int = 3,
        client: Any = None,
    ) -> None:
        check_api_key(api_key, "OPENAI_API_KEY")
        self.model = model
        self.base_url = validate_base_url(base_url) if base_url else None
        if client is None:
            if not api_key:
                raise ConfigError("OpenAI embeddings need an API key", hint="set OPENAI_API_KEY")
            import openai

            client = openai.OpenAI(
                api_key=api_key,
                **sdk_url_options(self.base_url),
                timeout=timeout_s,
                max_retries=max_retries,
            )
        self._client = client

    def _where(self) -> str:
        return (
            f"the embeddings endpoint at {redact_url(self.base_url)}" if self.base_url else "the OpenAI API"
        )

    def embed(self, texts: Sequence[str]) -> np.ndarray:
        """Unit vectors, one row per text.

        Raises:
            BackendUnavailableError: The server cannot be reached or timed out.
            BackendRequestError: It refused the request or answered with something that is not an
                OpenAI-style embeddings reply.
        """
        import openai

        rows: list[list[float]] = []
        for start in range(0, len(texts), BATCH):
            batch = list(texts[start : start + BATCH])
            try:
                # "float" explicitly: the SDK otherwise asks for base64 (which some compatible
                # servers do not speak) and decodes it in a step that crashes on a non-JSON reply.
                out = self._client.embeddings.create(model=self.model, input=batch, encoding_format="float")
            except openai.APITimeoutError:
                raise BackendUnavailableError(f"{self._where()} did not answer in time") from None
            except openai.APIConnectionError:
                raise BackendUnavailableError(f"cannot connect to {self._where()}") from None
            except openai.AuthenticationError:
                raise BackendRequestError(
                    f"{self._where()} refused the API key", hint="check OPENAI_API_KEY"
                ) from None
            except openai.APIStatusError as exc:
                raise BackendRequestError(
                    f"embeddings request to {self._where()} failed with HTTP {exc.status_code}"
                ) from None
            except openai.APIResponseValidationError:
                raise not_openai_reply(self._where(), "a body the SDK could not read") from None
            except json.JSONDecodeError:
                raise not_openai_reply(self._where(), "invalid JSON") from None
            try:
                if not isinstance(out.data, (list, tuple)):
                    raise TypeError("no data list")
                data = sorted(out.data, key=lambda d: d.index)
                vectors = [[float(x) for x in item.embedding] for item in data]
            except (AttributeError, TypeError, ValueError, KeyError):
                raise not_openai_reply(self._where(), describe_reply(out)) from None
            if len(vectors) != len(batch):
                raise BackendRequestError(
                    f"{self._where()} returned {len(vectors)} embeddings for {len(batch)} texts"
                )
            rows.extend(vectors)
        return normalise(np.asarray(rows, dtype=np.float32))
