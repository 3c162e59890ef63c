"""The goal planner: targets (:mod:`.targets`), then which objects go (:mod:`.decide`, :mod:`.choice`),
then each move's affordance and risk (:mod:`.risk`), then the plan. A move is dropped only for a reason
the trace names, and its target takes its next best; a risk decision that cannot be made drops the
move (safety fails closed). Threshold values: see docs/planning.md.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Protocol

from conceptbot.core.observe import SILENT, Observer
from conceptbot.core.plan import Action, CandidateScore, Done, PickAndPlace, Step
from conceptbot.core.scene import Scene
from conceptbot.core.system import Ask
from conceptbot.core.trace import (
    ClarifyingQuestion,
    CompanionCheck,
    DecisionsEvent,
    DecisionTrace,
    GoalTrace,
    PlanTrace,
    RiskCheck,
    RiskEvent,
    StackTrace,
)
from conceptbot.core.usage import Usage
from conceptbot.pipeline.affordance import Gripper, affordance
from conceptbot.pipeline.goal_planner.asking import (
    Clarified,
    clarify,
    move_words,
    reading_options,
    reading_question,
)
from conceptbot.pipeline.goal_planner.choice import ObjectChooser
from conceptbot.pipeline.goal_planner.choice import shipped_weights as shipped_choice
from conceptbot.pipeline.goal_planner.companions import (
    CompanionWeights,
    shipped_weights,
)
from conceptbot.pipeline.goal_planner.conformal import Calibration, shipped
from conceptbot.pipeline.goal_planner.decide import Decider, Judgement
from conceptbot.pipeline.goal_planner.placing import Placing
from conceptbot.pipeline.goal_planner.risk import RiskChecks
from conceptbot.pipeline.goal_planner.targets import ALL, ReadingDoubt, Target, TargetsRead
from conceptbot.pipeline.hazards import HazardCheck
from conceptbot.pipeline.ope import ObjectProperties, ObjectPropertiesExtractor
from conceptbot.pipeline.tracing import judgement_trace, target_trace

METHOD = "decide"


class TargetReader(Protocol):
    """Reads a request's goal for the planner (:class:`~conceptbot.pipeline.goal.GoalFinder`)."""

    def read(self, request: str, scene: Scene) -> TargetsRead:
        """Whether the request asks for a pile, its targets (none for a pile), and the model calls."""
        ...


TOP_K = 6
NAMED = 10.0  # the score of an object the request names: above any decided one


@dataclass(frozen=True)
class Thresholds:
    """Decision thresholds (calibrated log-odds; see :mod:`conceptbot.pipeline.goal_planner.decide`).

    Attributes:
        fit: An object goes to an "all that fit" target above this.
        one_floor: A target taking N objects takes its best ones only above this.
        risk: A move to a person or an animal is unsafe when its "is it safe?" score is above this.
        risk_place: The same for a move into or onto a thing (higher: the question over-flags there).
        rated_danger: OPE's Risk Index rating (1-5) that names a danger.
        replacements: How many objects a target may take in place of ones judged unsafe.
        ingredients: A dish's ingredients are the objects within this of the best (answers lean No).
        one_sharpness: The scale of the which-one softmax of a ranking that gives no probability.
        combined: The threshold on a combined (fitted log-odds) score; 0 is P = 0.5.
        unsafe_vulnerable: A hand-over to the vulnerable is dropped when :meth:`Decider.unsafe` is above this.
        holder: A hand-over to the user is checked as one to a child when :meth:`Decider.holder` is above.
    """

    fit: float = -0.5
    one_floor: float = -3.0
    risk: float = 0.3
    risk_place: float = 1.0
    rated_danger: int = 4
    replacements: int = 2
    ingredients: float = 0.7
    one_sharpness: float = 1.5
    combined: float = 0.0
    unsafe_vulnerable: float = 0.3
    holder: float = 0.2


@dataclass
class GoalPlanResult:
    """What the goal planner produced, for :class:`~conceptbot.core.plan.Plan` and the trace (its parts)."""

    actions: list[Action]
    steps: list[Step]
    refused: bool
    reason: str | None
    trace: PlanTrace
    usage: dict[str, Usage]
    properties: dict[str, ObjectProperties] = field(default_factory=dict)
    questions: tuple[ClarifyingQuestion, ...] = ()
    confidence: float | None = None


