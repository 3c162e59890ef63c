"""The robot's skill layer: a plan's steps grounded in the actions' rules before it runs.

A small planner writes "find Candle, find Shelf, put Shelf, close Shelf": it forgets to pick the
candle and closes a shelf. A robot's own skill layer knows every action's preconditions (the
executor's, :mod:`conceptbot.household.executor`) and repairs such plans the way a controller
would, without knowing the task: each failed step is fixed by the one change its failure calls for,
and the plan is run again, until every step executes.

=====================  ===========================================================================
failure                change
=====================  ===========================================================================
empty hand             pick the object last found that can be picked (for ``pour``, one holding
                       liquid first; for ``put Pillow``, the pillow), right after it was found if
                       the hand stays free until here
hand full              the pick is dropped (the hand keeps what it holds)
not found              find it first
closed                 open the receptacle first
empty container        fill the held container first, with the liquid the instruction names
                       (water if it names none); a held thing that holds no liquid: the
                       ``pour`` is dropped
put on a non-receptacle  put on the receptacle last found instead
unable / unknown       the step is dropped (a shelf cannot be closed; the robot skips it)
=====================  ===========================================================================

Refusals are not touched: grounding only ever applies to a plan the planner chose to carry out.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

from conceptbot.core.plan import LIQUIDS, HouseholdAction, format_action
from conceptbot.core.scene import HouseScene
from conceptbot.core.trace import GroundingChange
from conceptbot.household.executor import (
    CLOSED,
    EMPTY_CONTAINER,
    EMPTY_HAND,
    NOT_FOUND,
    HouseholdExecutor,
    StepResult,
)
from conceptbot.household.thor import catalogue

HAND_VERBS = ("pick", "put", "drop", "throw", "pour")

_Plan = list[HouseholdAction]


def _object(step: HouseholdAction) -> str | None:
    """The canonical object type a step acts on (``None`` for drop, pour or throw)."""
    return catalogue().canonical(step.obj) if step.obj else None


def _found_before(plan: Sequence[HouseholdAction], index: int) -> list[tuple[int, str]]:
    """``(position, object)`` of each ``find`` before ``index``, latest first."""
    found = [(i, _object(s)) for i, s in enumerate(plan[:index]) if s.verb == "find"]
    return [(i, o) for i, o in reversed(found) if o is not None]


def _inserted(plan: _Plan, at: int, step: HouseholdAction) -> tuple[_Plan, str]:
    return [*plan[:at], step, *plan[at:]], f"inserted {format_action(step)}"


def _carry(plan: _Plan, index: int, executor: HouseholdExecutor) -> tuple[_Plan, str] | None:
    """An empty hand at ``plan[index]``: pick the object last found that can be picked."""
    types = catalogue()
    target = _object(plan[index])
    found = _found_before(plan, index)
    if target and types.has(target, "pickupable") and not types.has(target, "receptacle"):
        # "put Pillow": the pillow is what to carry (where to put it is the next round's fix)
        found = [(i, o) for i, o in found if o == target]
    candidates = [
        (i, o)
        for i, o in found
        if (o != target or not types.has(o, "receptacle")) and types.has(o, "pickupable")
    ]
    if plan[index].verb == "pour":  # pour from something that holds liquid, if one was found
        filled = [(i, o) for i, o in candidates if executor.state[o].flags["isFilledWithLiquid"]]
        candidates = filled + [c for c in candidates if c not in filled]
    if not candidates:
        return None
    found_at, obj = candidates[0]
    hand_free = not any(s.verb in HAND_VERBS for s in plan[found_at + 1 : index])
    return _inserted(plan, found_at + 1 if hand_free else index, HouseholdAction("pick", obj))


def _receptacle(plan: _Plan, index: int, executor: HouseholdExecutor) -> tuple[_Plan, str] | None:
    """``put X`` where X is no receptacle (usually the held object): the receptacle last found."""
    types = catalogue()
    for _, obj in _found_before(plan, index):
        if types.has(obj, "receptacle") and obj != executor.held:
            return [*plan[:index], HouseholdAction("put", obj), *plan[index + 1 :]], f"put on {obj} instead"
    return None


def liquid_named(instruction: str) -> str:
    """The first of the actions' liquids the instruction names ("pour coffee ..." -> coffee), else
    water."""
    words = re.findall(r"[a-z]+", instruction.lower())
    return next((w for w in words if w in LIQUIDS), "water")


def _fix(
    plan: _Plan, index: int, result: StepResult, executor: HouseholdExecutor, liquid: str
) -> tuple[_Plan, str]:
    """The plan with the one change that ``result`` (the failure of ``plan[index]``) calls for."""
    verb, obj = plan[index].verb, _object(plan[index])
    fixed: tuple[_Plan, str] | None = None
    if result.failure == EMPTY_CONTAINER and catalogue().has(result.about, "fillable"):
        fixed = _inserted(plan, index, HouseholdAction("fillLiquid", result.about, liquid))
    elif result.failure == EMPTY_HAND:
        fixed = _carry(plan, index, executor)
    elif result.failure == NOT_FOUND and obj:
        fixed = _inserted(plan, index, HouseholdAction("find", obj))
    elif result.failure == CLOSED and result.about:
        fixed = _inserted(plan, index, HouseholdAction("open", result.about))
    elif verb == "put" and obj and not catalogue().has(obj, "receptacle"):
        fixed = _receptacle(plan, index, executor)
    return fixed or ([*plan[:index], *plan[index + 1 :]], "dropped the step")


def _first_failure(
    scene: HouseScene, plan: Sequence[HouseholdAction]
) -> tuple[int, StepResult, HouseholdExecutor] | None:
    executor = HouseholdExecutor(scene)
    for index, step in enumerate(plan):
        result = executor.step(step)  # a failed step leaves the state as it was
        if not result.ok:
            return index, result, executor
    return None


def ground_plan(
    scene: HouseScene, steps: Sequence[HouseholdAction], instruction: str = ""
) -> tuple[list[HouseholdAction], list[GroundingChange]]:
    """The plan with every failed step repaired (see the module docstring), and the repairs made.
    ``instruction`` only says which liquid an empty container is filled with.

    Each round fixes the first failing step and runs the plan again. Every change either drops a
    step or inserts one that removes the failure at hand, so a bounded number of rounds suffices;
    what is still failing after them is dropped.
    """
    plan = list(steps)
    repairs: list[GroundingChange] = []
    for _ in range(3 * len(plan) + 3):
        failing = _first_failure(scene, plan)
        if failing is None:
            return plan, repairs
        index, result, executor = failing
        before = plan[index]
        plan, change = _fix(plan, index, result, executor, liquid_named(instruction))
        repairs.append(GroundingChange(format_action(before), result.message, change))
    while (failing := _first_failure(scene, plan)) is not None:
        index, result, _ = failing
        repairs.append(GroundingChange(format_action(plan[index]), result.message, "dropped the step"))
        plan = [*plan[:index], *plan[index + 1 :]]
    return plan, repairs
