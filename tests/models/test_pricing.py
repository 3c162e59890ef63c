import pytest

from conceptbot.models.pricing import estimate_cost


def test_local_backends_are_free() -> None:
    assert estimate_cost("llamacpp", "qwen2.5-coder-1.5b", 1000, 1000) == 0.0


def test_dated_model_names_match_by_prefix() -> None:
    assert estimate_cost("openai", "gpt-4o-mini-2024-07-18", 1_000_000, 0) == pytest.approx(0.15)


def test_unknown_price_is_none() -> None:
    assert estimate_cost("openai", "some-future-model", 10, 10) is None
