"""Deterministic fakes for unit tests: a scripted LLM and a hashing embedder.

The fake LLM records every request and raises :class:`FakeExhaustedError` when it runs out of
scripted replies (a silent empty reply would hide bugs).
"""

from __future__ import annotations

import hashlib
import re
from collections import deque
from collections.abc import Iterable, Sequence

import numpy as np

from conceptbot.core.errors import FakeExhaustedError, NotSupportedError
from conceptbot.core.usage import Usage
from conceptbot.models.llm import Capabilities, ChatRequest, ChatResponse, ScoreRequest, ScoreResponse


class FakeLLM:
    """An LLM that returns scripted replies in order.

    Args:
        replies: Chat completion texts (one per choice), or exceptions to raise in their place.
        scores: For :meth:`score`, one list of log-probabilities per call; if not given, scoring
            is reported as not supported.
        model: Model name to report.
    """

    backend = "fake"

    def __init__(
        self,
        replies: Iterable[str | Exception] = (),
        scores: Iterable[Sequence[float]] | None = None,
        model: str = "fake-model",
    ) -> None:
        self.model = model
        self._replies: deque[str | Exception] = deque(replies)
        self._scores: deque[Sequence[float]] | None = None if scores is None else deque(scores)
        scoring = scores is not None
        self.capabilities = Capabilities(
            scoring=scoring, exact_scoring=scoring, json_schema=True, native_n=True
        )
        self.requests: list[ChatRequest] = []
        self.score_requests: list[ScoreRequest] = []

    def add_replies(self, *replies: str | Exception) -> None:
        """Append more scripted replies."""
        self._replies.extend(replies)

    def with_module(self, module: str) -> FakeLLM:
        """This backend itself: it keeps no call log to label (see :meth:`LLM.with_module`)."""
        return self

    def chat(self, request: ChatRequest) -> ChatResponse:
        """Return the next ``request.n`` scripted replies."""
        self.requests.append(request)
        choices = []
        for _ in range(request.n):
            if not self._replies:
                raise FakeExhaustedError(
                    f"FakeLLM ran out of scripted replies after {len(self.requests)} request(s)",
                    hint="script more replies with FakeLLM(replies=[...]) or add_replies()",
                )
            reply = self._replies.popleft()
            if isinstance(reply, Exception):
                raise reply
            choices.append(reply)
        prompt_tokens = sum(len(m.content.split()) for m in request.messages)
        usage = Usage(prompt_tokens=prompt_tokens, completion_tokens=sum(len(c.split()) for c in choices))
        return ChatResponse(
            choices=tuple(choices),
            usage=usage,
            backend=self.backend,
            model=self.model,
            finish_reasons=("stop",) * len(choices),
        )

    def score(self, request: ScoreRequest) -> ScoreResponse:
        """Return the next scripted list of log-probabilities."""
        self.score_requests.append(request)
        if self._scores is None:
            raise NotSupportedError("the fake backend was built without scores")
        if not self._scores:
            raise FakeExhaustedError("FakeLLM ran out of scripted scores")
        values = tuple(float(v) for v in self._scores.popleft())
        if len(values) != len(request.options):
            raise ValueError(f"scripted {len(values)} scores for {len(request.options)} options")
        return ScoreResponse(
            logprobs=values,
            token_counts=tuple(max(1, len(o.split())) for o in request.options),
            usage=Usage(),
            backend=self.backend,
            model=self.model,
        )


class FakeEmbedder:
    """A deterministic embedder: hashed bag of lower-cased words and character trigrams.

    Texts sharing words get high cosine similarity, which is enough to test filtering logic.
    """

    backend = "fake"

    def __init__(self, dim: int = 128, model: str = "fake-embedder") -> None:
        self.dim = dim
        self.model = model
        self.calls: list[tuple[str, ...]] = []

    def embed(self, texts: Sequence[str]) -> np.ndarray:
        """Unit vectors, one row per text."""
        self.calls.append(tuple(texts))
        out = np.zeros((len(texts), self.dim), dtype=np.float32)
        for row, text in enumerate(texts):
            words = re.findall(r"[a-z0-9]+", text.lower())
            grams = words + [w[i : i + 3] for w in words for i in range(max(1, len(w) - 2))]
            for gram in grams:
                digest = hashlib.sha256(gram.encode()).digest()
                out[row, int.from_bytes(digest[:4], "little") % self.dim] += 1.0
            norm = np.linalg.norm(out[row])
            if norm > 0:
                out[row] /= norm
        return out