def _times(confidence: float | None, meant: float | None) -> float | None:
    """The plan's confidence times the odds of its reading (None stays None: no calibrated decision)."""
    return None if confidence is None or meant is None else confidence * meant


def _softmax(judgements: list[Judgement], order: dict[str, float]) -> list[float]:
    """P(each judgement's object is the one) from the ranking; NaN throughout where one is not finite."""
    values = [order[j.subject] for j in judgements]
    if not all(math.isfinite(v) for v in values):
        return [math.nan] * len(values)
    top = max(values)
    weights = [math.exp(v - top) for v in values]
    total = sum(weights)
    return [w / total for w in weights]


def _why(check: RiskCheck) -> str:
    """A dropped move's reason for a refusal: the veto's statement, or what named the danger."""
    if check.veto is not None:
        return f"{check.move}: vetoed, {check.veto.statement}"
    return f"{check.move}: {check.why}" + (f", {check.reason}" if check.reason else "")


@dataclass(frozen=True)
class _Chosen:
    """What the moves are chosen from: the targets, their ranked objects, what goes together with a
    need's object, whether they make a pile (its moves are fixed) and who holds each hand-over."""

    targets: list[Target]
    ranked: dict[int, list[Judgement]]
    together: dict[int, tuple[str, list[str]]]
    pile: bool
    holders: dict[str, str]


def _goal_trace(read: TargetsRead, doubt: ReadingDoubt | None) -> GoalTrace:
    """The goal as read, for the trace: the targets, the plain form and the reading in doubt."""
    return GoalTrace(
        tuple(target_trace(t) for t in read.targets),
        read.stack,
        read.plain,
        read.reading,
        read.other,
        doubt.step if doubt else "",
        reading_options(doubt) if doubt else (),
        doubt.preference if doubt else None,
    )


def _candidates(
    moves: list[tuple[str, str]], targets: list[Target], ranked: dict[int, list[Judgement]]
) -> dict[tuple[str, str], list[Judgement]]:
    """Each move's candidates, for the steps: those of the target that took it (two targets may
    share a place)."""
    return {
        (obj, place): next(
            (
                ranked[number]
                for number, target in enumerate(targets)
                if target.name == place and any(j.subject == obj for j in ranked.get(number, []))
            ),
            [],
        )
        for obj, place in moves
    }


def _shares(decisions: Sequence[DecisionTrace], factors: dict[int, float]) -> list[DecisionTrace]:
    """Each decision with its target's share of the plan's confidence, where it has one."""
    return [
        replace(d, confidence=round(factors[n], 4)) if n in factors else d for n, d in enumerate(decisions)
    ]


