"""Wrappers that put the SQLite cache and the call log in front of any LLM or embedder.

The cache and the log serve the call, never the other way round: when the database fails mid-run
(a full disk, a file damaged or made read-only while running) a read counts as a miss and a write
or log entry is skipped, with one warning (:meth:`~conceptbot.models.cache_db.CacheStore.attempt`),
so an answer the backend gave, or the error it raised, reaches the caller either way.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import asdict, replace
from typing import Any

import numpy as np

from conceptbot.core.urls import redact_secrets
from conceptbot.core.usage import Usage
from conceptbot.models.cache_db import CacheStore, CallRecord, request_key
from conceptbot.models.embedder import Embedder
from conceptbot.models.llm import LLM, ChatRequest, ChatResponse, ScoreRequest, ScoreResponse
from conceptbot.models.pricing import estimate_cost


def _usage_dict(usage: Usage) -> dict[str, Any]:
    return asdict(usage)


def error_text(exc: BaseException) -> str:
    """An exception as stored in the call log: type and message, credentials masked, 500 characters.

    Masking comes before truncation so a cut can never leave half a URL with its key in it.
    """
    return redact_secrets(f"{type(exc).__name__}: {exc}")[:500]


class CachedLLM:
    """An :class:`~conceptbot.models.llm.LLM` that answers repeated requests from the cache and logs
    every call (hits too, with ``cached=1`` and zero cost).

    Args:
        inner: The real backend.
        store: The cache database, or ``None`` for no caching and no log.
        use_cache: Read and write the response cache (``--no-cache`` turns this off; calls are
            still logged).
        module: Label written to the call log (``cli``, ``ope``, ``urp``, ``planner``, ...).
    """

    def __init__(
        self, inner: LLM, store: CacheStore | None, *, use_cache: bool = True, module: str = "default"
    ) -> None:
        self.inner = inner
        self.store = store
        self.use_cache = use_cache
        self.module = module
        self.backend = inner.backend
        self.model = inner.model
        self.capabilities = inner.capabilities

    def with_module(self, module: str) -> CachedLLM:
        """The same backend and cache, logging under another module name."""
        return CachedLLM(self.inner, self.store, use_cache=self.use_cache, module=module)

    def _log(self, kind: str, usage: Usage, cached: bool, error: str | None = None) -> None:
        if self.store is None:
            return
        cost = (
            0.0
            if cached
            else estimate_cost(self.backend, self.model, usage.prompt_tokens, usage.completion_tokens)
        )
        self.store.attempt(
            "write the call log",
            self.store.log_call,
            CallRecord(
                kind=kind,
                module=self.module,
                backend=self.backend,
                model=self.model,
                prompt_tokens=usage.prompt_tokens,
                completion_tokens=usage.completion_tokens,
                latency_s=usage.latency_s,
                cost_usd=cost,
                cached=cached,
                error=error,
            ),
        )

    def _cached(self, kind: str, canonical: dict[str, Any]) -> tuple[str, dict[str, Any] | None, float]:
        key = request_key(kind, self.backend, self.model, canonical)
        started = time.perf_counter()
        hit = None
        if self.store is not None and self.use_cache:
            hit = self.store.attempt("read the cache", self.store.get_response, key)
        return key, hit, time.perf_counter() - started

    def _store(self, key: str, kind: str, canonical: dict[str, Any], response: dict[str, Any]) -> None:
        if self.store is not None and self.use_cache:
            self.store.attempt(
                "write the cache",
                self.store.put_response,
                key,
                kind=kind,
                backend=self.backend,
                model=self.model,
                request=canonical,
                response=response,
            )

    def chat(self, request: ChatRequest) -> ChatResponse:
        """Chat through the cache; see :meth:`LLM.chat`."""
        canonical = request.canonical()
        key, hit, lookup_s = self._cached("chat", canonical)
        if hit is not None:
            usage = Usage(hit["usage"]["prompt_tokens"], hit["usage"]["completion_tokens"], lookup_s, 0.0, 0)
            self._log("chat", usage, cached=True)
            return ChatResponse(
                choices=tuple(hit["choices"]),
                usage=usage,
                backend=self.backend,
                model=self.model,
                cached=True,
                finish_reasons=tuple(hit.get("finish_reasons", ())),
            )
        try:
            response = self.inner.chat(request)
        except Exception as exc:
            self._log("chat", Usage(calls=1), cached=False, error=error_text(exc))
            raise
        cost = estimate_cost(
            self.backend, self.model, response.usage.prompt_tokens, response.usage.completion_tokens
        )
        response = replace(response, usage=replace(response.usage, cost_usd=cost or 0.0))
        self._store(
            key,
            "chat",
            canonical,
            {
                "choices": list(response.choices),
                "usage": _usage_dict(response.usage),
                "finish_reasons": list(response.finish_reasons),
            },
        )
        self._log("chat", response.usage, cached=False)
        return response

    def score(self, request: ScoreRequest) -> ScoreResponse:
        """Score through the cache; see :meth:`LLM.score`."""
        canonical = request.canonical(with_priors=not self.inner.capabilities.exact_scoring)
        key, hit, lookup_s = self._cached("score", canonical)
        if hit is not None:
            usage = Usage(hit["usage"]["prompt_tokens"], 0, lookup_s, 0.0, 0)
            self._log("score", usage, cached=True)
            return ScoreResponse(
                logprobs=tuple(hit["logprobs"]),
                token_counts=tuple(hit["token_counts"]),
                usage=usage,
                backend=self.backend,
                model=self.model,
                cached=True,
                method=hit.get("method", "logprob"),
            )
        try:
            response = self.inner.score(request)
        except Exception as exc:
            self._log("score", Usage(calls=1), cached=False, error=error_text(exc))
            raise
        self._store(
            key,
            "score",
            canonical,
            {
                "logprobs": list(response.logprobs),
                "token_counts": list(response.token_counts),
                "usage": _usage_dict(response.usage),
                "method": response.method,
            },
        )
        self._log("score", response.usage, cached=False)
        return response


class CachedEmbedder:
    """An :class:`~conceptbot.models.embedder.Embedder` that embeds each (model, text) once.

    Args:
        inner: The real embedder.
        store: The cache database, or ``None``.
        use_cache: Read and write the embedding cache.
        module: Label for the call log.
    """

    def __init__(
        self, inner: Embedder, store: CacheStore | None, *, use_cache: bool = True, module: str = "embed"
    ) -> None:
        self.inner = inner
        self.store = store
        self.use_cache = use_cache
        self.module = module
        self.backend = inner.backend
        self.model = inner.model
        # Memory layer in front of SQLite: the pipeline embeds the same target words many times.
        self._memory: dict[str, np.ndarray] = {}

    def embed(self, texts: Sequence[str]) -> np.ndarray:
        """Unit vectors, one row per text; only unseen texts reach the backend."""
        if not texts:
            return np.zeros((0, 0), dtype=np.float32)
        known: dict[str, np.ndarray] = {t: self._memory[t] for t in texts if t in self._memory}
        missing = [t for t in dict.fromkeys(texts) if t not in known]
        if missing and self.store is not None and self.use_cache:
            known.update(
                self.store.attempt("read the cache", self.store.get_embeddings, self.model, missing) or {}
            )
            missing = [t for t in missing if t not in known]
        if missing:
            started = time.perf_counter()
            vectors = self.inner.embed(missing)
            latency = time.perf_counter() - started
            known.update(zip(missing, vectors, strict=False))
            if self.store is not None:
                if self.use_cache:
                    self.store.attempt(
                        "write the cache", self.store.put_embeddings, self.model, missing, vectors
                    )
                tokens = sum(len(t.split()) for t in missing)  # word count: a cheap token estimate
                self.store.attempt(
                    "write the call log",
                    self.store.log_call,
                    CallRecord(
                        kind="embed",
                        module=self.module,
                        backend=self.backend,
                        model=self.model,
                        prompt_tokens=tokens,
                        completion_tokens=0,
                        latency_s=latency,
                        cost_usd=estimate_cost(self.backend, self.model, tokens, 0),
                        cached=False,
                    ),
                )
        if self.use_cache:
            self._memory.update(known)
        return np.stack([known[t] for t in texts]).astype(np.float32)
