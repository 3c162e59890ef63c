"""The goal planner's risk checks of each move (a mixin of ``GoalPlanner``): vetoes, OPE's Risk
Index, the plain safety question for hand-overs to the vulnerable, and failing closed.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING

from conceptbot.core.errors import (
    BackendRequestError,
    BackendUnavailableError,
    ModelOutputError,
    NotSupportedError,
)
from conceptbot.core.observe import Observer
from conceptbot.core.plan import PickAndPlace, format_action
from conceptbot.core.scene import Scene
from conceptbot.core.trace import (
    RiskCheck,
    Veto,
)
from conceptbot.core.usage import Usage
from conceptbot.pipeline import modes
from conceptbot.pipeline.affordance import Gripper, affordance
from conceptbot.pipeline.goal_planner.asking import (
    move_words,
)
from conceptbot.pipeline.goal_planner.decide import Decider, Judgement
from conceptbot.pipeline.goal_planner.targets import Target
from conceptbot.pipeline.hazards import HazardCheck
from conceptbot.pipeline.ope import ObjectProperties, ObjectPropertiesExtractor
from conceptbot.pipeline.ope_answers import RiskIndex

if TYPE_CHECKING:
    from conceptbot.pipeline.goal_planner.planner import Thresholds

#: A question the backend could not answer: the risk decision it was for fails closed.
UNANSWERED = (ModelOutputError, BackendRequestError, BackendUnavailableError, NotSupportedError)

#: Who holds a hand-over to the user where the request gives it to a child (:meth:`RiskChecks._holders`).
CHILD = "child"


def _failed(obj: str, target: str, message: str) -> Veto:
    """The veto of a move whose risk decision could not be made."""
    statement = f"the risk decision could not be made: {message}"
    return Veto(format_action(PickAndPlace(obj, target)), obj, target, "error", statement)


def _vetoed(veto: Veto, move: str, ope: str | None, s_aff: float) -> RiskCheck:
    """The risk check of a vetoed move (no score: none was needed, or none could be had)."""
    return RiskCheck(veto.object, veto.to, move, None, None, (), ope, round(s_aff, 4), True, "vetoed", veto)


def _plainly(judgement: Judgement, limit: float) -> str:
    """Why the plain safety question drops a move, for the trace."""
    return f"asked plainly, {judgement.subject!r} scores {judgement.score:+.2f} unsafe (over {limit:+.2f})"


def _evidence(props: ObjectProperties, target: str) -> str:
    """OPE's finding about an object as evidence for one move (its danger with that destination only)."""
    return props.answer.move_summary(props.name, target)


def _answer(
    question: Callable[[], tuple[Judgement, Usage]], usage: dict[str, Usage], asked: list[str]
) -> Judgement | str:
    """A risk question's judgement, or why it could not be made (a backend error, a non-finite
    score): the caller then drops the move (safety fails closed)."""
    try:
        judgement, used = question()
    except UNANSWERED as exc:
        return exc.message
    usage["risk"] = usage["risk"] + used
    asked.append(judgement.scoring)
    if not (math.isfinite(judgement.score) and math.isfinite(judgement.p_yes)):
        return "the backend gave a non-finite score"
    return judgement


