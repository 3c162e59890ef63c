"""A goal as the goal planner's targets (:class:`~conceptbot.pipeline.goal_planner.targets.Target`).

Where the goal names a destination the target is ``how="named"``. Where it leaves the destination
open (``to`` None) a :data:`Chooser` settles it; :class:`ScoredChooser` asks the model the question
``TargetFinder`` asks ("should the robot put things in the X?", against a content-free
request). Without a chooser a need goes to the scene's user (the speaker).

What each kind of target becomes (chosen to keep the planner's behaviour where today's reader was
right):

* ``named``: the named objects, their count.
* ``criterion`` taking all: ``criterion`` is the request's words; a place in a sort without words of
  its own gets "belongs in the <place>" (with the key: "belongs in the glass bin, by material").
  Taking a number ("something to write with"): no criterion, as the word rules before it gave none: the
  planner then asks the move question and ranks names, which it was tuned on.
* ``remainder``: ``rest=True``, every object left.
* ``ingredients``: ``ingredients=True``, ``dish`` and the criterion "an ingredient of <dish>".
* ``need``: one object (the word rules' rule for a need of the speaker's: right on 13 of the 14
  dev needs; "brush my teeth" needs two), decided by the move question and the name ranking. Judged
  instead against "helps when <the need>" with the fitted combination (the judgement set's
  question: 88% per object), the dev needs fell from 10/21 to 8/21 (2026-12-02): a yes/no per
  object ranks the one that helps worse than the name ranking does.
* ``all``: every object. A stacking goal gives no targets: the planner piles the objects itself.

Where the goal asks for two or more things of different kinds, each taking a number ("something to
eat and something to drink") or each a need of its own ("I'm chilly and there's nothing to do"),
each target carries its ``part`` ("as something to eat", 'for "I'm chilly"'): without it the
targets asked the same question against the whole request and took its two best answers, often
two of one kind.
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

#: Chooses the destinations of a target whose goal names none: ``(destination, score)`` pairs, best
#: first (the score is kept in :attr:`Target.score`).
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
        choose: Chooses destinations for targets the goal leaves open, or whose place is not one
            of the scene's destinations (a plain form may name an object as the place); None: a
            need goes to the scene's user, and any other open target is an error.
        dish_said: The dish as the request says it, where ``goal.dish`` is the graph's concept
            for it (``Target.dish_said``).

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
    """Chooses an open target's destinations with the model: each destination scored "should the robot put
    things in the X?" minus the same for a content-free request; the best, and (except for a dish, made
    in one place) those above the finder's threshold. A need goes to the user where the scene has one
    (the speaker); any other open target goes to a place, never to a person or an animal (the goal names
    those it hands to).

    Args:
        finder: Its LLM, ``is_person``, threshold and food knowledge are used.
        request: The request the goal was read from.
        dish: The dish the goal asks to be made ("" for none): where it is made is asked about it.

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
            # A place the request leaves open is a place ("put the pill bottle out of the toddler's
            # reach", "throw away the poisonous ones"): whoever it hands things to, it names.
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
                # TargetFinder's scored question.
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
    """The goal planner's targets from :class:`~conceptbot.pipeline.goal.reader.GoalReader`: the
    request's structure from its parse, and where the words leave a place open, the model's scored
    choice (:class:`ScoredChooser`).

    Args:
        reader: Reads the goal.
        finder: Asks the scored question for open places (its LLM, threshold and food knowledge).
        dish_concept: The graph's concept for the dish the request names in its own words ("a
            hollandaise sauce" -> "hollandaise"), so that its definition can be found; None: the
            words, lower case.
        restater: Says the request plainly first, and the rules read both (:mod:`.aided`, with
            ``policy``); None: the rules read the words alone.
        policy: Which reading wins where the two differ (:data:`~conceptbot.pipeline.goal.aided.POLICIES`).
        judge: Where the two readings differ, the model's view of which was meant weighs with the
            step's odds (:mod:`.judge`, :func:`.doubt.judged`); None: the step's odds alone.
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
        # No plain form (no restater, or the model failed or said nothing): the words alone were
        # read, and the trace says no reading.
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
            # The other reading: its targets, and the reading it was chosen over as its other.
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
        # The model is asked about the dish as it was said ("is the kiwi an ingredient of tomato and
        # cucumber salad?"); the graph's concept ("salad") is what its facts are read for.
        targets = to_targets(goal, scene, choose=chooser, dish_said=said)
        usage = (chooser.usage + usage).with_latency(time.perf_counter() - started)
        return TargetsRead(goal.stack, targets, usage)


def _plain(name: str) -> str:
    """A name as words the parser reads as one noun phrase ("apple [/x]" -> "apple x")."""
    return " ".join(re.findall(r"[A-Za-z0-9][A-Za-z0-9'&-]*", name))


def read_plainly(reader: GoalReader, request: str, scene: Scene) -> Goal:
    """``reader.read``, with scene names that carry brackets, slashes or other marks read as their
    words: the parser splits "apple [/x]" into pieces that no longer make a noun phrase. The goal
    names the scene's own spellings."""
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
