"""Execute a plan in the simulator and check where everything ended up; optionally closed loop.

:func:`execute_plan` runs the ``pick_and_place`` steps of a plan one by one and stops at the first
failure. The final-state check compares, for every object the plan moved, where it is with where the
plan last put it (an earlier placement may be disturbed by a later one).

:func:`run_closed_loop` plans with a planner system, executes, and when a step fails gives the failure
back to the planner (:class:`~conceptbot.core.plan.Feedback`): the steps done so far and the failed
action with its reason; the planner plans the rest from there. At most ``max_replans`` times.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from conceptbot.core.observe import SILENT, Observer
from conceptbot.core.plan import Action, Feedback, PickAndPlace, Plan, format_actions
from conceptbot.core.scene import Scene
from conceptbot.core.system import PlannerSystem
from conceptbot.sim.skills import PickPlaceSkill, SkillResult, same_place
from conceptbot.sim.world import World


@dataclass
class Execution:
    """What happened when a plan ran.

    Attributes:
        results: One per attempted step, in order.
        placements: Object -> destination it is in/on at the end (None: on the table), for every
            object the plan tried to move.
        intended: Object -> where the plan last put it (successful steps only).
        plans: Every plan used (the first, then each replan).
        attempted: The moves tried, in order (one per result).
        ok: Every step succeeded and every moved object is where the plan put it.
        verdict: One line for people.
    """

    results: list[SkillResult] = field(default_factory=list)
    placements: dict[str, str | None] = field(default_factory=dict)
    intended: dict[str, str] = field(default_factory=dict)
    plans: list[tuple[Action, ...]] = field(default_factory=list)
    ok: bool = False
    verdict: str = ""
    attempted: list[PickAndPlace] = field(default_factory=list)

    @property
    def executed(self) -> tuple[PickAndPlace, ...]:
        """The moves that succeeded, in order."""
        return tuple(a for a, r in zip(self.attempted, self.results, strict=True) if r.ok)

    @property
    def seconds_per_action(self) -> list[float]:
        """Wall seconds of each attempted pick-and-place."""
        return [r.seconds for r in self.results]

    def to_dict(self) -> dict[str, Any]:
        """JSON form."""
        return {
            "ok": self.ok,
            "verdict": self.verdict,
            "plans": [format_actions(p) for p in self.plans],
            "steps": [
                {
                    "action": r.action,
                    "ok": r.ok,
                    "failure": r.failure,
                    "message": r.message,
                    "seconds": round(r.seconds, 3),
                    "attempts": int(r.details.get("attempts", 1)),
                }
                for r in self.results
            ],
            "placements": self.placements,
            "intended": self.intended,
        }


def _check(world: World, execution: Execution) -> None:
    """Fill placements, ok and verdict from the world's final state."""
    moved = {a.obj for a in execution.attempted}
    execution.placements = {name: world.locate(name) for name in sorted(moved)}
    failed = [r for r in execution.results if not r.ok]
    wrong = []
    for obj, target in execution.intended.items():
        where = execution.placements.get(obj)
        if world.off_table(obj):
            wrong.append(f"{obj} fell off the table (put in/on {target})")
        elif not same_place(world.holders(obj), target):
            wrong.append(f"{obj} is {'in/on ' + where if where else 'on the table'} (put in/on {target})")
    execution.ok = not failed and not wrong
    if execution.ok:
        n = len(execution.results)
        execution.verdict = (
            f"success: {n} pick-and-place step{'s' if n != 1 else ''}, every object where the plan put it"
        )
    else:
        parts = [f"{r.action} failed ({r.failure}: {r.message})" for r in failed] + wrong
        execution.verdict = "failure: " + "; ".join(parts)


def execute_actions(
    skill: PickPlaceSkill, scene: Scene, actions: Sequence[Action], execution: Execution
) -> SkillResult | None:
    """Run ``actions`` until ``Done`` or the first failure; returns the failed result or None."""
    for action in actions:
        if not isinstance(action, PickAndPlace):
            return None
        result = skill.run(action.obj, action.destination)
        execution.attempted.append(action)
        execution.results.append(result)
        if not result.ok:
            return result
        execution.intended[action.obj] = action.destination
    return None


def execute_plan(
    world: World, scene: Scene, actions: Sequence[Action], skill: PickPlaceSkill | None = None
) -> Execution:
    """Execute a plan's actions open loop (stop at the first failure) and check the final state."""
    skill = skill or PickPlaceSkill(world)
    execution = Execution(plans=[tuple(actions)])
    execute_actions(skill, scene, actions, execution)
    _check(world, execution)
    return execution


def run_closed_loop(
    system: PlannerSystem,
    request: str,
    scene: Scene,
    world: World,
    skill: PickPlaceSkill | None = None,
    max_replans: int = 2,
    risk: bool = False,
    observer: Observer | None = None,
) -> tuple[Execution, list[Plan]]:
    """Plan, execute, and replan after failures (see the module docstring).

    ``observer`` gets every plan's progress messages and events, and a message after each
    execution and before each replan.

    Returns:
        The execution record and every plan made (the first, then the replans).
    """
    skill = skill or PickPlaceSkill(world)
    execution = Execution()
    plans: list[Plan] = []
    feedback = Feedback()
    observer = observer if observer is not None else SILENT
    plan = system.plan(request, scene, risk=risk, observer=observer)
    while True:
        plans.append(plan)
        execution.plans.append(tuple(plan.actions))
        if plan.refused:
            break
        remaining = plan.actions[len(feedback.executed) :]  # a replan starts with the steps already done
        started = time.perf_counter()
        failed = execute_actions(skill, scene, remaining, execution)
        observer.progress(f"Simulator: executed in {time.perf_counter() - started:.1f} s")
        if failed is None or len(plans) > max_replans:
            break
        feedback = Feedback(
            executed=execution.executed,
            failed=(*feedback.failed, (execution.attempted[-1], f"{failed.failure}: {failed.message}")),
        )
        observer.progress(f"Replanning after: {failed.action} failed ({failed.failure})")
        plan = system.plan(request, scene, risk=risk, feedback=feedback, observer=observer)
    _check(world, execution)
    return execution, plans
