"""The goal planner's targets (:class:`Target`, :class:`TargetsRead`) and the scored questions that
choose a place the request leaves open (:class:`TargetFinder`).

The targets are read by :class:`~conceptbot.pipeline.goal.GoalFinder` from the request's parse.
Where the request names no place, each destination is asked "should the robot put things in the
X?" against a content-free request, never by free generation: a 1.5B model asked to write the goal
as JSON listed the scene's destinations and objects instead of the request's
(docs/notes/2026-11-30-planner-redesign.md). The word-rule reader that came before the parse
(``TargetFinder.find``) was removed on 2026-12-06: it lost to the goal reader on every goal-set
batch (docs/planning.md, "Reading the goal").
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
    """``(token position, name)`` for each name the text mentions, in text order.

    Names match as whole words, longest first, each word used once ("non-toxic container" before
    "toxic container"); a name's plural head noun counts ("bins" for "glass bin").
    """
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
        # "the wood, metal and fabric bins": the bins whose other words the text has; "the bins"
        # alone: all of them.
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
        criterion: What decides which objects go there, in the request's words ("poisonous",
            "made entirely of glass"), when the request sorts by a property; "" otherwise.
        dish: The dish the request asks to be made ("hollandaise"), when the graph says it is one:
            the graph's concept, which its facts and evidence are read for.
        ingredients: The objects that go are the ingredients of food to prepare.
        rest: It takes whatever no other target takes ("the rest", "everything else").
        part: Where the request asks for several things of different kinds ("something to eat and
            something to drink", "I'm chilly and there's nothing to do"), what this one is for, as
            the questions say it ("as something to eat", 'for "I'm chilly"'); "" otherwise.
        dish_said: The dish in the request's own words ("tomato and cucumber salad", where the
            graph's concept is "salad"), which the model is asked about; "": as ``dish``.
        need: Where the request states two or more needs ("I'm chilly and there's nothing to
            do"), this one's own words ("I'm chilly"): its objects are decided as if it were the
            whole request; "" otherwise.
        helps: It takes what helps with a need the request states ("I can't make out this tiny
            print"): each object is asked "would the X help with what the person said?", and
            ranked with what the graph states it is for.
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
    """Where the request reads two ways: both readings in words, how likely each is the one meant,
    and the other reading's targets, made when asked for (scoring an open place is a model call).

    Attributes:
        taken: The reading the targets are, in words.
        other: The reading not taken, in words.
        p_taken: P(the reading taken is the one meant), from the step of the choice that kept it
            (and the model's preference, where it was asked).
        p_other: P(the reading not taken is).
        step: The step of the choice (:data:`conceptbot.pipeline.goal.aided.STEPS`).
        alternative: Reads the request as the other reading.
        preference: The model's log-odds for the reading taken over the other, which moved the
            step's odds (:mod:`conceptbot.pipeline.goal.judge`); None where it was not asked.
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
        reading: Which reading the targets are: ``words`` (the rules on the request's words),
            ``plain`` (on the plain form), ``both`` (the two agree), or "" (only the words read).
        other: The reading not taken where the two differ, as goal-set JSON (else None).
        doubt: Where the two differ: what the planner needs to ask which was meant (else None).
    """

    stack: bool
    targets: list[Target]
    usage: Usage
    plain: str = ""
    reading: str = ""
    other: dict | None = None
    doubt: ReadingDoubt | None = None


class TargetFinder:
    """The scored questions that choose a destination the request leaves open (used by
    :class:`~conceptbot.pipeline.goal.adapter.ScoredChooser`; see the module docstring).

    Args:
        llm: An LLM that can score options (labelled ``goal``).
        is_person: Whether a destination is a person.
        threshold: A scored destination other than the best is a target above this.
        food: What the graph knows about food (:class:`conceptbot.pipeline.goal_planner.decide.FactFinder`):
            which destinations food is made in; None: every destination is a candidate for it.
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
        """The log-odds of Yes to "to make the hollandaise, should the robot put the ingredients in
        or on the ceramic bowl?" (asked about the dish, not the request: for the request, the plate
        beat the bowl for a sauce)."""
        return self._yes_no(prompts.render("prep_user", dish=dish, place=place))

    def _yes_no(self, question: str) -> tuple[float, Usage]:
        """The log-odds of Yes against No for one question, scored in one pass."""
        messages = (Message("system", prompts.render("decide_system")), Message("user", question))
        scored = self.llm.score(ScoreRequest(options=("Yes", "No"), messages=messages))
        yes, no = scored.logprobs
        return yes - no, scored.usage
