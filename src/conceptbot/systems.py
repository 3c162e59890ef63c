"""Every planner system by name, built from settings: ConceptBot's configurations and SayCan.

The one registry the CLI (``plan``, ``bench``, ``sim``), the web page and the Python API
(:func:`conceptbot.open_planner`) build planners through. It sits above ``pipeline``,
``baselines`` and ``household`` (it composes them) and below ``sim``, ``bench``, ``cli`` and
``web`` (they use what it builds).

Example::

    from conceptbot.systems import SystemOptions, build_system

    system = build_system(settings, "paper", SystemOptions(n=3))
    plan = system.plan("Bring me something to eat", scene)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import partial
from typing import Protocol

from conceptbot.baselines.saycan import SayCan
from conceptbot.core.config import Settings
from conceptbot.core.errors import ConfigError, NotSupportedError
from conceptbot.core.observe import Observer
from conceptbot.core.plan import Feedback, Plan
from conceptbot.core.scene import Scene
from conceptbot.knowledge.base import KnowledgeGraph
from conceptbot.knowledge.registry import open_graph
from conceptbot.models.cache_db import CacheStore
from conceptbot.models.caching import CachedEmbedder, CachedLLM
from conceptbot.models.embedder import Embedder
from conceptbot.models.llm import LLM
from conceptbot.models.registry import open_embedder, open_llm, open_run_store
from conceptbot.pipeline.conceptbot import CONFIGS as CONCEPTBOT_CONFIGS
from conceptbot.pipeline.conceptbot import PLANNERS, ConceptBot
from conceptbot.pipeline.planner import METHODS
from conceptbot.pipeline.retrieval import RelationRetriever, default_theta


class PlannerSystem(Protocol):
    """Anything that plans a request in a scene (what :func:`build_system` returns)."""

    def plan(
        self,
        request: str,
        scene: Scene,
        risk: bool = False,
        feedback: Feedback | None = None,
        observer: Observer | None = None,
    ) -> Plan:
        """Plan ``request`` in ``scene``.

        Args:
            request: What the person asked for, in their words.
            scene: The objects the robot sees, what it may pick and where things may go.
            risk: Rate each object's danger 1-5 (the Risk Index) instead of yes/no properties.
            feedback: What happened when an earlier plan ran (steps done, the failed action), to
                plan the rest from there; None for a fresh plan.
            observer: Gets a short message as each piece of work starts and each module's results
                as they finish (:class:`~conceptbot.core.observe.Observer`); None: nobody listens.

        Returns:
            The plan (actions ending with ``done()``, or a refusal with its reason) and its trace.

        Raises:
            ConfigError: The request or scene is unusable (empty, too long).
            ConceptBotError: A backend failed (unreachable, malformed output after a retry).
        """
        ...


@dataclass(frozen=True)
class SystemOptions:
    """How a ConceptBot system is built. SayCan has no options and ignores them.

    Attributes:
        theta: Cosine threshold for keeping graph relations, in [-1, 1]; None: the embedder's
            calibrated default (:func:`conceptbot.pipeline.retrieval.default_theta`).
        planner_method: The step planner's LLM score: ``auto`` (by backend), ``logprob`` (one
            pass) or ``vote`` (``n`` completions).
        n: Completions per step for ``vote`` (the paper's 5).
        fallback: Ask Wikipedia when the configured graph knows too little; None:
            ``settings.kg_fallback``. Not for a graph passed in as an object (compose it yourself).
        planner: ``auto`` (the goal planner), ``goal`` or ``steps`` (the paper's step-by-step
            planner); the ``paper`` systems are always ``steps``.

    Raises:
        ConfigError: A value of the wrong type, out of range or not one of the choices.
    """

    theta: float | None = None
    planner_method: str = "auto"
    n: int = 5
    fallback: bool | None = None
    planner: str = "auto"

    def __post_init__(self) -> None:
        if self.theta is not None:
            if isinstance(self.theta, bool) or not isinstance(self.theta, int | float):
                raise ConfigError(f"theta must be a number or None, got {self.theta!r}")
            if not (math.isfinite(self.theta) and -1.0 <= self.theta <= 1.0):
                raise ConfigError(
                    f"theta must be a cosine threshold in [-1, 1], got {self.theta!r}",
                    hint="leave it None for the embedder's calibrated default",
                )
            # A float either way: theta is part of OPE cache keys, where 1 and 1.0 differ.
            object.__setattr__(self, "theta", float(self.theta))
        _choice("planner_method", self.planner_method, METHODS)
        _choice("planner", self.planner, PLANNERS)
        if isinstance(self.n, bool) or not isinstance(self.n, int) or self.n < 1:
            raise ConfigError(f"n must be a whole number of completions >= 1, got {self.n!r}")
        if self.fallback is not None and not isinstance(self.fallback, bool):
            raise ConfigError(f"fallback must be True, False or None, got {self.fallback!r}")


def _choice(label: str, value: object, choices: tuple[str, ...]) -> None:
    if value not in choices:
        raise ConfigError(f"{label} must be one of {', '.join(choices)}, got {value!r}")


@dataclass(frozen=True)
class _Parts:
    """Backends given as objects, each in place of the one its setting names (None: the setting's)."""

    llm: LLM | None = None
    graph: KnowledgeGraph | None = None
    embedder: Embedder | None = None


_Builder = Callable[[Settings, SystemOptions, _Parts], PlannerSystem]


def build_system(
    settings: Settings,
    name: str,
    options: SystemOptions | None = None,
    *,
    llm: LLM | None = None,
    graph: KnowledgeGraph | None = None,
    embedder: Embedder | None = None,
) -> PlannerSystem:
    """The system called ``name``, its backends opened from ``settings`` or passed in.

    Args:
        settings: Resolved settings (backend specs, the home directory with the caches).
        name: One of :data:`SYSTEMS`.
        options: How to build a ConceptBot system (default: ``SystemOptions()``).
        llm: A model to use instead of ``settings.llm``. Like a configured one, it goes behind
            the response cache and call log (``settings.use_cache``) unless it already is.
        graph: A knowledge graph to use as given instead of ``settings.kg`` and its Wikipedia
            fallback (systems without a graph, ``saycan`` and ``nokg``, do not use it).
        embedder: An embedder to use instead of ``settings.embedder``, behind the embedding cache.

    Returns:
        The planner system.

    Raises:
        ConfigError: Unknown system, or options that do not fit it.
        NotSupportedError: SayCan with a backend that cannot score options.
        ConceptBotError: A configured backend cannot be opened (model not installed, no
            knowledge graph, ...), with a hint how to fix it.
    """
    builder = _BUILDERS.get(name)
    if builder is None:
        raise ConfigError(f"unknown system {name!r}", hint=f"use one of {', '.join(SYSTEMS)}")
    options = options if options is not None else SystemOptions()
    if graph is not None and options.fallback is not None:
        raise ConfigError(
            "the fallback option applies to the configured graph, not to a graph passed in",
            hint="compose the fallback yourself: conceptbot.knowledge.fallback.FallbackGraph(graph, ...)",
        )
    return builder(settings, options, _Parts(llm, graph, embedder))


def _llm(settings: Settings, store: CacheStore | None, given: LLM | None, module: str) -> LLM:
    if given is None:
        return open_llm(settings, store, module=module)
    if isinstance(given, CachedLLM):
        return given.with_module(module)
    return CachedLLM(given, store, use_cache=settings.use_cache, module=module)


def _embedder(settings: Settings, store: CacheStore | None, given: Embedder | None) -> Embedder:
    if given is None:
        return open_embedder(settings, store)
    if isinstance(given, CachedEmbedder):
        return given
    return CachedEmbedder(given, store, use_cache=settings.use_cache)


def graph_version(label: str, graph: KnowledgeGraph) -> str:
    """What names the graph's contents in OPE cache keys: ``LABEL:VERSION``.

    Args:
        label: The graph's spec (``settings.kg``), or its name for a graph passed in.
        graph: The graph.

    Returns:
        E.g. ``sqlite:omcs+wordnet:2026-11-02T10:00:00Z``.
    """
    # A graph without a version (a live API) was keyed "LABEL::" before graphs had a ``version``;
    # the same text keeps the OPE results cached since then valid.
    return f"{label}:{graph.version or ':'}"


def _saycan(settings: Settings, options: SystemOptions, parts: _Parts) -> PlannerSystem:
    llm = _llm(settings, open_run_store(settings), parts.llm, "saycan")
    if not llm.capabilities.scoring:
        raise NotSupportedError(
            f"SayCan scores options by log-probability, which the {llm.backend} backend cannot do",
            hint="use the llamacpp backend for SayCan",
        )
    return SayCan(llm)


def _conceptbot(config: str, settings: Settings, options: SystemOptions, parts: _Parts) -> PlannerSystem:
    store = open_run_store(settings)
    llm = _llm(settings, store, parts.llm, "pipeline")
    retriever = None
    version = ""
    if config != "nokg":
        if parts.graph is not None:
            graph, label = parts.graph, parts.graph.name
        else:
            graph, label = open_graph(settings, fallback=options.fallback), settings.kg
        embedder = _embedder(settings, store, parts.embedder)
        version = graph_version(label, graph)
        theta = options.theta if options.theta is not None else default_theta(embedder.model)
        retriever = RelationRetriever(graph, embedder, theta)
    # OPE's results are derived from LLM answers, so --no-cache (settings.use_cache False) covers
    # them too: without the store OPE neither reads nor writes its value cache.
    ope_store = store if settings.use_cache else None
    return ConceptBot(
        llm, retriever, config, ope_store, version, options.planner_method, options.n, options.planner
    )


def _paper(config: str, settings: Settings, options: SystemOptions, parts: _Parts) -> PlannerSystem:
    if options.planner not in ("auto", "steps"):
        raise ConfigError(
            f"the paper systems plan step by step; planner={options.planner!r} does not fit",
            hint=f"use system {config!r} for the {options.planner} planner",
        )
    return _conceptbot(config, settings, replace(options, planner="steps"), parts)


_BUILDERS: dict[str, _Builder] = {
    "saycan": _saycan,
    **{config: partial(_conceptbot, config) for config in CONCEPTBOT_CONFIGS},
    "paper": partial(_paper, "conceptbot"),
    "paper-nokg": partial(_paper, "nokg"),
}

SYSTEMS: tuple[str, ...] = tuple(_BUILDERS)
"""Every system by name: SayCan; the ConceptBot configurations (the goal planner: ``conceptbot``,
``urp`` without OPE, ``nokg`` without the graph; ``ope`` is the paper's OPE-only ablation); and the
paper's pipeline with its step-by-step planner, with and without the graph (``paper``,
``paper-nokg``)."""