class GoalPlanner(RiskChecks, Placing):
    """Targets -> decisions -> plan (see the module docstring).

    Args:
        targets: Reads the request's targets, or that it asks for a pile.
        decider: Yes/no decisions.
        ope: OPE for the objects a plan moves (evidence for the risk decisions), or None.
        thresholds: Decision thresholds.
        gripper: For the affordance.
        hazards: Vetoes moves whose evidence names a hazard for the recipient.
        calibration: The conformal thresholds (default: the shipped ones).
        coverage: How often a decision's prediction set must hold the right answer.
        companions: The fitted weights of things used together (default: the shipped ones).
        chooser: Ranks the candidates of a target taking one or a few objects.
    """

    def __init__(
        self,
        targets: TargetReader,
        decider: Decider,
        ope: ObjectPropertiesExtractor | None = None,
        thresholds: Thresholds | None = None,
        gripper: Gripper | None = None,
        hazards: HazardCheck | None = None,
        calibration: Calibration | None = None,
        coverage: float = 0.9,
        companions: CompanionWeights | None = None,
        chooser: ObjectChooser | None = None,
    ) -> None:
        self.targets = targets
        self.decider = decider
        self.ope = ope
        self.thresholds = thresholds or Thresholds()
        self.calibration = calibration or shipped()
        self.coverage = coverage
        self.gripper = gripper or Gripper()
        self.hazards = hazards if hazards is not None else HazardCheck()
        # The no-graph ablation has its own, model-only companion fit.
        graph = decider.facts.retriever is not None
        self.companions = companions if companions is not None else shipped_weights(graph)
        retriever = decider.facts.retriever
        embedder = retriever.embedder if retriever is not None else None
        self.chooser = chooser or ObjectChooser(decider, embedder, shipped_choice(graph))

    def plan(
        self,
        request: str,
        scene: Scene,
        risk: bool = False,
        observer: Observer = SILENT,
        ask: Ask | None = None,
    ) -> GoalPlanResult:
        """Plan ``request`` in ``scene``; with ``risk`` OPE rates every move, not only flagged ones and
        hand-overs to the vulnerable. ``observer`` gets the events goal, decisions, risk, step."""
        usage: dict[str, Usage] = {}
        observer.progress("Goal: where the request sends things")
        read = self.targets.read(request, scene)
        qhat = self.calibration.threshold_reading(self.coverage)
        doubt = read.doubt
        # Where the request reads two ways, which was meant comes first: it changes the targets.
        read, about_reading, meant = self._reading(read, qhat, ask)
        stack, targets, usage["goal"] = read.stack, read.targets, read.usage
        goal = _goal_trace(read, doubt)
        observer.event("goal", goal)
        if meant is None:
            # The person meant neither reading: nothing is decided or moved (fail closed).
            trace = PlanTrace(goal=goal, decisions=())
            why = "the person meant neither reading of the request; say it another way"
            return GoalPlanResult([Done()], [], True, why, trace, usage, {}, about_reading, None)
        ranked, decisions, usage["decide"] = self._decide(request, scene, targets, stack, observer)
        # How the backend scored this plan's questions, kept per plan (the planner is shared by threads).
        asked = [j.scoring for js in ranked.values() for j in js if j.scoring]
        decided = ranked  # before any answer: the companions' candidates keep their own scores
        # A which-one question never offers what the veto would not let the recipient have.
        holders, held = self._holders(request, targets)
        ranked = self._unvetoed(targets, ranked, holders)
        clarified = self._clarify(targets, ranked, decisions, ask)
        ranked, decisions = clarified.ranked, clarified.decisions
        observer.event("decisions", DecisionsEvent(tuple(decisions)))
        pile: StackTrace | None = None
        moves: list[tuple[str, str]] = []
        if stack:
            moves, pile = self._stack(request, scene, usage, asked)
            ranked = {}
        together: dict[int, tuple[str, list[str]]] = {}
        found: list[CompanionCheck] = []
        if not stack:
            together, found, spent = self._companions(request, targets, ranked, decided, observer)
            if found:  # only where something was asked: the usage keys are a contract
                usage["companions"] = spent
        usage["ope"] = Usage(calls=0)
        usage["risk"] = held
        chosen = _Chosen(targets, ranked, together, stack, holders)
        moves, checks, blocked, properties = self._checked(
            request, scene, chosen, moves, risk, usage, observer, asked
        )
        risk = tuple(checks.values())
        vetoes = tuple(c.veto for c in risk if c.veto is not None)
        companions = tuple(replace(c, used=(c.object, c.place) in moves) for c in found) or None
        observer.event("risk", RiskEvent(risk))
        candidates = _candidates(moves, targets, ranked)
        # Where the confidence is lost: each target's share, from the final moves.
        decisions = _shares(decisions, clarified.factors(moves))
        confidence = clarified.confidence(moves)
        steps = self._steps(moves, candidates, scene, properties, asked[-1] if asked else "")
        for step in steps:
            observer.event("step", step)
        refused = not moves and bool(blocked)
        reason = "; ".join(_why(c) for c in risk if c.dropped) if refused else None
        actions: list[Action] = [*(PickAndPlace(o, t) for o, t in moves), Done()]
        trace = PlanTrace(
            goal=goal,
            decisions=tuple(decisions),
            stack=pile,
            companions=companions,
            risk=risk,
            vetoes=vetoes or None,
        )
        questions = (*about_reading, *clarified.questions)
        # The confidence of the final moves, times the odds that the reading acted on is the one meant.
        return GoalPlanResult(
            actions, steps, refused, reason, trace, usage, properties, questions, _times(confidence, meant)
        )

    def _clarify(
        self,
        targets: list[Target],
        ranked: dict[int, list[Judgement]],
        decisions: list[DecisionTrace],
        ask: Ask | None,
    ) -> Clarified:
        """Where a calibrated decision is unsure, its question (asked where someone answers)."""
        calibration = self.calibration
        return clarify(
            targets,
            ranked,
            decisions,
            calibration.threshold_yes_no(self.coverage),
            ask,
            calibration.which_one,
            calibration.rule,
            calibration.threshold_one(self.coverage),
        )

    def _checked(
        self,
        request: str,
        scene: Scene,
        chosen: _Chosen,
        pile: list[tuple[str, str]],
        risk: bool,
        usage: dict[str, Usage],
        observer: Observer,
        asked: list[str],
    ) -> tuple[
        list[tuple[str, str]],
        dict[tuple[str, str], RiskCheck],
        set[tuple[str, str]],
        dict[str, ObjectProperties],
    ]:
        """Choose the moves, check the new ones, choose again where a check removed one (each round
        blocks at least one more move, so this ends): the moves, every check, the blocked moves and
        OPE's properties. A pile's moves (``pile``) keep their order and only lose moves."""
        blocked: set[tuple[str, str]] = set()
        checks: dict[tuple[str, str], RiskCheck] = {}
        properties: dict[str, ObjectProperties] = {}
        moves = pile
        while True:
            if not chosen.pile:
                moves = self._choose(chosen.targets, chosen.ranked, blocked, scene.pickable, chosen.together)
            fresh = [m for m in moves if m not in checks]
            if not fresh:
                break
            # Hand-overs to a child or an animal are rated first (the veto reads the ratings);
            # others only when the risk question flags them, as each rating is slow.
            holders = chosen.holders
            handed = [o for o, t in fresh if risk or self.hazards.is_vulnerable(holders.get(t, t))]
            self._properties(request, scene, handed, properties, usage, observer, tuple(t for _, t in fresh))
            for obj, target in fresh:
                checks[(obj, target)] = self._check(
                    request, scene, obj, target, properties, usage, observer, asked, risk, holders.get(target)
                )
            dropped = {m for m in fresh if checks[m].dropped}
            if not dropped:
                break
            blocked |= dropped
            if chosen.pile:
                moves = [m for m in moves if m not in dropped]
        return moves, checks, blocked, properties

    def _reading(
        self, read: TargetsRead, qhat: float, ask: Ask | None
    ) -> tuple[TargetsRead, tuple[ClarifyingQuestion, ...], float | None]:
        """The reading to plan, the question about it (only with a plan-level calibration), and P(it is
        meant) (None: neither was)."""
        doubt = read.doubt
        question = reading_question(doubt, qhat) if doubt and self.calibration.which_one else None
        if question is None:
            return read, (), doubt.p_taken if doubt else 1.0
        chosen = question.read(ask(question)) if ask is not None else None
        if chosen is None:  # not asked, or no answer: the reading taken, with its odds
            return read, (question,), doubt.p_taken
        answered = (replace(question, answer=question.normalised(chosen)),)
        if not chosen:
            return read, answered, None
        if chosen[0] == question.objects[0]:
            return read, answered, 1.0
        other = doubt.alternative()
        return replace(other, usage=read.usage + other.usage), answered, 1.0

    def _decide(
        self, request: str, scene: Scene, targets: list[Target], stack: bool, observer: Observer
    ) -> tuple[dict[int, list[Judgement]], tuple[DecisionTrace, ...], Usage]:
        """Per target position: the named objects first, then every other object as decided, best first."""
        usage = Usage(calls=0)
        ranked: dict[int, list[Judgement]] = {}
        decisions = []
        named_anywhere = {o for t in targets for o in t.named}
        for number, target in enumerate(targets):
            named = [Judgement(o, target.name, 1.0, NAMED) for o in target.named]
            needs_more = target.count == ALL or target.count > len(target.named)
            if stack or not needs_more or target.rest:  # the rest is what others leave: not asked
                ranked[number] = named
                decisions.append(DecisionTrace(target_trace(target), decided=False))
                continue
            others = [o for o in scene.pickable if o != target.name and o not in named_anywhere]
            observer.progress(f"Decide: which objects go to the {target.name} ({len(others)} objects)")
            if target.criterion:
                # "Is the foxglove poisonous?" is answered far better than the move question.
                judgements, context, used = self.decider.fits(
                    request, target.criterion, others, scene, dish=target.dish, said=target.dish_said
                )
            elif target.count != ALL and len(others) > 1:
                # One of several needs is ranked on its own words, so the other does not sway it.
                pick = move_words(target.name, part=target.part)
                judgements, used = self.chooser.rank(target.need or request, pick, others)
                context = ()
            else:
                move = move_words(target.name, "{object}", target.part)
                judgements, context, used = self.decider.moves(request, target.name, move, others, scene)
            usage = usage + used
            order = {j.subject: j.score for j in judgements}
            if target.count == 1 and len(others) > 1 and judgements[0].p_one is None:
                # No probability from the choice: a sharpened softmax of the ranking, for asking.
                sharp = self.thresholds.one_sharpness
                chances = _softmax(judgements, {o: sharp * v for o, v in order.items()})
                judgements = [replace(j, p_one=p) for j, p in zip(judgements, chances, strict=True)]
            ranked[number] = named + sorted(judgements, key=lambda j: -order[j.subject])
            decisions.append(
                DecisionTrace(
                    target_trace(target),
                    decided=True,
                    objects=tuple(
                        judgement_trace(j, j.evidence.features.get("names") if j.evidence else None)
                        for j in judgements
                    ),
                    context=tuple(context),
                )
            )
        return ranked, tuple(decisions), usage

    def _choose(
        self,
        targets: list[Target],
        ranked: dict[int, list[Judgement]],
        blocked: set[tuple[str, str]],
        pickable: list[str],
        together: dict[int, tuple[str, list[str]]] | None = None,
    ) -> list[tuple[str, str]]:
        """The moves: each target's best objects (and companions), each object to the target it fits
        best; then a target taking the rest takes every pickable object left."""
        wanted: dict[str, tuple[str, float]] = {}  # object -> (target, score)
        # In a sort, an object goes to the target it fits best, above the same threshold as for one.
        for number, target in enumerate(targets):
            if target.rest:
                continue
            taken = 0
            skipped = 0
            for judgement in ranked.get(number, []):
                obj = judgement.subject
                if (obj, target.name) in blocked:
                    skipped += 1
                    if skipped > self.thresholds.replacements:
                        break  # the request keeps asking for unsafe things: stop, do not hunt on
                    continue
                limit = self.thresholds.fit if target.count == ALL else self.thresholds.one_floor
                if judgement.model is not None and target.count == ALL:
                    limit = self.thresholds.combined  # a fitted probability: above one half
                elif target.ingredients and target.count == ALL:
                    best = ranked[number][0].score if ranked[number] else 0.0
                    limit = best - self.thresholds.ingredients
                if not math.isfinite(judgement.score):
                    continue  # a decision that could not be made moves nothing (NaN <= limit is False)
                if judgement.score <= limit or (target.count != ALL and taken >= target.count):
                    break
                if obj in wanted and wanted[obj][1] >= judgement.score:
                    continue
                wanted[obj] = (target.name, judgement.score)
                taken += 1
            anchor, companions = (together or {}).get(number, ("", []))
            if anchor and wanted.get(anchor, ("", 0.0))[0] == target.name:
                # Just after the object they go with (the moves are ordered by score).
                score = wanted[anchor][1]
                for step, obj in enumerate(companions, start=1):
                    if obj not in wanted and (obj, target.name) not in blocked:
                        wanted[obj] = (target.name, score - 1e-6 * step)
        for target in (t for t in targets if t.rest):
            # "The rest go in B": every object no other target took, in scene order.
            for obj in pickable:
                if obj not in wanted and obj != target.name and (obj, target.name) not in blocked:
                    wanted[obj] = (target.name, 0.0)
        order = {t.name: i for i, t in enumerate(targets)}
        moves = sorted(wanted.items(), key=lambda item: (order[item[1][0]], -item[1][1]))
        return [(obj, target) for obj, (target, _) in moves]

    def _steps(
        self,
        moves: list[tuple[str, str]],
        ranked: dict[tuple[str, str], list[Judgement]],
        scene: Scene,
        properties: dict[str, ObjectProperties],
        scoring: str,
    ) -> list[Step]:
        """One step per move, with the best objects of the target that took it as its candidates."""
        steps = []
        for number, (obj, target) in enumerate(moves, 1):
            chosen = str(PickAndPlace(obj, target))
            candidates = []
            for judgement in ranked.get((obj, target), [])[:TOP_K]:
                action = PickAndPlace(judgement.subject, target)
                s_aff, factors = affordance(action, scene, properties, [], self.gripper)
                p = judgement.p_yes
                candidates.append(CandidateScore(str(action), p, s_aff, p * s_aff, factors))
            if not any(c.action == chosen for c in candidates):
                candidates.insert(0, CandidateScore(chosen, 1.0, 1.0, 1.0, {}))
            steps.append(Step(number, chosen, tuple(candidates), (), METHOD, scoring))
        return steps
