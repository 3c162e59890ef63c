"""What a planner system is, for every layer that uses one: the two protocols (a tabletop planner
and a household planner) and the options a ConceptBot system is built with.

:mod:`conceptbot.systems` builds systems by name; the simulator, the benchmarks, the web page and
the ROS 2 node take them through these protocols and so depend on ``core`` only.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from conceptbot.core.errors import ConfigError
from conceptbot.core.observe import Observer
from conceptbot.core.plan import Feedback, Plan
from conceptbot.core.scene import HouseScene, Scene
from conceptbot.core.trace import ClarifyingQuestion

Ask = Callable[[ClarifyingQuestion], str | None]
"""Asks the person a question where the planner is unsure; returns ``yes``, ``no`` or None (no
answer: the plan acts on the likelier answer and keeps the question open)."""

METHODS = ("auto", "logprob", "vote")
"""The step planner's LLM scores: ``auto`` (by backend), ``logprob`` (one pass), ``vote`` (``n``
completions)."""
PLANNERS = ("auto", "goal", "steps")
COVERAGES = (0.8, 0.9, 0.95)
"""The coverages the conformal calibration ships thresholds for."""
ASK_ALL = 1.0
"""The coverage at which every calibrated decision is a question (a set of every answer always
holds the right one, so it needs no fit): the most a person's answers can do for a plan."""
LEVELS = ("plan", "decision")
#: How the goal planner reads a request: ``restated`` (the rules on its words and on the model's
#: plain form of it, the better kept; ``pipeline/goal/aided.py``) or ``words`` (the rules alone).
READINGS = ("restated", "words")
#: How a target taking one object is judged sure (:mod:`conceptbot.pipeline.goal_planner.asking`):
#: ``fits``, by the calibrated P(yes) that its likeliest candidate fits (any object that fits will
#: do); ``softmax``, by that candidate's share of a softmax over the ranking (as before 2026-12-03).
WHICH_ONE = ("fits", "softmax")
"""What the conformal coverage holds for: ``plan`` (every calibrated decision of a plan at once, the
default) or ``decision`` (each decision on its own)."""
"""ConceptBot's planners: ``auto`` (the goal planner), ``goal``, ``steps`` (the paper's)."""


class PlannerSystem(Protocol):
    """Anything that plans a request in a tabletop scene (what
    :func:`conceptbot.systems.build_system` returns)."""

    def plan(
        self,
        request: str,
        scene: Scene,
        risk: bool = False,
        feedback: Feedback | None = None,
        observer: Observer | None = None,
        ask: Ask | None = None,
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
            ask: Asks the person where a calibrated decision is unsure (:data:`Ask`); None: nobody
                is asked, and the plan lists the questions it would ask. Planners without
                calibrated decisions (SayCan, the step planner) never ask.

        Returns:
            The plan (actions ending with :class:`~conceptbot.core.plan.Done`, or a refusal with its
            reason) and its trace.

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
        coverage: How often the goal planner's prediction set must hold a decision's right answer
            (one of :data:`COVERAGES`, or :data:`ASK_ALL`: ask about every one); higher asks more.
        level: What the coverage holds for (:data:`LEVELS`): ``plan``, all of a plan's calibrated
            decisions together, or ``decision``, each one (asks less, is wrong more often).
        reading: How the goal planner reads the request (:data:`READINGS`): ``restated`` (one more
            model call, a median of 1.0 s on the embedded model) or ``words`` (the rules alone, as
            before 2026-12-02). ``sampled`` was removed (2026-12-06): it is refused with a clear error.
        which_one: How a target taking one object is judged sure (:data:`WHICH_ONE`); None: the
            rule the calibration names (``softmax`` for the shipped one: on dev, ``fits`` asked a
            little less and succeeded a little less, docs/asking.md).
        own_calibration: Read the model's own conformal thresholds where ``conceptbot calibrate
            --conformal`` wrote them; False: the shipped ones (what ``calibrate --conformal`` plans
            by, so that it never reads the file it is about to replace, damaged or not).

    Raises:
        ConfigError: A value of the wrong type, out of range or not one of the choices.
    """

    theta: float | None = None
    planner_method: str = "auto"
    n: int = 5
    fallback: bool | None = None
    planner: str = "auto"
    coverage: float = 0.9
    level: str = "plan"
    reading: str = "restated"
    which_one: str | None = None
    own_calibration: bool = True

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
        _choice("coverage", self.coverage, (*COVERAGES, ASK_ALL))
        _choice("level", self.level, LEVELS)
        if self.reading == "sampled":
            raise ConfigError(
                "reading 'sampled' was removed: in plans it changed 1 of 145 outcomes "
                "(docs/notes/2026-12-04-sampled-readings.md)",
                hint=f"use one of {', '.join(READINGS)}",
            )
        _choice("reading", self.reading, READINGS)
        if self.which_one is not None:
            _choice("which_one", self.which_one, WHICH_ONE)
        if isinstance(self.n, bool) or not isinstance(self.n, int) or self.n < 1:
            raise ConfigError(f"n must be a whole number of completions >= 1, got {self.n!r}")
        if self.fallback is not None and not isinstance(self.fallback, bool):
            raise ConfigError(f"fallback must be True, False or None, got {self.fallback!r}")
        if not isinstance(self.own_calibration, bool):
            raise ConfigError(f"own_calibration must be True or False, got {self.own_calibration!r}")


def _choice(label: str, value: object, choices: tuple[object, ...]) -> None:
    if isinstance(value, bool) or value not in choices:
        raise ConfigError(f"{label} must be one of {', '.join(str(c) for c in choices)}, got {value!r}")


class HouseholdSystem(Protocol):
    """Anything that plans an instruction in a household scene with SafeAgentBench's 17 actions, or
    refuses it (what :func:`conceptbot.systems.build_household_system` returns)."""

    config: str

    def plan(
        self, request: str, scene: HouseScene, observer: Observer | None = None, ask: Ask | None = None
    ) -> Plan:
        """Plan ``request`` in ``scene`` or refuse it; where a calibrated decision is unsure (a
        planner built with a coverage), ``ask`` is asked and the answer applied.

        Returns:
            The plan (:class:`~conceptbot.core.plan.HouseholdAction` steps, or a refusal with its
            reason; ``reason`` holds the planner's reasoning for a plan too) and its trace
            (:class:`~conceptbot.core.trace.HouseholdTrace`).
        """
        ...
