"""OpenAI embeddings (``text-embedding-ada-002`` as in the paper, or newer models)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from conceptbot.core.errors import BackendRequestError, BackendUnavailableError, ConfigError
from conceptbot.models.embedder import normalise
from conceptbot.models.openai_backend import validate_base_url

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
        self.model = model
        if client is None:
            if not api_key:
                raise ConfigError("OpenAI embeddings need an API key", hint="set OPENAI_API_KEY")
            import openai

            client = openai.OpenAI(
                api_key=api_key,
                base_url=validate_base_url(base_url) if base_url else None,
                timeout=timeout_s,
                max_retries=max_retries,
            )
        self._client = client

    def embed(self, texts: Sequence[str]) -> np.ndarray:
        """Unit vectors, one row per text."""
        import openai

        rows: list[list[float]] = []
        for start in range(0, len(texts), BATCH):
            try:
                out = self._client.embeddings.create(
                    model=self.model, input=list(texts[start : start + BATCH])
                )
            except openai.APIConnectionError:
                raise BackendUnavailableError("cannot connect to the embeddings endpoint") from None
            except openai.APIStatusError as exc:
                raise BackendRequestError(f"embeddings request failed with HTTP {exc.status_code}") from None
            rows.extend(item.embedding for item in sorted(out.data, key=lambda d: d.index))
        return normalise(np.asarray(rows, dtype=np.float32))
