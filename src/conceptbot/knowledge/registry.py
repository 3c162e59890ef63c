"""Knowledge graph backends by name, and the composed graph the product uses.

Specs (``CONCEPTBOT_KG`` / ``--kg``)::

    sqlite                        the local SQLite graph (default; `conceptbot kg install`)
    conceptnet-api[:BASE_URL]     the ConceptNet 5 REST API with the paper's cache
    conceptnet-api-cache          that cache only, never the network
"""

from __future__ import annotations

from collections.abc import Callable

from conceptbot.core.config import Settings
from conceptbot.core.errors import ConfigError
from conceptbot.knowledge.base import KnowledgeGraph
from conceptbot.knowledge.fallback import FallbackGraph

GraphFactory = Callable[[str, Settings], KnowledgeGraph]
_GRAPHS: dict[str, GraphFactory] = {}


def register_graph(name: str, factory: GraphFactory) -> None:
    """Register a knowledge graph factory: ``factory(argument, settings) -> KnowledgeGraph``."""
    _GRAPHS[name] = factory


def create_graph(spec: str, settings: Settings) -> KnowledgeGraph:
    """The raw graph named by ``spec``.

    Raises:
        ConfigError: Unknown backend.
        KnowledgeUnavailableError: The graph cannot be opened.
    """
    name, _, argument = spec.strip().partition(":")
    if name not in _GRAPHS:
        raise ConfigError(f"unknown knowledge graph {name!r}", hint=f"known: {', '.join(sorted(_GRAPHS))}")
    return _GRAPHS[name](argument, settings)


def open_graph(
    settings: Settings,
    *,
    fallback: bool | None = None,
    choose: Callable[..., object] | None = None,
) -> KnowledgeGraph:
    """The configured graph, with the Wikipedia fallback in front when enabled.

    Args:
        settings: Resolved settings (``kg``, ``kg_fallback``, timeouts).
        fallback: Override ``settings.kg_fallback``.
        choose: Interactive page chooser for the fallback (the CLI passes one), or None for the
            documented ranking rule.
    """
    primary = create_graph(settings.kg, settings)
    if not (settings.kg_fallback if fallback is None else fallback):
        return primary
    from conceptbot.knowledge.wikipedia import WikipediaClient, WikipediaFallback

    client = WikipediaClient(settings.wikipedia_url, timeout_s=min(settings.timeout_s, 10.0), max_retries=1)
    return FallbackGraph(primary, WikipediaFallback(client, choose=choose))


def _sqlite(argument: str, settings: Settings) -> KnowledgeGraph:
    from conceptbot.knowledge.sqlite_store import SQLiteGraph

    return SQLiteGraph(settings.kg_path)


def _api(argument: str, settings: Settings, cache_only: bool = False) -> KnowledgeGraph:
    from conceptbot.knowledge.conceptnet_api import DEFAULT_BASE_URL, ConceptNetAPI

    return ConceptNetAPI(
        settings.home / "kg" / "conceptnet_api_cache.db",
        base_url=argument or DEFAULT_BASE_URL,
        timeout_s=settings.timeout_s,
        max_retries=settings.max_retries,
        cache_only=cache_only,
    )


register_graph("sqlite", _sqlite)
register_graph("conceptnet-api", _api)
register_graph("conceptnet-api-cache", lambda argument, settings: _api(argument, settings, cache_only=True))
