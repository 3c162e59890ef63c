"""Build a household planner from settings, by configuration name."""

from __future__ import annotations

from conceptbot.core.config import Settings
from conceptbot.core.errors import ConfigError
from conceptbot.household.planner import (
    HOUSEHOLD_CONFIGS,
    ConceptBotHouseholdPlanner,
    HouseholdPlanner,
    PlainHouseholdPlanner,
)
from conceptbot.knowledge.registry import open_graph
from conceptbot.models.registry import open_embedder, open_llm, open_store
from conceptbot.pipeline.retrieval import RelationRetriever, default_theta


def build_household_planner(settings: Settings, config: str) -> HouseholdPlanner:
    """``plain`` (the LLM alone) or ``conceptbot`` (OPE Risk Index + URP relations + the LLM).

    For ConceptBot the planning call gets its own backend instance (for llama.cpp: a second context
    over the same memory-mapped weights), so its long system prompt stays evaluated while OPE and
    URP use the other one.

    Raises:
        ConfigError: Unknown configuration.
    """
    store = open_store(settings)
    if config == "plain":
        return PlainHouseholdPlanner(open_llm(settings, store, module="planner"))
    if config == "conceptbot":
        graph = open_graph(settings)
        embedder = open_embedder(settings, store)
        retriever = RelationRetriever(graph, embedder, default_theta(embedder.model))
        return ConceptBotHouseholdPlanner(
            open_llm(settings, store, module="pipeline"),
            retriever,
            planner_llm=open_llm(settings, store, module="planner"),
        )
    raise ConfigError(f"unknown configuration {config!r}", hint=f"use one of {', '.join(HOUSEHOLD_CONFIGS)}")
