import numpy as np
import pytest

from conceptbot.core.errors import BackendUnavailableError, FakeExhaustedError, NotSupportedError
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.models.llm import ChatRequest, ScoreRequest


def test_fake_llm_replies_in_order_and_records_requests() -> None:
    llm = FakeLLM(["one", "two", "three"])
    first = llm.chat(ChatRequest.of("hi", system="be brief"))
    second = llm.chat(ChatRequest.of("again", n=2))
    assert first.text == "one"
    assert second.choices == ("two", "three")
    assert [r.messages[-1].content for r in llm.requests] == ["hi", "again"]
    assert llm.requests[0].messages[0].role == "system"


def test_fake_llm_raises_when_it_runs_out() -> None:
    llm = FakeLLM(["only"])
    llm.chat(ChatRequest.of("a"))
    with pytest.raises(FakeExhaustedError, match="ran out"):
        llm.chat(ChatRequest.of("b"))


def test_fake_llm_raises_scripted_exceptions() -> None:
    llm = FakeLLM([BackendUnavailableError("down")])
    with pytest.raises(BackendUnavailableError):
        llm.chat(ChatRequest.of("a"))


def test_fake_scoring_is_scripted_or_unsupported() -> None:
    request = ScoreRequest(options=("a", "b"), prompt="p")
    with pytest.raises(NotSupportedError):
        FakeLLM().score(request)
    scored = FakeLLM(scores=[[-1.0, -2.0]]).score(request)
    assert scored.logprobs == (-1.0, -2.0)


def test_fake_embedder_is_deterministic_and_normalised() -> None:
    embedder = FakeEmbedder()
    a = embedder.embed(["sharp knife", "sharp knife", "fluffy cloud"])
    assert np.allclose(a[0], a[1])
    assert np.allclose(np.linalg.norm(a, axis=1), 1.0)
    assert a[0] @ a[1] > a[0] @ a[2]
