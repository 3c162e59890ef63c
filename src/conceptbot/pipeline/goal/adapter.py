"""A goal as the goal planner's targets (:class:`~conceptbot.pipeline.goal_planner.targets.Target`).

An open destination (``to`` None) is settled by a :data:`Chooser`. Where the goal asks for several
kinds of thing, each target carries its ``part`` ("as something to eat") so that its questions are
not asked against the whole request.
"""

from __future__ import annotations

import re
import time
from collections.abc import Callable, Sequence
from dataclasses import replace

from conceptbot.core.scene import Scene
from conceptbot.core.usage import Usage
from conceptbot.pipeline.goal.aided import Policy, Reading, read_twice
from conceptbot.pipeline.goal.doubt import describe
from conceptbot.pipeline.goal.judge import ReadingJudge, reading_odds
from conceptbot.pipeline.goal.reader import GoalReader
from conceptbot.pipeline.goal.restate import Restater
from conceptbot.pipeline.goal.types import ALL as GOAL_ALL
from conceptbot.pipeline.goal.types import Goal, GoalTarget
from conceptbot.pipeline.goal_planner.targets import (
    ALL,
    CONTENT_FREE_DISH,
    CONTENT_FREE_REQUEST,
    ReadingDoubt,
    Target,
    TargetFinder,
    TargetsRead,
)

#: Chooses an open target's destinations: ``(destination, score)`` pairs, best first.
Chooser = Callable[[GoalTarget, Scene], list[tuple[str, float]]]


def _users(scene: Scene) -> list[str]:
    return [d for d in scene.destinations if d.lower() == "user"]


def _criterion(target: GoalTarget, name: str, dish: str) -> str:
    if target.takes == "ingredients":
        return f"an ingredient of {dish or 'the food the person asked for'}"
    if target.takes != "criterion" or target.count != GOAL_ALL:
        return ""
    if not target.criterion:
        return f"belongs in the {name}"
    if target.criterion.startswith("by "):
        return f"belongs in the {name}, {target.criterion}"
    return target.criterion


def to_targets(goal: Goal, scene: Scene, choose: Chooser | None = None, dish_said: str = "") -> list[Target]:
    """The goal planner's targets for ``goal`` (see the module docstring).

    Args:
        goal: The goal read from the request.
        scene: Its scene.
        choose: Chooses open destinations; None: a need goes to the user, any other is an error.
        dish_said: The dish as the request says it, where ``goal.dish`` is the graph's concept.

    Returns:
        The targets, in the goal's order (a chosen target's places best first).

    Raises:
        ValueError: A target has no destination and nothing can choose one (pass ``choose``).
    """
    if goal.stack:
        return []
    dish = goal.dish or ""
    targets = []
    several = sum(_counted(t) for t in goal.targets) >= 2
    for target in goal.targets:
        if target.to is not None and target.to in scene.destinations:
            places, how = [(target.to, 0.0)], "named"
        elif choose is not None:
            places, how = choose(target, scene), "scored"
        elif target.takes == "need" and _users(scene):
            places, how = [(_users(scene)[0], 0.0)], "speaker"
        else:
            raise ValueError(
                f"the goal's {target.takes} target names no destination and nothing chooses one: "
                "pass choose= (for instance ScoredChooser(finder, request))"
            )
        count = 1 if target.takes == "need" else ALL if target.count == GOAL_ALL else int(target.count)
        for name, score in places:
            targets.append(
                Target(
                    name,
                    count,
                    how,
                    list(target.named),
                    score,
                    _criterion(target, name, dish),
                    dish if target.takes == "ingredients" else "",
                    target.takes == "ingredients",
                    target.takes == "remainder",
                    _part(target) if several and _counted(target) else "",
                    dish_said if target.takes == "ingredients" and dish_said != dish else "",
                    target.criterion if several and target.takes == "need" else "",
                    target.takes == "need",
                )
            )
    return targets


def _counted(target: GoalTarget) -> bool:
    """A target taking a number of objects by its words: one of several things asked for."""
    return target.takes == "need" or (target.takes == "criterion" and target.count != GOAL_ALL)


def _part(target: GoalTarget) -> str:
    """What the target is for, as the questions say it (see the module docstring)."""
    if target.takes == "need":
        return f'for "{target.criterion}"' if target.criterion else ""
    return f"as {target.criterion}"


class ScoredChooser:
    """Chooses an open target's destinations with the model: the best and (except for a dish) those
    above the finder's threshold. A need goes to the user; any other to a place, never a person.

    Args:
        finder: Its LLM, ``is_person``, threshold and food knowledge are used.
        request: The request the goal was read from.
        dish: The dish the goal asks to be made ("" for none).

    Attributes:
        usage: The model calls made so far.
    """

    def __init__(self, finder: TargetFinder, request: str, dish: str = "") -> None:
        self.finder = finder
        self.request = request
        self.dish = dish
        self.usage = Usage(calls=0)

    def __call__(self, target: GoalTarget, scene: Scene) -> list[tuple[str, float]]:
        """The destinations of ``target``, best first, with their calibrated scores."""
        if target.takes == "need" and _users(scene):
            return [(_users(scene)[0], 0.0)]
        candidates = list(scene.destinations)
        if target.takes != "need":
            # An open place is a place: whoever the request hands things to, it names.
            candidates = [d for d in candidates if not self.finder.is_person(d)] or candidates
        making = target.takes == "ingredients"
        if making and self.finder.food is not None:
            candidates = self.finder.food.prep_places(candidates) or candidates
        scores = {}
        for dest in candidates:
            if making and self.dish:
                # Where the dish is made: asked about the dish, calibrated against "the food".
                odds, used = self.finder.prep_log_odds(self.dish, dest)
                prior, used_prior = self.finder.prep_log_odds(CONTENT_FREE_DISH, dest)
            else:
                odds, used = self.finder.log_odds(self.request, dest)
                prior, used_prior = self.finder.log_odds(CONTENT_FREE_REQUEST, dest)
            self.usage = self.usage + used + used_prior
            scores[dest] = odds - prior
        ranked = sorted(scores, key=lambda d: -scores[d])
        return [
            (d, scores[d])
            for i, d in enumerate(ranked)
            if i == 0 or (scores[d] > self.finder.threshold and not making)
        ]


