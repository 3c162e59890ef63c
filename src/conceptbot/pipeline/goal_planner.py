"""The default planner: compile the request into a goal, decide each object, assemble the plan.

1. :class:`~conceptbot.pipeline.goal.GoalCompiler` turns the request into selections ("one object
   that fits 'a fruit' to the user", "every object that fits 'poisonous' to the toxic bin"),
   a stacking flag and a refusal.
2. Selections that name scene objects take those objects; the others are decided object by object
   (:class:`~conceptbot.pipeline.decide.Decider`: yes/no by log-probability, the object's graph
   facts in the question, calibrated). "one" takes the best object above ``one_floor``; "all" takes
   every object above ``fit_threshold``. An object claimed by two selections goes to the one it
   fits best.
3. Stacking orders the chosen objects by how good a base each makes (a decision too) and puts each
   on the one below.
4. Constraints: each move's affordance (detection confidence, grasp width) and a risk decision
   ("would it be dangerous to give the scissors to the child?", with OPE's properties and the
   graph's facts as evidence). A move judged dangerous is dropped; a "one" selection then takes its
   next best object. The trace says why.

The paper's step-by-step planner stays available (:mod:`conceptbot.pipeline.planner`, config
``paper``).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from typing import Any

from conceptbot.core.plan import Action, CandidateScore, EventSink, Step
from conceptbot.core.scene import Scene
from conceptbot.core.usage import Usage
from conceptbot.pipeline import modes
from conceptbot.pipeline.affordance import PEOPLE, Gripper, affordance
from conceptbot.pipeline.decide import Decider, Judgement
from conceptbot.pipeline.goal import ONE, Goal, GoalCompiler
from conceptbot.pipeline.ope import ObjectProperties, ObjectPropertiesExtractor, Progress

METHOD = "decide"
TOP_K = 6
NAMED = 10.0  # the score of an object the request names: above any decided one


@dataclass(frozen=True)
class Thresholds:
    """Decision thresholds (calibrated log-odds; see :mod:`conceptbot.pipeline.decide`).

    Attributes:
        fit: An object fits an "all" selection above this.
        one_floor: The best object of a "one" selection is taken only above this.
        risk: A move is dangerous when P(Yes) of the risk question is above this.
    """

    fit: float = 0.0
    one_floor: float = -3.0
    risk: float = 0.5


@dataclass
class GoalPlanResult:
    """What the goal planner produced, for :class:`~conceptbot.core.plan.Plan` and the trace."""

    actions: list[str]
    steps: list[Step]
    refused: bool
    reason: str | None
    trace: dict[str, Any]
    usage: dict[str, Usage]
    properties: dict[str, ObjectProperties] = field(default_factory=dict)


def is_person(name: str) -> bool:
    """Whether a destination is a person (things are handed to it)."""
    return any(word in PEOPLE or word in ("toddler", "dog", "cat", "man", "woman", "girl", "boy")
               for word in name.lower().split())  # fmt: skip


def move_text(obj: str, target: str) -> str:
    """The move in words, for the risk question."""
    if is_person(target):
        return f"give the {obj} to the {target}"
    return f"put the {obj} in or on the {target}"


class GoalPlanner:
    """Goal -> decisions -> plan (see the module docstring).

    Args:
        compiler: Request -> goal.
        decider: Yes/no decisions.
        ope: OPE for the objects a plan moves (evidence for the risk decisions), or None.
        thresholds: Decision thresholds.
        gripper: For the affordance.
    """

    def __init__(
        self,
        compiler: GoalCompiler,
        decider: Decider,
        ope: ObjectPropertiesExtractor | None = None,
        thresholds: Thresholds | None = None,
        gripper: Gripper | None = None,
    ) -> None:
        self.compiler = compiler
        self.decider = decider
        self.ope = ope
        self.thresholds = thresholds or Thresholds()
        self.gripper = gripper or Gripper()

    def plan(
        self,
        request: str,
        scene: Scene,
        risk: bool = False,
        progress: Progress | None = None,
        events: EventSink | None = None,
    ) -> GoalPlanResult:
        """Plan ``request`` in ``scene``."""
        say = progress or (lambda message: None)
        emit = events or (lambda name, data: None)
        usage: dict[str, Usage] = {}
        say("Goal: compiling the request")
        goal, usage["goal"] = self.compiler.compile(request, scene)
        trace: dict[str, Any] = {"goal": goal.to_dict()}
        emit("goal", trace["goal"])
        if goal.refuse:
            reason = goal.reason or "judged unsafe"
            return GoalPlanResult(["done()"], [], True, reason, trace, usage)
        decide_usage = Usage(calls=0)
        ranked: dict[int, list[Judgement]] = {}
        decisions = []
        for index, selection in enumerate(goal.selections):
            candidates = [o for o in scene.pickable if o != selection.to]
            if selection.named:
                ranked[index] = [Judgement(o, selection.what, 1.0, NAMED) for o in selection.named]
                decisions.append({**selection.to_dict(), "decided": False, "objects": []})
                continue
            say(f"Decide: which objects fit {selection.what!r} ({len(candidates)} objects)")
            judgements, context, used = self.decider.fits(
                request, selection.what, selection.count, candidates, scene
            )
            decide_usage = decide_usage + used
            ranked[index] = sorted(judgements, key=lambda j: -j.score)
            decisions.append(
                {
                    **selection.to_dict(),
                    "decided": True,
                    "context": list(context),
                    "objects": [j.to_dict() for j in judgements],
                }
            )
        trace["decisions"] = decisions
        emit("decisions", {"decisions": decisions})
        blocked: set[tuple[str, str]] = set()
        risk_trace: list[dict[str, Any]] = []
        properties: dict[str, ObjectProperties] = {}
        ope_usage = Usage(calls=0)
        risk_usage = Usage(calls=0)
        # Choose, check the moves, and choose again where a check removed one (at most a few rounds:
        # each round blocks at least one more move).
        for _ in range(4):
            chosen = self._choose(goal, ranked, blocked)
            moves = self._order(goal, chosen, scene, request, trace)
            fresh = [m for m in moves if m not in {(r["object"], r["to"]) for r in risk_trace}]
            if not fresh:
                break
            if self.ope is not None:
                wanted = [o for o, _ in fresh if o not in properties]
                if wanted:
                    say(f"OPE: properties of {', '.join(wanted)}")
                    mode, _why = modes.choose_mode(request, scene.names, force_risk=risk)
                    found, _retrievals, used = self.ope.run(wanted, mode, request, scene_objects=scene.names)
                    properties.update(found)
                    ope_usage = ope_usage + used
            new_blocks = 0
            for obj, target in fresh:
                s_aff, factors = affordance(Action(obj, target), scene, properties, [], self.gripper)
                evidence = [properties[obj].summary()] if obj in properties else []
                say(f"Risk: {move_text(obj, target)}?")
                judgement, used = self.decider.dangerous(
                    request, move_text(obj, target), obj, scene, evidence
                )
                risk_usage = risk_usage + used
                dangerous = judgement.p_yes > self.thresholds.risk
                infeasible = factors.get("pick", 1.0) <= 0.0 or factors.get("place", 1.0) <= 0.0
                risk_trace.append(
                    {
                        "object": obj,
                        "to": target,
                        "move": move_text(obj, target),
                        "p_dangerous": round(judgement.p_yes, 4),
                        "evidence": list(judgement.facts),
                        "affordance": round(s_aff, 4),
                        "dropped": dangerous or infeasible,
                        "why": "judged dangerous" if dangerous else "not feasible" if infeasible else "",
                    }
                )
                if dangerous or infeasible:
                    blocked.add((obj, target))
                    new_blocks += 1
            if not new_blocks:
                break
        chosen = self._choose(goal, ranked, blocked)
        moves = self._order(goal, chosen, scene, request, trace)
        trace["risk"] = risk_trace
        emit("risk", {"checks": risk_trace})
        usage["decide"] = decide_usage
        if ope_usage.calls or properties:
            usage["ope"] = ope_usage
        usage["risk"] = risk_usage
        steps = self._steps(moves, goal, ranked, chosen, scene, properties)
        for step in steps:
            emit("step", step.to_dict())
        reason = None
        refused = False
        if not moves and any(r["dropped"] for r in risk_trace):
            refused = True
            reason = "; ".join(f"{r['move']}: {r['why']}" for r in risk_trace if r["dropped"])
        actions = [str(Action(o, t)) for o, t in moves] + ["done()"]
        return GoalPlanResult(actions, steps, refused, reason, trace, usage, properties)

    def _choose(
        self, goal: Goal, ranked: dict[int, list[Judgement]], blocked: set[tuple[str, str]]
    ) -> dict[str, tuple[int, float]]:
        """Object -> (selection index, score): "one" selections first, in order; then "all"."""
        taken: dict[str, tuple[int, float]] = {}
        order = sorted(range(len(goal.selections)), key=lambda i: goal.selections[i].count != ONE)
        for index in order:
            selection = goal.selections[index]
            for judgement in ranked.get(index, []):
                obj = judgement.subject
                if (obj, selection.to) in blocked:
                    continue
                if selection.count == ONE:
                    if judgement.score <= self.thresholds.one_floor:
                        break
                    if obj in taken:
                        continue
                    taken[obj] = (index, judgement.score)
                    break
                if judgement.score <= self.thresholds.fit:
                    break  # ranked: nothing after fits either
                if obj not in taken or (
                    taken[obj][1] < judgement.score and goal.selections[taken[obj][0]].count != ONE
                ):
                    taken[obj] = (index, judgement.score)
        return taken

    def _order(
        self,
        goal: Goal,
        chosen: dict[str, tuple[int, float]],
        scene: Scene,
        request: str,
        trace: dict[str, Any],
    ) -> list[tuple[str, str]]:
        """The moves, in selection order then scene order; a stack bottom-up."""
        if goal.stack:
            return self._stack(list(chosen), scene, request, trace)
        moves = []
        for index, selection in enumerate(goal.selections):
            for obj in scene.pickable:
                if chosen.get(obj, (None,))[0] == index:
                    moves.append((obj, selection.to))
        return moves

    def _stack(
        self, objects: list[str], scene: Scene, request: str, trace: dict[str, Any]
    ) -> list[tuple[str, str]]:
        # Only what can be both moved and stacked on takes part; with fewer than two chosen, the
        # request meant "all of them".
        items = [o for o in objects if scene.get(o) and scene.get(o).destination]  # type: ignore[union-attr]
        if len(items) < 2:
            items = [o for o in scene.pickable if scene.get(o).destination]  # type: ignore[union-attr]
        if len(items) < 2:
            return []
        if "stack" not in trace:
            base = "a sturdy object with a flat top that other things can be stacked on"
            judgements, _, _ = self.decider.fits(request, base, "all", items, scene)

            def volume(name: str) -> float:
                size = scene.get(name).size_m  # type: ignore[union-attr]
                return size[0] * size[1] * size[2] if size else 0.0

            order = sorted(judgements, key=lambda j: (-round(j.score, 1), -volume(j.subject)))
            trace["stack"] = {"base_question": base, "order": [j.to_dict() for j in order]}
        bottom_up = [entry["object"] for entry in trace["stack"]["order"]]
        return [(upper, lower) for lower, upper in itertools.pairwise(bottom_up)]

    def _steps(
        self,
        moves: list[tuple[str, str]],
        goal: Goal,
        ranked: dict[int, list[Judgement]],
        chosen: dict[str, tuple[int, float]],
        scene: Scene,
        properties: dict[str, ObjectProperties],
    ) -> list[Step]:
        """One step per move, its candidates the selection's best objects (for the CLI and the page)."""
        steps = []
        for number, (obj, target) in enumerate(moves, 1):
            index = chosen.get(obj, (None, 0.0))[0]
            pool = ranked.get(index, []) if index is not None else []
            candidates = []
            for judgement in pool[:TOP_K]:
                action = Action(judgement.subject, target)
                s_aff, factors = affordance(action, scene, properties, [], self.gripper)
                p = judgement.p_yes
                candidates.append(CandidateScore(str(action), p, s_aff, p * s_aff, factors))
            if not any(c.action == str(Action(obj, target)) for c in candidates):
                candidates.insert(0, CandidateScore(str(Action(obj, target)), 1.0, 1.0, 1.0, {}))
            steps.append(Step(number, str(Action(obj, target)), tuple(candidates), (), METHOD))
        return steps
