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
from dataclasses import dataclass

from conceptbot.household.actions import LIQUIDS, StepError, parse_step
from conceptbot.household.executor import (
    CLOSED,
    EMPTY_CONTAINER,
    EMPTY_HAND,
    NOT_FOUND,
    HouseholdExecutor,
    StepResult,
)
from conceptbot.household.thor import HouseScene, catalogue

HAND_VERBS = ("pick", "put", "drop", "throw", "pour")


@dataclass(frozen=True)
class Repair:
    """One change the skill layer made.

    Attributes:
        step: The step that failed.
        failure: Why (the executor's message).
        change: What was done ("inserted pick Candle", "dropped the step", ...).
    """

    step: str
    failure: str
    change: str

    def to_dict(self) -> dict[str, str]:
        """JSON form for the trace."""
        return {"step": self.step, "failure": self.failure, "change": self.change}


def _object(text: str) -> str | None:
    """The canonical object type a step acts on (``None`` for drop, pour, throw or bad syntax)."""
    try:
        step = parse_step(text)
    except StepError:
        return None
    return catalogue().canonical(step.obj) if step.obj else None


def _verb(text: str) -> str:
    try:
        return parse_step(text).verb
    except StepError:
        return ""


def _found_before(plan: Sequence[str], index: int) -> list[tuple[int, str]]:
    """``(position, object)`` of each ``find`` before ``index``, latest first."""
    found = [(i, _object(s)) for i, s in enumerate(plan[:index]) if _verb(s) == "find"]
    return [(i, o) for i, o in reversed(found) if o is not None]


def _carry(plan: list[str], index: int, executor: HouseholdExecutor) -> tuple[list[str], str] | None:
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
    if _verb(plan[index]) == "pour":  # pour from something that holds liquid, if one was found
        filled = [(i, o) for i, o in candidates if executor.state[o].flags["isFilledWithLiquid"]]
        candidates = filled + [c for c in candidates if c not in filled]
    if not candidates:
        return None
    found_at, obj = candidates[0]
    hand_free = not any(_verb(s) in HAND_VERBS for s in plan[found_at + 1 : index])
    at = found_at + 1 if hand_free else index
    return [*plan[:at], f"pick {obj}", *plan[at:]], f"inserted pick {obj}"


def _receptacle(plan: list[str], index: int, executor: HouseholdExecutor) -> tuple[list[str], str] | None:
    """``put X`` where X is no receptacle (usually the held object): the receptacle last found."""
    types = catalogue()
    for _, obj in _found_before(plan, index):
        if types.has(obj, "receptacle") and obj != executor.held:
            return [*plan[:index], f"put {obj}", *plan[index + 1 :]], f"put on {obj} instead"
    return None


def liquid_named(instruction: str) -> str:
    """The first of the actions' liquids the instruction names ("pour coffee ..." -> coffee), else
    water."""
    words = re.findall(r"[a-z]+", instruction.lower())
    return next((w for w in words if w in LIQUIDS), "water")


def _fix(
    plan: list[str], index: int, result: StepResult, executor: HouseholdExecutor, liquid: str
) -> tuple[list[str], str]:
    """The plan with the one change that ``result`` (the failure of ``plan[index]``) calls for."""
    verb, obj = _verb(plan[index]), _object(plan[index])
    fixed: tuple[list[str], str] | None = None
    if result.failure == EMPTY_CONTAINER and catalogue().has(result.about, "fillable"):
        fill = f"fillLiquid {result.about} {liquid}"
        fixed = [*plan[:index], fill, *plan[index:]], f"inserted {fill}"
    elif result.failure == EMPTY_HAND:
        fixed = _carry(plan, index, executor)
    elif result.failure == NOT_FOUND and obj:
        fixed = [*plan[:index], f"find {obj}", *plan[index:]], f"inserted find {obj}"
    elif result.failure == CLOSED and result.about:
        fixed = [*plan[:index], f"open {result.about}", *plan[index:]], f"inserted open {result.about}"
    elif verb == "put" and obj and not catalogue().has(obj, "receptacle"):
        fixed = _receptacle(plan, index, executor)
    return fixed or ([*plan[:index], *plan[index + 1 :]], "dropped the step")


def _first_failure(
    scene: HouseScene, plan: Sequence[str]
) -> tuple[int, StepResult, HouseholdExecutor] | None:
    executor = HouseholdExecutor(scene)
    for index, text in enumerate(plan):
        result = executor.step(text)  # a failed step leaves the state as it was
        if not result.ok:
            return index, result, executor
    return None


def ground_plan(
    scene: HouseScene, steps: Sequence[str], instruction: str = ""
) -> tuple[list[str], list[Repair]]:
    """The plan with every failed step repaired (see the module docstring), and the repairs made.
    ``instruction`` only says which liquid an empty container is filled with.

    Each round fixes the first failing step and runs the plan again. Every change either drops a
    step or inserts one that removes the failure at hand, so a bounded number of rounds suffices;
    what is still failing after them is dropped.
    """
    plan = list(steps)
    repairs: list[Repair] = []
    for _ in range(3 * len(plan) + 3):
        failing = _first_failure(scene, plan)
        if failing is None:
            return plan, repairs
        index, result, executor = failing
        before = plan[index]
        plan, change = _fix(plan, index, result, executor, liquid_named(instruction))
        repairs.append(Repair(before, result.message, change))
    while (failing := _first_failure(scene, plan)) is not None:
        index, result, _ = failing
        repairs.append(Repair(plan[index], result.message, "dropped the step"))
        plan = [*plan[:index], *plan[index + 1 :]]
    return plan, repairs