class GoalFinder:
    """The goal planner's targets from the goal reader, open places chosen by :class:`ScoredChooser`.

    Args:
        reader: Reads the goal.
        finder: Asks the scored question for open places.
        dish_concept: The graph's concept for the dish as said ("a hollandaise sauce" -> "hollandaise").
        restater: Says the request plainly first and both are read (:mod:`.aided`); None: words alone.
        policy: Which reading wins where the two differ (:data:`~conceptbot.pipeline.goal.aided.POLICIES`).
        judge: Weighs the model's view of which reading was meant with the step's odds; None: odds alone.
    """

    def __init__(
        self,
        reader: GoalReader,
        finder: TargetFinder,
        dish_concept: Callable[[str, Sequence[str]], str | None] | None = None,
        restater: Restater | None = None,
        policy: Policy = "grounded",
        judge: ReadingJudge | None = None,
    ) -> None:
        self.reader = reader
        self.finder = finder
        self.dish_concept = dish_concept
        self.restater = restater
        self.policy = policy
        self.judge = judge

    def read(self, request: str, scene: Scene) -> TargetsRead:
        """Whether the request asks for a pile, its targets, and the model calls made."""
        started = time.perf_counter()
        if self.restater is None:
            own = read_plainly(self.reader, request, scene)
            reading = Reading(own, own)
        else:
            reading = read_twice(
                lambda text, seen: read_plainly(self.reader, text, seen),
                self.restater,
                request,
                scene,
                self.policy,
            )
        read = self._targets(request, scene, reading.goal, reading.usage, started)
        # No plain form: the words alone were read, and the trace says no reading.
        source = reading.source if reading.restated is not None else ""
        other = reading.other
        if other is None:
            return replace(read, plain=reading.plain, reading=source)
        flipped = "words" if reading.source == "plain" else "plain"
        taken_text = describe(reading.goal)
        other_text = describe(other)
        found, judged_by = reading_odds(reading.step, request, taken_text, other_text, self.judge)
        if judged_by is not None:
            read = replace(read, usage=read.usage + judged_by.usage)

        def alternative() -> TargetsRead:
            assert other is not None
            again = self._targets(request, scene, other, Usage(calls=0), time.perf_counter())
            return replace(again, plain=reading.plain, reading=flipped, other=reading.goal.to_dict())

        doubt = ReadingDoubt(
            taken_text,
            other_text,
            found.taken,
            found.other,
            reading.step,
            alternative,
            judged_by.log_odds if judged_by is not None else None,
        )
        return replace(read, plain=reading.plain, reading=source, other=other.to_dict(), doubt=doubt)

    def _targets(self, request: str, scene: Scene, goal: Goal, usage: Usage, started: float) -> TargetsRead:
        """A goal's targets, its dish as the graph's concept and open places chosen by scoring."""
        said = (goal.dish or "").lower()
        if goal.dish:
            found = self.dish_concept
            concept = found(goal.dish, scene.pickable) if found is not None else None
            goal = replace(goal, dish=concept or said)
        chooser = ScoredChooser(self.finder, request, goal.dish or "")
        # The model is asked about the dish as said; the graph's concept is what facts are read for.
        targets = to_targets(goal, scene, choose=chooser, dish_said=said)
        usage = (chooser.usage + usage).with_latency(time.perf_counter() - started)
        return TargetsRead(goal.stack, targets, usage)


def _plain(name: str) -> str:
    """A name as words the parser reads as one noun phrase ("apple [/x]" -> "apple x")."""
    return " ".join(re.findall(r"[A-Za-z0-9][A-Za-z0-9'&-]*", name))


def read_plainly(reader: GoalReader, request: str, scene: Scene) -> Goal:
    """``reader.read``, with scene names carrying marks ("apple [/x]") read as their words (the parser
    would split them); the goal names the scene's own spellings."""
    plain = {o.name: _plain(o.name) for o in scene.objects}
    odd = {n: p for n, p in plain.items() if p and p != n and p not in plain}
    if not odd or len(set(odd.values())) < len(odd):
        return reader.read(request, scene)
    text = request
    for name in sorted(odd, key=len, reverse=True):
        text = re.sub(re.escape(name), odd[name], text, flags=re.IGNORECASE)
    renamed = replace(scene, objects=tuple(replace(o, name=odd.get(o.name, o.name)) for o in scene.objects))
    back = {p: n for n, p in odd.items()}
    goal = reader.read(text, renamed)

    def spelt(name: str | None) -> str | None:
        return back.get(name, name) if name is not None else None

    targets = tuple(
        replace(t, to=spelt(t.to), named=tuple(back.get(n, n) for n in t.named)) for t in goal.targets
    )
    return replace(goal, targets=targets)
