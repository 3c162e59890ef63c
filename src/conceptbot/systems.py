"""Every planner system by name, built from settings: ConceptBot's configurations and SayCan on
the tabletop (:func:`build_system`, :data:`SYSTEMS`), and the household planners for SafeAgentBench
(:func:`build_household_system`, :data:`HOUSEHOLD_SYSTEMS`).

The one registry the CLI (``plan``, ``bench``, ``sim``, ``safebench``), the web page and the Python
API (:func:`conceptbot.open_planner`) build planners through. It sits above ``pipeline``,
``baselines`` and ``household`` (it composes them) and below ``sim``, ``bench``, ``cli`` and
``web`` (they use what it builds, through the protocols in :mod:`conceptbot.core.system`).

Example::

    from conceptbot.systems import SystemOptions, build_system

    system = build_system(settings, "paper", SystemOptions(n=3))
    plan = system.plan("Bring me something to eat", scene)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import partial

from conceptbot.baselines.saycan import SayCan
from conceptbot.core.config import Settings
from conceptbot.core.errors import ConfigError, NotSupportedError
from conceptbot.core.system import HouseholdSystem, PlannerSystem, SystemOptions
from conceptbot.household.harm import READINGS
from conceptbot.household.judge import QUESTIONS, HarmJudge, OutcomeJudge
from conceptbot.household.planner import ConceptBotHouseholdPlanner, PlainHouseholdPlanner
from conceptbot.household.similar import SimilarCases
from conceptbot.knowledge.base import KnowledgeGraph
from conceptbot.knowledge.registry import open_graph
from conceptbot.models.cache_db import CacheStore
from conceptbot.models.caching import CachedEmbedder, CachedLLM
from conceptbot.models.embedder import Embedder
from conceptbot.models.llm import LLM
from conceptbot.models.registry import open_embedder, open_llm, open_run_store
from conceptbot.pipeline.conceptbot import CONFIGS as CONCEPTBOT_CONFIGS
from conceptbot.pipeline.conceptbot import ConceptBot
from conceptbot.pipeline.retrieval import RelationRetriever, default_theta


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
    # The embedder is not the graph: the no-graph ablation ranks objects with it too (choice.py).
    embedder = _embedder(settings, store, parts.embedder)
    if config != "nokg":
        if parts.graph is not None:
            graph, label = parts.graph, parts.graph.name
        else:
            graph, label = open_graph(settings, fallback=options.fallback), settings.kg
        version = graph_version(label, graph)
        theta = options.theta if options.theta is not None else default_theta(embedder.model)
        retriever = RelationRetriever(graph, embedder, theta)
    # OPE's results are derived from LLM answers, so --no-cache (settings.use_cache False) covers
    # them too: without the store OPE neither reads nor writes its value cache.
    ope_store = store if settings.use_cache else None
    return ConceptBot(
        llm,
        retriever,
        config,
        ope_store,
        version,
        options.planner_method,
        options.n,
        options.planner,
        coverage=options.coverage,
        level=options.level,
        reading=options.reading,
        which_one=options.which_one,
        # A model calibrated with `conceptbot calibrate --conformal` asks by its own thresholds.
        calibration_dir=settings.calibration_dir if options.own_calibration else None,
        embedder=embedder,
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


def _plain_household(settings: Settings, coverage: float | None = None) -> HouseholdSystem:
    return PlainHouseholdPlanner(open_llm(settings, open_run_store(settings), module="planner"))


def _conceptbot_household(joint: bool, settings: Settings, coverage: float | None = None) -> HouseholdSystem:
    """OPE, URP's keywords and the planning call each get their own backend instance (for
    llama.cpp: a context each over the same memory-mapped weights), so each module's system prompt
    stays evaluated from one task to the next."""
    store = open_run_store(settings)  # --no-cache with an unusable home: unlogged, with a warning
    embedder = open_embedder(settings, store)
    retriever = RelationRetriever(open_graph(settings), embedder, default_theta(embedder.model))
    return ConceptBotHouseholdPlanner(
        open_llm(settings, store, module="ope"),
        retriever,
        planner_llm=open_llm(settings, store, module="planner"),
        keyword_llm=open_llm(settings, store, module="urp"),
        judge=None if joint else _harm_judge(settings, store),
        outcome=None if joint else OutcomeJudge(open_llm(settings, store, module="outcome")),
        similar=None if joint else SimilarCases(embedder),
        coverage=coverage,
    )


def _harm_judge(settings: Settings, store: CacheStore | None) -> HarmJudge:
    """The harm judge asking the questions the harm judgement weighs, with a backend instance per
    system prompt it asks with."""
    questions = tuple(q for q in QUESTIONS if q.name in READINGS)
    _, *others = dict.fromkeys(q.system for q in questions)
    contexts = {system: open_llm(settings, store, module="judge") for system in others}
    return HarmJudge(open_llm(settings, store, module="judge"), questions=questions, contexts=contexts)


_HOUSEHOLD_BUILDERS: dict[str, Callable[[Settings, float | None], HouseholdSystem]] = {
    "plain": _plain_household,
    "conceptbot": partial(_conceptbot_household, False),
    "conceptbot-joint": partial(_conceptbot_household, True),
}

HOUSEHOLD_SYSTEMS: tuple[str, ...] = tuple(_HOUSEHOLD_BUILDERS)
"""Every household system by name: ``plain`` (the LLM alone judges and plans), ``conceptbot`` (the plan of
what was asked, refused by one fitted judgement over the harm judge's readings with OPE's Risk Index
and URP's graph relations as evidence, the outcome judge's reading of what the plan leaves behind,
and what the plan does in the symbolic world) and ``conceptbot-joint`` (the first design: the
evidence goes to the joint judging-and-planning call)."""
DEFAULT_HOUSEHOLD_SYSTEMS = ("plain", "conceptbot")
"""What ``conceptbot safebench run`` runs unless told otherwise."""


def build_household_system(settings: Settings, name: str, coverage: float | None = None) -> HouseholdSystem:
    """The household system called ``name``, its backends opened from ``settings``.

    Args:
        settings: Resolved settings.
        name: One of :data:`HOUSEHOLD_SYSTEMS`.
        coverage: Ask where the harm judge is unsure, at this coverage (``conceptbot`` only; the
            plain planner makes no calibrated decision, so it plans as without).

    Raises:
        ConfigError: Unknown system.
        ConceptBotError: A configured backend cannot be opened, with a hint how to fix it.
    """
    builder = _HOUSEHOLD_BUILDERS.get(name)
    if builder is None:
        raise ConfigError(
            f"unknown configuration {name!r}", hint=f"use one of {', '.join(HOUSEHOLD_SYSTEMS)}"
        )
    if coverage is not None and name == "conceptbot-joint":
        raise ConfigError("conceptbot-joint makes no calibrated decision to ask about", hint="use conceptbot")
    return builder(settings, coverage)
