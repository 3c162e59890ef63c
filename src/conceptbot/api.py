"""The Python API: open a planner from settings or from backend objects, plan a request in a scene.

For robotics code that calls the planner itself (a ROS node, a notebook, an evaluation harness)
instead of going through the CLI or the web page. Everything here is also at the package top::

    import conceptbot

    planner = conceptbot.open_planner()  # the settings of `conceptbot plan`
    result = planner.plan("I would like a hollandaise sauce", conceptbot.load_scene("kitchen"))
    result.actions    # (PickAndPlace("butter", "ceramic bowl"), ..., Done())
    conceptbot.format_actions(result.actions)  # ['pick_and_place(butter, ceramic bowl)', ..., 'done()']
    result.refused, result.reason, result.trace
    result.to_dict()  # the JSON object `conceptbot plan --json` prints

    # watch it work: progress messages as each piece starts, each module's results as it finishes
    watch = conceptbot.Callbacks(on_progress=print, on_event=lambda name, data: print(name, data))
    planner.plan("Bring me something to eat", conceptbot.load_scene("kitchen"), observer=watch)

    # another system or backend, by the names the CLI uses
    conceptbot.open_planner("saycan", llm="openai-compatible:http://127.0.0.1:8000/v1#llama-3.3-70b")
    # your own backends: objects implementing conceptbot.LLM, KnowledgeGraph, Embedder
    conceptbot.open_planner(llm=my_llm, graph=my_graph, embedder=my_embedder)
"""

from __future__ import annotations

from dataclasses import fields
from pathlib import Path
from typing import Any

from conceptbot.core.config import Settings, load_settings
from conceptbot.core.errors import ConfigError
from conceptbot.core.scene import Scene
from conceptbot.core.system import PlannerSystem, SystemOptions
from conceptbot.knowledge.base import KnowledgeGraph
from conceptbot.models.embedder import Embedder
from conceptbot.models.llm import LLM
from conceptbot.scenes import resolve_scene
from conceptbot.systems import SYSTEMS, build_system


def open_planner(
    system: str = "conceptbot",
    *,
    settings: Settings | None = None,
    llm: str | LLM | None = None,
    graph: KnowledgeGraph | None = None,
    embedder: str | Embedder | None = None,
    options: SystemOptions | None = None,
    **overrides: Any,
) -> PlannerSystem:
    """A planner system, ready to :meth:`~conceptbot.core.system.PlannerSystem.plan`.

    Backends named in the settings are opened as the CLI opens them (the embedded model loads on
    the first plan, not here). Objects passed in replace the backend their setting names: the LLM
    and the embedder go behind the same cache and call log (``use_cache=False`` turns the cache
    off); the graph is used as given, without the Wikipedia fallback.

    Args:
        system: One of :data:`~conceptbot.systems.SYSTEMS` (``conceptbot``, ``saycan``, ``paper``, ...).
        settings: Settings to start from; default :func:`~conceptbot.core.config.load_settings`
            (``$CONCEPTBOT_HOME/config.toml`` and the environment).
        llm: A backend spec (``"openai:gpt-4o-mini"``, ``"llamacpp:qwen2.5-coder-1.5b"``), or an
            object implementing :class:`~conceptbot.models.llm.LLM`.
        graph: An object implementing :class:`~conceptbot.knowledge.base.KnowledgeGraph` (for a
            configured graph by spec, pass ``kg="conceptnet-api"``).
        embedder: An embedder spec (``"sentence-transformers:all-MiniLM-L6-v2"``), or an object
            implementing :class:`~conceptbot.models.embedder.Embedder`.
        options: How the ConceptBot systems are built (theta, planner, ...).
        **overrides: :class:`~conceptbot.core.config.Settings` fields by name, e.g.
            ``use_cache=False``, ``kg_fallback=False``, ``home="/data/conceptbot"``; they win over
            ``settings``.

    Returns:
        The planner system.

    Raises:
        ConfigError: Unknown system or setting, a value of the wrong type, or an object that does
            not implement its protocol (the message names what is missing).
        ConceptBotError: A configured backend cannot be opened (model not installed, no
            knowledge graph, ...), with a hint how to fix it.
    """
    if system not in SYSTEMS:
        raise ConfigError(f"unknown system {system!r}", hint=f"use one of {', '.join(SYSTEMS)}")
    if isinstance(llm, str):
        overrides["llm"], llm = llm, None
    if isinstance(embedder, str):
        overrides["embedder"], embedder = embedder, None
    _check_settings(overrides)
    if options is not None and not isinstance(options, SystemOptions):
        raise ConfigError(
            f"options must be a SystemOptions, got {type(options).__name__}",
            hint="e.g. options=conceptbot.SystemOptions(theta=0.6)",
        )
    _check_object("llm", llm, LLM)
    _check_object("graph", graph, KnowledgeGraph)
    _check_object("embedder", embedder, Embedder)
    if settings is None:
        settings = load_settings(**overrides)
    else:
        if overrides.get("home") is not None:
            overrides["home"] = Path(overrides["home"]).expanduser()
        settings = settings.with_overrides(**overrides)
    return build_system(settings, system, options, llm=llm, graph=graph, embedder=embedder)


def load_scene(ref: str | Path) -> Scene:
    """A scene by demo name (``"kitchen"``; see ``conceptbot scenes``) or from a JSON file.

    Args:
        ref: A demo scene name or the path of a scene file; an existing file wins.

    Returns:
        The validated scene.

    Raises:
        ConfigError: No such file or demo scene (the message lists the demo scenes), or the file is
            not a valid scene.
    """
    return resolve_scene(str(ref))


def _check_settings(overrides: dict[str, Any]) -> None:
    known = {f.name for f in fields(Settings)}
    for name in overrides:
        if name in known:
            continue
        if name in {f.name for f in fields(SystemOptions)}:
            raise ConfigError(
                f"{name} is a system option, not a setting",
                hint=f"pass options=conceptbot.SystemOptions({name}=...)",
            )
        raise ConfigError(f"unknown setting {name!r}", hint=f"settings: {', '.join(sorted(known))}")


def _check_object(label: str, value: object, protocol: type) -> None:
    """Raise when ``value`` (unless None) lacks a member of ``protocol``, naming what is missing."""
    if value is None or isinstance(value, protocol):
        return
    members = [*getattr(protocol, "__annotations__", {})]
    members += [n for n, v in vars(protocol).items() if callable(v) and not n.startswith("_")]
    missing = [m for m in members if not hasattr(value, m)]
    raise ConfigError(
        f"{label} must implement conceptbot.{protocol.__name__}; "
        f"{type(value).__name__} lacks {', '.join(missing) or 'its members'}",
        hint=f"give it {', '.join(members)} (see the {protocol.__name__} docstring)",
    )
