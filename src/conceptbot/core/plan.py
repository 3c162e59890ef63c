"""Actions, plans and the trace that explains them.

An action is typed. On the tabletop it is :class:`PickAndPlace` (an object and its destination) or
:class:`Done`; in a household (SafeAgentBench) it is a :class:`HouseholdAction`, one of the 17
actions of :data:`HOUSEHOLD_ACTIONS`. A plan's actions are a tuple of one family. Their text
(``pick_and_place(object, destination)``, ``done()``; ``find Mug``, ``fillLiquid Mug water``) is
written only by :func:`format_action` and read only here: by :func:`parse_action` (against a scene:
an object that is not in the scene, a self-placement or a malformed command never reaches a plan),
:func:`read_action` (text from a results file, unchecked) and :func:`parse_household_action`. Text
is for prompts, results files and JSON; everything else passes actions.

:meth:`Plan.to_dict` is the JSON contract of ``conceptbot plan --json``; :func:`plan_schema` gives
its JSON Schema (``conceptbot/schemas/plan.schema.json``, shipped with the package).
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from typing import Any

from conceptbot.core.scene import Scene
from conceptbot.core.trace import ClarifyingQuestion, PlanTrace
from conceptbot.core.usage import Usage

DONE = "done()"
_PICK = re.compile(r"pick_and_place\s*\(\s*([^,()]+?)\s*,\s*([^,()]+?)\s*\)", re.IGNORECASE)
_DONE = re.compile(r"done\s*\(\s*\)", re.IGNORECASE)


@dataclass(frozen=True)
class PickAndPlace:
    """Pick ``obj`` up and put it in or on ``destination`` (both the scene's names)."""

    obj: str
    destination: str

    @property
    def is_done(self) -> bool:
        """False: a move."""
        return False

    def __str__(self) -> str:
        return format_action(self)


@dataclass(frozen=True)
class Done:
    """The plan is finished."""

    @property
    def is_done(self) -> bool:
        """True: the end of the plan."""
        return True

    def __str__(self) -> str:
        return format_action(self)


#: One action of a tabletop plan.
Action = PickAndPlace | Done

# SafeAgentBench's 17 actions: verb -> (takes an object, takes a liquid). drop, throw and pour act on
# what the hand holds.
HOUSEHOLD_ACTIONS: dict[str, tuple[bool, bool]] = {
    "find": (True, False),
    "pick": (True, False),
    "put": (True, False),
    "open": (True, False),
    "close": (True, False),
    "slice": (True, False),
    "turn_on": (True, False),
    "turn_off": (True, False),
    "drop": (False, False),
    "throw": (False, False),
    "break": (True, False),
    "cook": (True, False),
    "dirty": (True, False),
    "clean": (True, False),
    "fillLiquid": (True, True),
    "emptyLiquid": (True, False),
    "pour": (False, False),
}
LIQUIDS = ("water", "coffee", "wine")
"""The liquids ``fillLiquid`` takes."""


@dataclass(frozen=True)
class HouseholdAction:
    """One of SafeAgentBench's 17 actions: ``verb`` (canonical spelling, a key of
    :data:`HOUSEHOLD_ACTIONS`), ``obj`` (as written; the executor maps it to an object type) and
    ``liquid`` for ``fillLiquid``."""

    verb: str
    obj: str | None = None
    liquid: str | None = None

    @property
    def is_done(self) -> bool:
        """False: a household plan has no end marker."""
        return False

    def __str__(self) -> str:
        return format_action(self)


#: Any action, of either world.
AnyAction = PickAndPlace | Done | HouseholdAction


def format_action(action: AnyAction) -> str:
    """The action's text: ``pick_and_place(obj, destination)``, ``done()``, or a household step as
    the benchmark writes it (``find Mug``, ``fillLiquid Mug water``, ``pour``)."""
    if isinstance(action, Done):
        return DONE
    if isinstance(action, HouseholdAction):
        return " ".join(p for p in (action.verb, action.obj, action.liquid) if p)
    return f"pick_and_place({action.obj}, {action.destination})"


def format_actions(actions: Iterable[AnyAction]) -> list[str]:
    """The actions' texts, in order (for a results file, JSON or a prompt)."""
    return [format_action(a) for a in actions]


class InvalidActionError(ValueError):
    """Text that is not a valid action (in the scene, where one is given); the message says why."""


_VERBS = {v.lower(): v for v in HOUSEHOLD_ACTIONS}
_STEP_SPLIT = re.compile(r"[\s,()]+")


def parse_household_action(text: str) -> HouseholdAction:
    """One household step as people (and the dataset) write it: forgiving about the spelling
    (``turn on candle``, ``find Watering Can``, any case), strict about what it accepts (a known
    verb, the right number of arguments, a liquid of :data:`LIQUIDS`).

    Raises:
        InvalidActionError: Unknown verb, missing or extra arguments, unknown liquid.
    """
    words = [w for w in _STEP_SPLIT.split(text.strip()) if w]
    if not words:
        raise InvalidActionError("empty step")
    head = words[0].lower()
    if head == "turn" and len(words) > 1 and words[1].lower() in ("on", "off"):
        head, words = f"turn_{words[1].lower()}", [f"turn_{words[1].lower()}", *words[2:]]
    verb = _VERBS.get(head.replace("-", "_"))
    if verb is None:
        raise InvalidActionError(f"unknown action {words[0]!r}")
    takes_object, takes_liquid = HOUSEHOLD_ACTIONS[verb]
    rest = words[1:]
    liquid = None
    if takes_liquid:
        if not rest or rest[-1].lower() not in LIQUIDS:
            raise InvalidActionError(
                f"{verb} needs a liquid ({', '.join(LIQUIDS)}) after the object: {text!r}"
            )
        liquid = rest.pop().lower()
    if not takes_object:
        # "pour" and "drop" act on the held object; a trailing word is tolerated (the dataset
        # writes "pour Mug" once) but ignored.
        return HouseholdAction(verb)
    if not rest:
        raise InvalidActionError(f"{verb} needs an object: {text!r}")
    return HouseholdAction(verb, " ".join(rest), liquid)


def parse_household_actions(texts: Iterable[str]) -> tuple[HouseholdAction, ...]:
    """Each text's household action (see :func:`parse_household_action`)."""
    return tuple(parse_household_action(t) for t in texts)


def _clean(name: str) -> str:
    return name.strip().strip("'\"`").strip()


def read_action(text: str) -> Action:
    """The first action in ``text`` as written, unchecked (a results file's, a user's plan file's):
    the names are kept as they are.

    Raises:
        InvalidActionError: No action in the text.
    """
    pick = _PICK.search(text)
    done = _DONE.search(text)
    if pick is None and done is None:
        raise InvalidActionError(f"not an action: {text.strip()[:80]!r}")
    if pick is None or (done is not None and done.start() < pick.start()):
        return Done()
    return PickAndPlace(_clean(pick.group(1)), _clean(pick.group(2)))


def read_actions(texts: Iterable[str]) -> tuple[Action, ...]:
    """Each text's action, unchecked (see :func:`read_action`)."""
    return tuple(read_action(t) for t in texts)


def parse_action(text: str, scene: Scene) -> Action:
    """The first action in ``text``, with names mapped to the scene's exact spelling.

    Raises:
        InvalidActionError: No action, an unknown object, a non-pickable object, a target that is not a
            destination, or an object placed on itself.
    """
    return check_action(read_action(text), scene)


def check_action(action: Action, scene: Scene) -> Action:
    """``action`` with its names in the scene's exact spelling, checked as :func:`parse_action`
    checks text (for actions made in code: a planner's, a grader's).

    Raises:
        InvalidActionError: An unknown object, a non-pickable object, a target that is not a
            destination, or an object placed on itself.
    """
    if isinstance(action, Done):
        return action
    obj_name, target_name = action.obj, action.destination
    obj, target = scene.get(obj_name), scene.get(target_name)
    if obj is None:
        raise InvalidActionError(f"object not in the scene: {obj_name!r}")
    if target is None:
        raise InvalidActionError(f"destination not in the scene: {target_name!r}")
    if not obj.pickable:
        raise InvalidActionError(f"{obj.name!r} cannot be picked")
    if not target.destination:
        raise InvalidActionError(f"{target.name!r} is not a destination")
    if obj.name == target.name:
        raise InvalidActionError(f"cannot place {obj.name!r} on itself")
    return PickAndPlace(obj.name, target.name)


def valid_actions(scene: Scene, include_done: bool = True) -> list[Action]:
    """Every valid ``pick_and_place`` in the scene (no self-placement), then ``done()``."""
    actions: list[Action] = [PickAndPlace(o, d) for o in scene.pickable for d in scene.destinations if o != d]
    return [*actions, Done()] if include_done else actions


@dataclass(frozen=True)
class CandidateScore:
    """One candidate's scores at one step.

    Attributes:
        action: The action text.
        llm: S_LLM (normalised over the candidates).
        affordance: S_aff = S_pick * S_place * S_bbox * S_prop.
        combined: S_LLM * S_aff.
        factors: The affordance factors by name, for the trace.
    """

    action: str
    llm: float
    affordance: float
    combined: float
    factors: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class Step:
    """One planner step: the chosen action, the best candidates, and rejected LLM outputs.

    ``method`` is the planner's way of choosing (``saycan``, ``logprob``, ``vote``, ``decide``);
    ``scoring`` how the backend scored the options (``logprob`` embedded; over HTTP ``echo``,
    ``search``, ``chat-logprobs`` or ``vote``; empty where nothing was scored).
    """

    index: int
    chosen: str
    candidates: tuple[CandidateScore, ...]
    rejected: tuple[str, ...] = ()
    method: str = "logprob"
    scoring: str = ""

    def to_dict(self) -> dict[str, Any]:
        """JSON form (as in ``conceptbot plan --json``)."""
        return {
            "index": self.index,
            "chosen": self.chosen,
            "method": self.method,
            "scoring": self.scoring,
            "rejected": list(self.rejected),
            "candidates": [
                {
                    "action": c.action,
                    "llm": round(c.llm, 4),
                    "affordance": round(c.affordance, 4),
                    "combined": round(c.combined, 4),
                    "factors": {k: round(v, 4) for k, v in c.factors.items()},
                }
                for c in self.candidates
            ],
        }


@dataclass(frozen=True)
class Feedback:
    """What happened when part of a plan ran, given back to a planner so it can plan the rest.

    Attributes:
        executed: Actions that succeeded, in order (the new plan starts with them).
        failed: ``(action, reason)`` for each action that failed; the planner will not choose them again.
    """

    executed: tuple[Action, ...] = ()
    failed: tuple[tuple[Action, str], ...] = ()

    @property
    def failed_actions(self) -> set[Action]:
        """The failed actions."""
        return {action for action, _ in self.failed}

    def script_lines(self) -> list[str]:
        """The failures as comment lines for a robot-script prompt."""
        return [f"# failed: {format_action(action)} ({reason})" for action, reason in self.failed]


@dataclass
class Plan:
    """A plan with everything needed to explain it.

    Attributes:
        actions: The actions: a tabletop plan's end with :class:`Done`; a household plan's are
            :class:`HouseholdAction` (no end marker).
        steps: Per-step scores (the tabletop planners).
        refused: True when the planner judged the request unsafe.
        reason: Why it refused (or None); a household planner gives its reasoning for a plan too.
        trace: Everything retrieved and decided on the way (empty for a plan built by hand).
        usage: Per-module tokens, time and cost.
        confidence: The probability that the plan's calibrated decisions are all right (their
            product; an answered question counts as sure), where the planner calibrates them; None
            elsewhere.
        questions: What the planner asked, or would ask, where a decision's conformal prediction set
            holds both answers (most uncertain first), with the answers given.
    """

    actions: tuple[AnyAction, ...]
    steps: list[Step] = field(default_factory=list)
    refused: bool = False
    reason: str | None = None
    trace: PlanTrace = field(default_factory=PlanTrace)
    usage: dict[str, Usage] = field(default_factory=dict)
    confidence: float | None = None
    questions: tuple[ClarifyingQuestion, ...] = ()

    def __post_init__(self) -> None:
        self.actions = tuple(self.actions)
        self.questions = tuple(self.questions)
        wrong = [a for a in self.actions if not isinstance(a, AnyAction)]
        if wrong:  # text is read into actions at the edge (read_action, parse_action), never here
            raise TypeError(
                f"a plan's actions are PickAndPlace, Done or HouseholdAction, not {type(wrong[0]).__name__}"
            )
        if len({isinstance(a, HouseholdAction) for a in self.actions}) > 1:
            raise TypeError("a plan's actions are all tabletop actions or all household actions")

    def to_dict(self) -> dict[str, Any]:
        """The JSON contract of ``conceptbot plan --json``."""
        return {
            "plan": format_actions(self.actions),
            "steps": [s.to_dict() for s in self.steps],
            "refused": self.refused,
            "reason": self.reason,
            "trace": self.trace.to_dict(),
            "usage": usage_dict(self.usage),
            "confidence": None if self.confidence is None else round(self.confidence, 4),
            "questions": [q.to_dict() for q in self.questions],
        }


def usage_dict(usage: Mapping[str, Usage]) -> dict[str, dict[str, Any]]:
    """Per-module usage as ``conceptbot plan --json`` shows it (latency to the millisecond)."""
    return {
        module: {
            "prompt_tokens": u.prompt_tokens,
            "completion_tokens": u.completion_tokens,
            "latency_s": round(u.latency_s, 3),
            "cost_usd": u.cost_usd,
            "calls": u.calls,
        }
        for module, u in usage.items()
    }


@cache
def _schema_text() -> str:
    return resources.files("conceptbot.schemas").joinpath("plan.schema.json").read_text(encoding="utf-8")


def plan_schema() -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of :meth:`Plan.to_dict`, i.e. of ``conceptbot plan --json``.

    Strict where the contract is stable (the top-level keys, steps, usage); the trace's parts differ
    by planner, so known parts are typed and others allowed. A fresh copy on every call.

    Returns:
        The schema as a dict, e.g. for ``jsonschema.validate(plan.to_dict(), plan_schema())``.
    """
    return json.loads(_schema_text())
