"""The goal planner's targets (:class:`Target`, :class:`TargetsRead`) and the scored questions that
choose a place the request leaves open (:class:`TargetFinder`), never free generation (a small model
writing the goal lists the scene instead of the request).
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from typing import Protocol

from conceptbot.core.usage import Usage
from conceptbot.models.llm import LLM, Message, ScoreRequest
from conceptbot.pipeline import prompts

ALL = 0  # count meaning "every object that fits"
CONTENT_FREE_REQUEST = "Do the task."
CONTENT_FREE_DISH = "the food"  # the dish a preparation question is calibrated against


@cache
def words() -> dict:
    """The vocabulary of ``request_words.json``."""
    text = resources.files("conceptbot.pipeline").joinpath("request_words.json").read_text(encoding="utf-8")
    return json.loads(text)


def tokens(text: str) -> list[str]:
    """Lower-case word tokens, and the punctuation that ends a clause as tokens of its own."""
    return re.findall(r"[a-z0-9][a-z0-9'&-]*|[,;:.!?]", text.lower())


def _find(seq: list[str], key: list[str], used: list[bool]) -> int:
    for start in range(len(seq) - len(key) + 1):
        if key and seq[start : start + len(key)] == key and not any(used[start : start + len(key)]):
            return start
    return -1


def mentions(text: str, names: Sequence[str]) -> list[tuple[int, str]]:
    """``(token position, name)`` for each name the text mentions, in text order (whole words, longest
    first, each word once; a plural head noun counts)."""
    seq = tokens(text)
    used = [False] * len(seq)
    found: dict[str, int] = {}
    for name in sorted(names, key=lambda n: -len(tokens(n))):
        key = tokens(name)
        at = _find(seq, key, used)
        if at >= 0:
            used[at : at + len(key)] = [True] * len(key)
            found[name] = at
    plurals: dict[str, list[str]] = {}
    for name in names:
        key = tokens(name)
        if name not in found and len(key) >= 2:
            plural = key[-1] + ("es" if key[-1].endswith(("s", "x", "ch", "sh")) else "s")
            if plural in seq:
                plurals.setdefault(plural, []).append(name)
    for plural, group in plurals.items():
        # "the wood and metal bins": the bins whose other words the text has; "the bins": all.
        described = [n for n in group if set(tokens(n)[:-1]) <= set(seq)]
        for name in described or group:
            found[name] = seq.index(plural)
    return sorted((at, name) for name, at in found.items())


class FoodKnowledge(Protocol):
    """What the planner asks the graph about food (implemented by ``FactFinder``)."""

    def prep_places(self, destinations: Sequence[str]) -> list[str]:
        """The destinations food can be prepared in or on."""
        ...


@dataclass
class Target:
    """A destination the request sends things to.

    Attributes:
        name: The destination.
        count: How many objects (``ALL``: every one that fits).
        how: ``named``, ``speaker`` or ``scored``.
        named: Objects the request names for it.
        score: The calibrated log-odds when scored.
        criterion: What decides which objects go there, in the request's words ("poisonous"), or "".
        dish: The dish to be made, as the graph's concept (its facts are read for it), or "".
        ingredients: The objects that go are the ingredients of food to prepare.
        rest: It takes whatever no other target takes ("the rest").
        part: What this one is for where the request asks for several kinds ("as something to eat").
        dish_said: The dish in the request's own words, which the model is asked about; "": ``dish``.
        need: This one's own words where the request states several needs, else "".
        helps: It takes what helps with a need the request states.
    """

    name: str
    count: int
    how: str
    named: list[str] = field(default_factory=list)
    score: float = 0.0
    criterion: str = ""
    dish: str = ""
    ingredients: bool = False
    rest: bool = False
    part: str = ""
    dish_said: str = ""
    need: str = ""
    helps: bool = False

    def to_dict(self) -> dict:
        """JSON form for the trace."""
        return {
            "to": self.name,
            "count": "all" if self.count == ALL else self.count,
            "how": self.how,
            "named": list(self.named),
            "score": round(self.score, 3),
            "criterion": self.criterion,
            "dish": self.dish,
            "ingredients": self.ingredients,
            "rest": self.rest,
            **({"part": self.part} if self.part else {}),
        }


@dataclass(frozen=True)
class ReadingDoubt:
    """Where the request reads two ways: both readings in words, their odds, and the other's targets
    (made only when asked for: scoring an open place costs a call).

    Attributes:
        taken: The reading the targets are, in words.
        other: The reading not taken, in words.
        p_taken: P(the reading taken is the one meant).
        p_other: P(the reading not taken is).
        step: The step of the choice (:data:`conceptbot.pipeline.goal.aided.STEPS`).
        alternative: Reads the request as the other reading.
        preference: The model's log-odds for the reading taken over the other; None if not asked.
    """

    taken: str
    other: str
    p_taken: float
    p_other: float
    step: str
    alternative: Callable[[], TargetsRead]
    preference: float | None = None


@dataclass(frozen=True)
class TargetsRead:
    """A request's goal as the goal planner takes it (what a ``TargetReader`` returns).

    Attributes:
        stack: The request asks for a pile (no targets then).
        targets: Where things go, in the request's order.
        usage: The model calls made to read it.
        plain: The model's plain form of the request, where it was said plainly (else "").
        reading: Which reading the targets are: ``words``, ``plain``, ``both``, or "" (words only).
        other: The reading not taken where the two differ, as goal-set JSON (else None).
        doubt: Where the two differ, what the planner needs to ask which was meant (else None).
    """

    stack: bool
    targets: list[Target]
    usage: Usage
    plain: str = ""
    reading: str = ""
    other: dict | None = None
    doubt: ReadingDoubt | None = None


class TargetFinder:
    """The scored questions that choose a destination the request leaves open (see the module).

    Args:
        llm: An LLM that can score options (labelled ``goal``).
        is_person: Whether a destination is a person.
        threshold: A scored destination other than the best is a target above this.
        food: Which destinations food is made in (``FactFinder``); None: every destination.
    """

    def __init__(
        self,
        llm: LLM,
        is_person: Callable[[str], bool],
        threshold: float = 1.0,
        food: FoodKnowledge | None = None,
    ) -> None:
        self.llm = llm
        self.is_person = is_person
        self.threshold = threshold
        self.food = food

    def log_odds(self, request: str, dest: str) -> tuple[float, Usage]:
        """The log-odds of Yes to "should the robot put things in the X?" for ``request``."""
        action = f"give things to the {dest}" if self.is_person(dest) else f"put things in or on the {dest}"
        return self._yes_no(prompts.render("target_user", request=request, action=action))

    def prep_log_odds(self, dish: str, place: str) -> tuple[float, Usage]:
        """The log-odds of Yes to "to make the <dish>, should the robot put the ingredients in the X?"."""
        return self._yes_no(prompts.render("prep_user", dish=dish, place=place))

    def _yes_no(self, question: str) -> tuple[float, Usage]:
        """The log-odds of Yes against No for one question, scored in one pass."""
        messages = (Message("system", prompts.render("decide_system")), Message("user", question))
        scored = self.llm.score(ScoreRequest(options=("Yes", "No"), messages=messages))
        yes, no = scored.logprobs
        return yes - no, scored.usage
