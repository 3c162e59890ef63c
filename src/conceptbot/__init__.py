"""ConceptBot: commonsense-grounded LLM planning for robots.

The Python API (:mod:`conceptbot.api`)::

    import conceptbot

    planner = conceptbot.open_planner()
    result = planner.plan("I would like a hollandaise sauce", conceptbot.load_scene("kitchen"))
    result.actions, result.refused, result.reason, result.trace, result.to_dict()

The names below load on first use, so ``import conceptbot`` stays cheap (no model runtime, no
torch) for the CLI and for code that only wants one submodule.

Layers (imports flow one way, each importing only those below it; ``tests/test_layers.py`` checks
it; an arrow points from the importer to what it imports): ``api`` -> ``cli`` -> ``web``, ``ros2``
(the ROS 2 node) -> ``sim``, ``bench`` -> ``systems`` -> ``baselines``, ``household`` ->
``pipeline`` -> ``knowledge`` -> ``models``, ``scenes`` -> ``core``.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from conceptbot.core.version import __version__

_EXPORTS: dict[str, str] = {
    "open_planner": "conceptbot.api",
    "load_scene": "conceptbot.api",
    "scene_from_dict": "conceptbot.core.scene",
    "Scene": "conceptbot.core.scene",
    "Plan": "conceptbot.core.plan",
    "PickAndPlace": "conceptbot.core.plan",
    "Done": "conceptbot.core.plan",
    "format_actions": "conceptbot.core.plan",
    "read_actions": "conceptbot.core.plan",
    "Observer": "conceptbot.core.observe",
    "Callbacks": "conceptbot.core.observe",
    "FanOut": "conceptbot.core.observe",
    "Settings": "conceptbot.core.config",
    "load_settings": "conceptbot.core.config",
    "SYSTEMS": "conceptbot.systems",
    "SystemOptions": "conceptbot.core.system",
    "PlannerSystem": "conceptbot.core.system",
    "LLM": "conceptbot.models.llm",
    "KnowledgeGraph": "conceptbot.knowledge.base",
    "Embedder": "conceptbot.models.embedder",
    "ConceptBotError": "conceptbot.core.errors",
    "ConfigError": "conceptbot.core.errors",
}

__all__ = [  # the names of _EXPORTS, written out for tools that read __all__ without running it
    "LLM",
    "SYSTEMS",
    "Callbacks",
    "ConceptBotError",
    "ConfigError",
    "Done",
    "Embedder",
    "FanOut",
    "KnowledgeGraph",
    "Observer",
    "PickAndPlace",
    "Plan",
    "PlannerSystem",
    "Scene",
    "Settings",
    "SystemOptions",
    "__version__",
    "format_actions",
    "load_scene",
    "load_settings",
    "open_planner",
    "read_actions",
    "scene_from_dict",
]

if TYPE_CHECKING:  # the same names for type checkers and editors, which do not run __getattr__
    from conceptbot.api import load_scene, open_planner
    from conceptbot.core.config import Settings, load_settings
    from conceptbot.core.errors import ConceptBotError, ConfigError
    from conceptbot.core.observe import Callbacks, FanOut, Observer
    from conceptbot.core.plan import Done, PickAndPlace, Plan, format_actions, read_actions
    from conceptbot.core.scene import Scene, scene_from_dict
    from conceptbot.core.system import PlannerSystem, SystemOptions
    from conceptbot.knowledge.base import KnowledgeGraph
    from conceptbot.models.embedder import Embedder
    from conceptbot.models.llm import LLM
    from conceptbot.systems import SYSTEMS


def __getattr__(name: str) -> Any:
    """Import an API name's module on first use (PEP 562)."""
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'conceptbot' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS})
