"""Every planner system by configuration name: the ConceptBot configurations and SayCan."""

from __future__ import annotations

from typing import Protocol

from conceptbot.baselines.saycan import SayCan
from conceptbot.core.config import Settings
from conceptbot.core.errors import ConfigError, NotSupportedError
from conceptbot.core.plan import EventSink, Feedback, Plan
from conceptbot.core.scene import Scene
from conceptbot.models.registry import open_llm, open_store
from conceptbot.pipeline.conceptbot import CONFIGS as CONCEPTBOT_CONFIGS
from conceptbot.pipeline.factory import build_conceptbot

SYSTEMS = ("saycan", *CONCEPTBOT_CONFIGS, "paper", "paper-nokg")
"""Every system by name: SayCan; the ConceptBot configurations (the goal planner: ``conceptbot``,
``urp`` without OPE, ``nokg`` without the graph; ``ope`` is the paper's OPE-only ablation); and the
paper's pipeline with its step-by-step planner, with and without the graph (``paper``,
``paper-nokg``)."""


class PlannerSystem(Protocol):
    """Anything that plans a request in a scene."""

    def plan(
        self,
        request: str,
        scene: Scene,
        risk: bool = False,
        progress=None,
        feedback: Feedback | None = None,
        events: EventSink | None = None,
    ) -> Plan:
        """Plan ``request`` in ``scene`` (continuing after ``feedback`` from an execution, if given;
        ``events`` gets each module's results as they finish)."""
        ...


def build_system(settings: Settings, config: str, **options) -> PlannerSystem:
    """The system called ``config`` (one of :data:`SYSTEMS`).

    Raises:
        ConfigError: Unknown configuration.
        NotSupportedError: SayCan with a backend that cannot score options.
    """
    if config == "saycan":
        llm = open_llm(settings, open_store(settings), module="saycan")
        if not llm.capabilities.scoring:
            raise NotSupportedError(
                f"SayCan scores options by log-probability, which the {llm.backend} backend cannot do",
                hint="use the llamacpp backend for SayCan",
            )
        return SayCan(llm)
    if config in ("paper", "paper-nokg"):
        base = "conceptbot" if config == "paper" else "nokg"
        return build_conceptbot(settings, base, planner="steps", **options)
    if config in CONCEPTBOT_CONFIGS:
        return build_conceptbot(settings, config, **options)
    raise ConfigError(f"unknown configuration {config!r}", hint=f"use one of {', '.join(SYSTEMS)}")