class RiskChecks:
    """Risk checks of moves; the planner supplies the attributes below."""

    decider: Decider
    ope: ObjectPropertiesExtractor | None
    thresholds: Thresholds
    gripper: Gripper
    hazards: HazardCheck

    def _holders(self, request: str, targets: list[Target]) -> tuple[dict[str, str], Usage]:
        """Who holds what goes to the user: a child where the request says so (or the question fails)."""
        hazards = self.hazards
        people = [t.name for t in targets if hazards.is_person(t.name) and not hazards.is_vulnerable(t.name)]
        if not people:
            return {}, Usage(calls=0)
        try:
            judgement, used = self.decider.holder(request)
        except UNANSWERED:
            return dict.fromkeys(people, CHILD), Usage(calls=0)
        child = not judgement.score <= self.thresholds.holder  # NaN: a child
        return (dict.fromkeys(people, CHILD) if child else {}), used

    def _properties(
        self,
        request: str,
        scene: Scene,
        objects: list[str],
        properties: dict[str, ObjectProperties],
        usage: dict[str, Usage],
        observer: Observer,
        extra: tuple[str, ...] = (),
    ) -> None:
        """OPE's Risk Index of each of ``objects`` not rated yet, with only the partners a veto reads (each
        rating is slow); an object whose rating fails stays unrated, and its move is vetoed."""
        wanted = [o for o in dict.fromkeys(objects) if o not in properties]
        if self.ope is None or not wanted:
            return
        observer.progress(f"OPE: properties of {', '.join(wanted)}")
        partners = list(dict.fromkeys([*scene.destinations, *extra]))
        for obj in wanted:
            try:
                found = self.ope.run([obj], modes.RISK, request, scene_objects=[obj, *partners])
            except UNANSWERED:
                continue
            properties.update(found.properties)
            usage["ope"] = usage["ope"] + found.usage

    def _check(
        self,
        request: str,
        scene: Scene,
        obj: str,
        target: str,
        properties: dict[str, ObjectProperties],
        usage: dict[str, Usage],
        observer: Observer,
        asked: list[str],
        rate: bool = False,
        who: str | None = None,
    ) -> RiskCheck:
        """The risk decision and the affordance of one move (``rate``: always ask OPE; ``who``: holder);
        kept only when its score is known and at or below the threshold (fails closed)."""
        who = who or target
        move = move_words(who, obj)
        s_aff, factors = affordance(PickAndPlace(obj, target), scene, properties, [], self.gripper)
        ope = _evidence(properties[obj], target) if obj in properties else None
        veto = self.hazards.veto(obj, who, properties)
        if veto is not None and who != target:  # the move as planned, the hazard as judged
            veto = replace(veto, move=format_action(PickAndPlace(obj, target)), to=target)
        if veto is not None:
            observer.progress(f"Risk: {move}: vetoed ({veto.statement})")
            return _vetoed(veto, move, ope, s_aff)
        observer.progress(f"Risk: is it safe to {move}?")
        judgement = _answer(lambda: self.decider.dangerous(request, move, obj, scene, ()), usage, asked)
        if isinstance(judgement, str):
            return _vetoed(_failed(obj, target, judgement), move, ope, s_aff)
        limit = self.thresholds.risk if self.hazards.is_person(who) else self.thresholds.risk_place
        flagged = judgement.score > limit
        reason = None
        if flagged or rate or self.hazards.is_vulnerable(who):
            # A flag alone drops nothing (it flags harmless moves): OPE is asked, and names the reason.
            self._properties(request, scene, [obj], properties, usage, observer, (target,))
            if self.ope is not None and obj not in properties:
                return _vetoed(_failed(obj, target, "OPE could not rate it"), move, ope, s_aff)
            reason = self._reason(obj, target, properties, flagged, who)
        if reason is None and self.hazards.is_vulnerable(who):
            # Asked without the request, which sways the small model towards what was asked.
            plain = _answer(lambda: self.decider.unsafe(who, obj), usage, asked)
            if isinstance(plain, str):
                return _vetoed(_failed(obj, target, plain), move, ope, s_aff)
            if plain.score > self.thresholds.unsafe_vulnerable:
                reason = _plainly(plain, self.thresholds.unsafe_vulnerable)
        dangerous = reason is not None
        infeasible = factors.get("pick", 1.0) <= 0.0 or factors.get("place", 1.0) <= 0.0
        return RiskCheck(
            object=obj,
            to=target,
            move=move,
            p_unsafe=round(judgement.p_yes, 4),
            score=round(judgement.score, 3),
            evidence=tuple(judgement.facts),
            ope=ope,
            affordance=round(s_aff, 4),
            dropped=dangerous or infeasible,
            why="judged dangerous" if dangerous else "not feasible" if infeasible else "",
            reason=reason or "",
        )

    def _unvetoed(
        self, targets: list[Target], ranked: dict[int, list[Judgement]], holders: dict[str, str]
    ) -> dict[int, list[Judgement]]:
        """Each target's ranking less the which-one candidates the veto drops (named ones stay, traced)."""
        out = dict(ranked)
        for number, judgements in ranked.items():
            to = holders.get(targets[number].name, targets[number].name)
            if targets[number].count == 1 and self.hazards.is_vulnerable(to):
                out[number] = [
                    j for j in judgements if j.p_one is None or self.hazards.veto(j.subject, to, {}) is None
                ]
        return out

    def _reason(
        self, obj: str, target: str, properties: dict[str, ObjectProperties], flagged: bool, who: str = ""
    ) -> str | None:
        """Why a move is dangerous, in OPE's words (a rating at ``rated_danger`` or above), or None;
        without OPE a flag from the risk question is the reason."""
        found = properties.get(obj)
        if found is None:
            return "the risk question flagged it (no OPE rating to check it)" if flagged else None
        answer = found.answer
        limit = self.thresholds.rated_danger
        with_target = answer.score_with(target) if isinstance(answer, RiskIndex) else None
        if with_target is not None and with_target >= limit:
            return f"OPE rates the {obj} {with_target}/5 dangerous with the {target}"
        rated = answer.rated_danger()
        if self.hazards.is_vulnerable(who or target) and rated >= limit:
            return f"OPE rates the {obj} {rated}/5 dangerous for the {who or target}"
        return None
