"""Cost estimates from the price table in ``prices.toml``."""

from __future__ import annotations

import tomllib
from functools import lru_cache
from importlib import resources

FREE_BACKENDS = frozenset({"llamacpp", "fake", "openai-compatible", "sentence-transformers"})


@lru_cache(maxsize=1)
def _table() -> dict[str, dict[str, dict[str, float]]]:
    text = resources.files("conceptbot.models").joinpath("prices.toml").read_text(encoding="utf-8")
    return tomllib.loads(text)


def estimate_cost(backend: str, model: str, prompt_tokens: int, completion_tokens: int) -> float | None:
    """Estimated USD cost of a call, 0.0 for local backends, ``None`` if the model's price is unknown."""
    if backend in FREE_BACKENDS:
        return 0.0
    prices = _table().get(backend, {})
    entry = prices.get(model)
    if entry is None:
        prefixes = [name for name in prices if model.startswith(name)]
        if not prefixes:
            return None
        entry = prices[max(prefixes, key=len)]
    return (prompt_tokens * entry["input"] + completion_tokens * entry["output"]) / 1_000_000
