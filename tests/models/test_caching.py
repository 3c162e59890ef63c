import math
from pathlib import Path

import numpy as np
import pytest

from conceptbot.core.errors import BackendUnavailableError
from conceptbot.models.cache_db import CacheStore
from conceptbot.models.caching import CachedEmbedder, CachedLLM
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.models.llm import ChatRequest, ScoreRequest


@pytest.fixture
def store(tmp_path: Path) -> CacheStore:
    return CacheStore(tmp_path / "cache.db")


def test_second_identical_request_comes_from_the_cache(store: CacheStore) -> None:
    inner = FakeLLM(["fresh answer"])
    llm = CachedLLM(inner, store, module="ope")
    first = llm.chat(ChatRequest.of("what is a knife?"))
    second = llm.chat(ChatRequest.of("what is a knife?"))
    assert (first.cached, second.cached) == (False, True)
    assert second.text == "fresh answer"
    assert len(inner.requests) == 1
    calls = store.calls()
    assert [c.cached for c in calls] == [True, False]
    assert {c.module for c in calls} == {"ope"}


def test_different_parameters_miss_the_cache(store: CacheStore) -> None:
    inner = FakeLLM(["a", "b"])
    llm = CachedLLM(inner, store)
    llm.chat(ChatRequest.of("q", temperature=0.0))
    assert llm.chat(ChatRequest.of("q", temperature=0.5)).text == "b"


def test_no_cache_calls_the_backend_every_time_but_still_logs(store: CacheStore) -> None:
    inner = FakeLLM(["a", "b"])
    llm = CachedLLM(inner, store, use_cache=False)
    assert [llm.chat(ChatRequest.of("q")).text for _ in range(2)] == ["a", "b"]
    assert len(store.calls()) == 2


def test_errors_are_logged_and_raised(store: CacheStore) -> None:
    llm = CachedLLM(FakeLLM([BackendUnavailableError("server down")]), store, module="urp")
    with pytest.raises(BackendUnavailableError):
        llm.chat(ChatRequest.of("q"))
    (call,) = store.calls()
    assert call.module == "urp" and "server down" in (call.error or "")


def test_scores_are_cached(store: CacheStore) -> None:
    inner = FakeLLM(scores=[[-1.0, -3.0]])
    llm = CachedLLM(inner, store)
    request = ScoreRequest(options=("x", "y"), prompt="p")
    assert llm.score(request).logprobs == llm.score(request).logprobs == (-1.0, -3.0)
    assert len(inner.score_requests) == 1


def test_priors_key_the_cache_only_where_the_backend_uses_them(store: CacheStore) -> None:
    exact = FakeLLM(scores=[[-1.0, -3.0]])  # scores every option exactly: priors change nothing
    request = ScoreRequest(options=("x", "y"), prompt="p")
    with_priors = ScoreRequest(options=("x", "y"), prompt="p", priors=(0.0, -math.inf))
    CachedLLM(exact, store).score(request)
    assert CachedLLM(exact, store).score(with_priors).cached and len(exact.score_requests) == 1
    assert with_priors.canonical()["priors"] == [0.0, None]  # JSON has no -inf
    assert "priors" not in with_priors.canonical(with_priors=False)
    with pytest.raises(ValueError, match="one prior per option"):
        ScoreRequest(options=("x", "y"), prompt="p", priors=(0.0,))


def test_openai_calls_are_priced(store: CacheStore) -> None:
    inner = FakeLLM(["ok"], model="gpt-4o-mini")
    inner.backend = "openai"  # price it as the OpenAI API would be
    llm = CachedLLM(inner, store)
    response = llm.chat(ChatRequest.of("one two three four"))
    expected = (response.usage.prompt_tokens * 0.15 + response.usage.completion_tokens * 0.60) / 1e6
    assert response.usage.cost_usd == pytest.approx(expected)
    assert store.calls()[0].cost_usd == pytest.approx(expected)


def test_embeddings_are_computed_once_per_model_and_text(store: CacheStore) -> None:
    inner = FakeEmbedder()
    embedder = CachedEmbedder(inner, store)
    first = embedder.embed(["knife", "fork", "knife"])
    assert inner.calls == [("knife", "fork")]
    # A new wrapper (new process) reads the disk cache; only the new text reaches the backend.
    fresh = CachedEmbedder(inner, store)
    second = fresh.embed(["fork", "spoon"])
    assert inner.calls[-1] == ("spoon",)
    assert np.allclose(first[1], second[0])
