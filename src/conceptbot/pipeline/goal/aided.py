"""Reading a request twice: the rules on its own words and on the model's plain form of it.
:func:`choose` picks one; where they disagree :class:`Reading` keeps both, so the planner can ask.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Literal

from conceptbot.core.scene import Scene
from conceptbot.core.usage import Usage
from conceptbot.pipeline.goal.compare import same_goal, structure, words
from conceptbot.pipeline.goal.reader import GoalReader
from conceptbot.pipeline.goal.restate import Restater
from conceptbot.pipeline.goal.types import Goal

Policy = Literal["words", "plain", "grounded"]
#: The steps of the grounded choice, in :func:`choose`'s order ("agree": the two readings are one).
STEPS = ("agree", "wording", "needs", "command", "need", "dropped", "moved", "fewer", "words fewer")
#: The policies :func:`choose` knows, for the benchmark's table.
POLICIES: tuple[Policy, ...] = ("words", "plain", "grounded")
#: Targets whose place may be left open by any reading: the planner chooses it.
OPEN = frozenset({"need", "ingredients"})


@dataclass(frozen=True)
class Reading:
    """A request's goal, read from its words and from the model's plain form.

    Attributes:
        goal: The reading chosen.
        words: The rules' reading of the request's own words.
        plain: The model's plain form ("" when there is none).
        restated: The rules' reading of the plain form, or None.
        source: Which reading ``goal`` is: ``words``, ``plain`` or ``both`` (they agree).
        usage: The model's calls.
        step: Which of :func:`choose`'s steps decided (:data:`STEPS`; "" for one reading or a fixed policy).
    """

    goal: Goal
    words: Goal
    plain: str = ""
    restated: Goal | None = None
    source: Literal["words", "plain", "both"] = "words"
    usage: Usage = field(default_factory=lambda: Usage(calls=0))
    step: str = ""

    @property
    def doubtful(self) -> bool:
        """The two readings differ: which one the person meant is a question."""
        return self.restated is not None and self.source != "both"

    @property
    def other(self) -> Goal | None:
        """The reading not taken where the two differ, else None."""
        if not self.doubtful:
            return None
        return self.words if self.source == "plain" else self.restated


def choose(
    own: Goal,
    restated: Goal | None,
    policy: Policy,
    request: str = "",
    plain: str = "",
    names: Sequence[str] = (),
) -> Reading:
    """The reading ``policy`` picks from the words' (``own``) and the plain form's (``restated``).

    ``words`` and ``plain`` always take that one; ``grounded``: the words where only a criterion's
    wording differs, both are needs, or the plain form drops or moves a target; a command over a need
    unless :func:`ungrounded`; else fewer signs of being made up (with ``names``), the plain on a tie.
    """
    if restated is None:
        return Reading(own, own)
    if same_goal(own, restated).ok:
        return Reading(own, own, restated=restated, source="both", step="agree")
    taken = Reading(restated, own, restated=restated, source="plain")
    kept = Reading(own, own, restated=restated, source="words")
    if policy != "grounded":
        return taken if policy == "plain" else kept
    if same_goal(structure(own), structure(restated)).ok:
        return replace(kept, step="wording")
    mine, theirs = ungrounded(own, request, request, names), ungrounded(restated, request, plain, names)
    own_need, plain_need = _needs(own), _needs(restated)
    if own_need and plain_need:
        return replace(kept, step="needs")
    if own_need or plain_need:
        command_ok = not (theirs if own_need else mine)
        if command_ok:
            return replace(taken if own_need else kept, step="command")
        return replace(kept if own_need else taken, step="need")
    # A sign both readings carry is no reason to doubt the words more than the plain form.
    mine_only = [sign for sign in mine if sign not in theirs]
    if set(restated.targets) < set(own.targets) and not mine_only:
        return replace(kept, step="dropped")
    if _moved_elsewhere(own, restated) and not mine_only:
        return replace(kept, step="moved")
    criteria = {t.to for t in own.targets if t.takes == "criterion" and t.criterion}
    theirs += [
        f"dropped the criterion for {t.to}" for t in restated.targets if t.takes == "all" and t.to in criteria
    ]
    return replace(taken, step="fewer") if len(theirs) <= len(mine) else replace(kept, step="words fewer")


def ungrounded(goal: Goal, request: str, text: str, names: Sequence[str] = ()) -> list[str]:
    """What in ``goal``, read from ``text``, the request does not bear out: a target with no place, words
    the request lacks, a "the" thing the scene lacks (unless two ``names`` match), a criterion twice."""
    said = set(words(request))
    lowered = " ".join(text.lower().split())
    found = [f"no place for {t.criterion or ', '.join(t.named) or t.takes}" for t in goal.targets
             if t.to is None and t.takes not in OPEN]  # fmt: skip
    found += [f"not said: {t.criterion}" for t in goal.targets
              if t.takes != "need" and set(words(t.criterion)) - said]  # fmt: skip
    definite = [t for t in goal.targets if t.takes == "criterion" and t.count == 1]
    kinds = [set(words(n)) for n in names] if definite else []  # the scene read only when needed
    found += [
        f"no {t.criterion} here"
        for t in definite
        if f"the {t.criterion.lower()}" in lowered
        and sum(bool(words(t.criterion)) and set(words(t.criterion)) <= kind for kind in kinds) < 2
    ]
    criteria = [t.criterion for t in goal.targets if t.takes == "criterion" and t.criterion]
    found += [
        f"twice: {c}" for c in sorted(set(criteria)) if criteria.count(c) > 1 and not c.startswith("by ")
    ]
    if goal.dish and set(words(goal.dish)) - said:
        found.append(f"not said: {goal.dish}")
    return found


def _moved_elsewhere(own: Goal, restated: Goal) -> bool:
    """The plain form sends a named object, or the kind asked for (same content words), elsewhere."""
    placed = {n: t.to for t in own.targets if t.to for n in t.named}
    if any(t.to and placed.get(n, t.to) != t.to for t in restated.targets for n in t.named):
        return True
    kinds = [(set(words(t.criterion)), t.to) for t in own.targets if t.to and t.criterion]
    return any(
        t.to and kind and kind == set(words(t.criterion)) and to != t.to
        for t in restated.targets
        if t.criterion
        for kind, to in kinds
    )


def _needs(goal: Goal) -> bool:
    """The goal is needs only."""
    return bool(goal.targets) and all(t.takes == "need" for t in goal.targets)


class AidedReader:
    """Reads a request's goal from its words and from the model's plain form (see the module).

    Args:
        reader: The rules.
        restater: The model's plain form.
        policy: Which reading wins where they differ.
    """

    def __init__(self, reader: GoalReader, restater: Restater, policy: Policy = "grounded") -> None:
        self.reader = reader
        self.restater = restater
        self.policy = policy

    def read(self, request: str, scene: Scene) -> Reading:
        """Both readings of ``request`` and the one chosen."""
        return read_twice(self.reader.read, self.restater, request, scene, self.policy)


def read_twice(
    read: Callable[[str, Scene], Goal],
    restater: Restater,
    request: str,
    scene: Scene,
    policy: Policy,
) -> Reading:
    """``read`` on the request's words and on ``restater``'s plain form, and ``policy``'s choice."""
    own = read(request, scene)
    said = restater.restate(request)
    restated = read(said.text, scene) if said.text else None
    chosen = choose(own, restated, policy, request, said.text, scene.names)
    return replace(chosen, plain=said.text, usage=said.usage)
