"""The goal planner's risk checks of each move (a mixin of
:class:`~conceptbot.pipeline.goal_planner.planner.GoalPlanner`): vetoes from the evidence, OPE's
Risk Index where a move is handed to a child or an animal or the risk question flags it, the plain
safety question for hand-overs to the vulnerable, and failing closed where a decision cannot be
made (see the planner's module docstring, point 4).
"""

from __future__ import annotations

import math
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
    """OPE's finding about an object, as evidence for one move: in the Risk Index mode its danger
    and its interaction score with the move's destination only (the other partners are noise for
    this question)."""
    return props.answer.move_summary(props.name, target)


class RiskChecks:
    """Risk checks of moves; the planner supplies the attributes below."""

    decider: Decider
    ope: ObjectPropertiesExtractor | None
    thresholds: Thresholds
    gripper: Gripper
    hazards: HazardCheck

    def _holders(self, request: str, targets: list[Target]) -> tuple[dict[str, str], Usage]:
        """Who holds what goes to a person that is not a child by name (the user): a child, where
        the request says so ("My four-year-old wants to help: hand him the craft knife"), so that
        the hand-over is checked as one to a child. One question per plan, only where such a
        person is a target; a question that cannot be answered counts as a child (fails closed)."""
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
        """OPE's Risk Index of each of ``objects`` not rated yet, rated with the scene's places and
        people and ``extra`` (the only partners a veto reads: with every object of a 20-object
        room, each rating was a generation of 300 tokens). An object whose rating fails stays
        unrated, and its move is vetoed where it is checked (:meth:`_check`)."""
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
        """The risk decision and the affordance of one move (``rate``: OPE's Risk Index is asked for
        it whatever the risk question says; ``who``: who holds it, where not ``target`` itself
        (:meth:`_holders`), for every check).

        A veto (:mod:`conceptbot.pipeline.hazards`) drops the move before the model is asked; a
        decision the backend cannot make (an error, a non-finite score) drops it too, and so does a
        score that compares with nothing (NaN): the move is kept only when its score is known and at
        or below the threshold."""
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
        try:
            judgement, used = self.decider.dangerous(request, move, obj, scene, ())
        except UNANSWERED as exc:
            return _vetoed(_failed(obj, target, exc.message), move, ope, s_aff)
        usage["risk"] = usage["risk"] + used
        asked.append(judgement.scoring)
        if not (math.isfinite(judgement.score) and math.isfinite(judgement.p_yes)):
            return _vetoed(_failed(obj, target, "the backend gave a non-finite score"), move, ope, s_aff)
        limit = self.thresholds.risk if self.hazards.is_person(who) else self.thresholds.risk_place
        flagged = judgement.score > limit
        reason = None
        if flagged or rate or self.hazards.is_vulnerable(who):
            # A flag from the question alone is no reason to drop a move ("give the crayons to the
            # toddler" was flagged on dev): OPE's Risk Index of the object is asked, and the move is
            # dropped for what it names, which the trace shows.
            self._properties(request, scene, [obj], properties, usage, observer, (target,))
            if self.ope is not None and obj not in properties:
                return _vetoed(_failed(obj, target, "OPE could not rate it"), move, ope, s_aff)
            reason = self._reason(obj, target, properties, flagged, who)
        if reason is None and self.hazards.is_vulnerable(who):
            # Asked without the request, which sways the small model towards what was asked.
            try:
                plain, used = self.decider.unsafe(who, obj)
            except UNANSWERED as exc:
                return _vetoed(_failed(obj, target, exc.message), move, ope, s_aff)
            usage["risk"] = usage["risk"] + used
            asked.append(plain.scoring)
            if not (math.isfinite(plain.score) and math.isfinite(plain.p_yes)):
                return _vetoed(_failed(obj, target, "the backend gave a non-finite score"), move, ope, s_aff)
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
        """Each target's ranking less the candidates of a which-one decision that the veto drops
        for that recipient (by the graph's statements: OPE has rated nothing yet); named objects
        stay, so that their veto is traced where the move is checked."""
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
        """Why a move is dangerous, in OPE's words, or None when nothing names a danger.

        OPE's rating of the object with the destination at ``rated_danger`` or above names a danger
        for any move; the object's own danger rating does for a hand-over to a child or an animal.
        Without OPE (an ablation) a flag from the risk question is the reason: the move cannot be
        cleared, so it is dropped."""
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
