"""Build a household planner from settings, by configuration name."""

from __future__ import annotations

from conceptbot.core.config import Settings
from conceptbot.core.errors import ConfigError
from conceptbot.household.judge import QUESTIONS, HarmJudge
from conceptbot.household.planner import (
    HOUSEHOLD_CONFIGS,
    ConceptBotHouseholdPlanner,
    HouseholdPlanner,
    PlainHouseholdPlanner,
)
from conceptbot.knowledge.registry import open_graph
from conceptbot.models.cache_db import CacheStore
from conceptbot.models.registry import open_embedder, open_llm, open_run_store
from conceptbot.pipeline.retrieval import RelationRetriever, default_theta


def build_household_planner(settings: Settings, config: str) -> HouseholdPlanner:
    """``plain`` (the LLM alone), ``conceptbot`` (OPE Risk Index + URP relations as evidence for the
    harm judge, then the LLM plans) or ``conceptbot-joint`` (the same evidence for the LLM's joint
    judging-and-planning call: the first design).

    For ConceptBot, OPE, URP's keywords and the planning call each get their own backend instance
    (for llama.cpp: a context each over the same memory-mapped weights), so each module's system
    prompt stays evaluated from one task to the next.

    Raises:
        ConfigError: Unknown configuration.
    """
    store = open_run_store(settings)  # --no-cache with an unusable home: unlogged, with a warning
    if config == "plain":
        return PlainHouseholdPlanner(open_llm(settings, store, module="planner"))
    if config in ("conceptbot", "conceptbot-joint"):
        graph = open_graph(settings)
        embedder = open_embedder(settings, store)
        retriever = RelationRetriever(graph, embedder, default_theta(embedder.model))
        return ConceptBotHouseholdPlanner(
            open_llm(settings, store, module="ope"),
            retriever,
            planner_llm=open_llm(settings, store, module="planner"),
            keyword_llm=open_llm(settings, store, module="urp"),
            judge=_judge(settings, store) if config == "conceptbot" else None,
        )
    raise ConfigError(f"unknown configuration {config!r}", hint=f"use one of {', '.join(HOUSEHOLD_CONFIGS)}")


def _judge(settings: Settings, store: CacheStore | None) -> HarmJudge:
    """The harm judge, with a backend instance per system prompt it asks with."""
    _, *others = dict.fromkeys(q.system for q in QUESTIONS)
    contexts = {system: open_llm(settings, store, module="judge") for system in others}
    return HarmJudge(open_llm(settings, store, module="judge"), contexts=contexts)
