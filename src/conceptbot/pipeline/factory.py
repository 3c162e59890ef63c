"""Build a ConceptBot from settings: LLM, embedder, knowledge graph and caches, by name."""

from __future__ import annotations

from conceptbot.core.config import Settings
from conceptbot.knowledge.registry import open_graph
from conceptbot.models.registry import open_embedder, open_llm, open_store
from conceptbot.pipeline.conceptbot import ConceptBot
from conceptbot.pipeline.retrieval import RelationRetriever, default_theta


def build_conceptbot(
    settings: Settings,
    config: str = "conceptbot",
    *,
    theta: float | None = None,
    planner_method: str = "auto",
    n: int = 5,
    fallback: bool | None = None,
    planner: str = "auto",
) -> ConceptBot:
    """The configured system (raises the layers' clear errors when a part is missing)."""
    store = open_store(settings)
    llm = open_llm(settings, store, module="pipeline")
    retriever = None
    graph_version = ""
    if config != "nokg":
        graph = open_graph(settings, fallback=fallback)
        embedder = open_embedder(settings, store)
        meta = getattr(getattr(graph, "primary", graph), "meta", {})
        graph_version = f"{settings.kg}:{meta.get('install', '')}:{meta.get('built_at', '')}"
        retriever = RelationRetriever(
            graph, embedder, theta if theta is not None else default_theta(embedder.model)
        )
    return ConceptBot(llm, retriever, config, store, graph_version, planner_method, n, planner)
