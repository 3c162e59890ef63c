"""The request compiled into a small, checkable goal (URP's job, in a form a small model can fill).

A :class:`Goal` says which destination takes which objects by what description, how many ("one"
or "all" that fit), and whether the objects are to be stacked. The LLM fills it as JSON under a
schema whose destinations are the scene's (constrained decoding: it cannot invent one), after a few
worked examples (``prompts/goal_system.txt``). Whether to refuse is not asked here: a 1.5B model
asked for a refusal flag in the same reply refused ordinary requests ("a hollandaise sauce is not a
food item"); each planned move gets its own scored risk decision instead.

Descriptions that name scene objects ("the stapler", "a bag of chips") resolve to those objects by
their names (:func:`named_objects`); every other description ("a fruit", "an ingredient of
hollandaise sauce", "made entirely of paper") is decided object by object (:mod:`.decide`).

Measured on the dev split (docs/planner-redesign.md): the 1.5B model fills this schema badly for
requests to bring or use things (it lists objects and destinations), so this planner is not the
default yet.
"""

from __future__ import annotations

import re
import time
from dataclasses import dataclass, field
from typing import Any

from conceptbot.core.scene import Scene
from conceptbot.core.usage import Usage
from conceptbot.models.llm import LLM, ChatRequest
from conceptbot.models.structured import chat_json
from conceptbot.pipeline import prompts

ONE, ALL = "one", "all"
MAX_TASKS = 6


@dataclass(frozen=True)
class Selection:
    """One part of a goal: put ``count`` objects that fit ``what`` at ``to``.

    Attributes:
        what: The description, as the request puts it ("a fruit", "made only of paper").
        count: ``"one"`` (the best fitting object) or ``"all"`` (every object that fits).
        to: A destination of the scene.
        named: Scene objects the description names (resolved by name, not decided by the LLM).
    """

    what: str
    count: str
    to: str
    named: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """JSON form for the trace."""
        return {"what": self.what, "count": self.count, "to": self.to, "named": list(self.named)}


@dataclass(frozen=True)
class Goal:
    """What the request asks for."""

    selections: tuple[Selection, ...]
    stack: bool = False
    refuse: bool = False
    reason: str = ""
    raw: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """JSON form for the trace."""
        return {
            "selections": [s.to_dict() for s in self.selections],
            "stack": self.stack,
            "refuse": self.refuse,
            "reason": self.reason,
        }


def goal_schema(scene: Scene) -> dict[str, Any]:
    """The reply schema, destinations limited to the scene's."""
    return {
        "type": "object",
        "properties": {
            "tasks": {
                "type": "array",
                "maxItems": MAX_TASKS,
                "items": {
                    "type": "object",
                    "properties": {
                        "what": {"type": "string", "maxLength": 80},
                        "how_many": {"type": "string", "enum": [ONE, ALL]},
                        "to": {"type": "string", "enum": list(scene.destinations)},
                    },
                    "required": ["what", "how_many", "to"],
                },
            },
            "stack": {"type": "boolean"},
        },
        "required": ["tasks", "stack"],
    }


def _words(text: str) -> str:
    return " " + " ".join(re.findall(r"[\w'-]+", text.lower())) + " "


def named_objects(what: str, candidates: list[str]) -> tuple[str, ...]:
    """The candidates a description names, longest names first, in the order the description has them.

    A name counts when all its words appear together in the description ("the lime soda" names
    ``lime soda``; "a bag of chips" names ``chips``), or when the description is a part of one
    name only ("chips" names ``multigrain chips`` when nothing else contains it). Each word of the
    description serves one name, so "safety scissors" does not also name ``scissors``.
    """
    text = _words(what)
    found: list[tuple[int, str]] = []
    for name in sorted(candidates, key=lambda n: -len(n)):
        key = _words(name)
        at = text.find(key)
        if key.strip() and at >= 0:
            found.append((at, name))
            text = text[:at] + " " + "#" * (len(key) - 2) + " " + text[at + len(key) :]
    if not found:
        core = _words(re.sub(r"^\s*(the|a|an|some|my|your)\s+", "", what.lower()))
        holders = [n for n in candidates if core.strip() and core in _words(n)]
        if len(holders) == 1:
            return (holders[0],)
    return tuple(name for _, name in sorted(found))


class GoalCompiler:
    """Compile a request into a :class:`Goal` with one constrained JSON call.

    Args:
        llm: The LLM (labelled ``goal``).
    """

    def __init__(self, llm: LLM) -> None:
        self.llm = llm

    def compile(self, request: str, scene: Scene) -> tuple[Goal, Usage]:
        """The goal for ``request`` in ``scene`` and the call's usage."""
        started = time.perf_counter()
        states = "; ".join(f"{n}: {s}" for n, s in scene.entity_states.items())
        user = prompts.render(
            "goal_user",
            destinations=", ".join(scene.destinations),
            states=f"States: {states}.\n" if states else "",
            request=request,
        )
        chat = ChatRequest.of(user, system=prompts.render("goal_system"), max_tokens=220)
        value, response = chat_json(self.llm, chat, goal_schema(scene))
        selections = []
        for task in value["tasks"]:
            what = str(task["what"]).strip()
            if not what:
                continue
            selection = Selection(what, task["how_many"], task["to"], named_objects(what, scene.pickable))
            if selection not in selections:
                selections.append(selection)
        goal = Goal(tuple(selections), stack=bool(value["stack"]), raw=value)
        return goal, response.usage.with_latency(time.perf_counter() - started)
