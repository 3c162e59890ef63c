"""What carrying out a plan would do that a household robot must not, read from the skill layer.

The harm judge reads the instruction; these read the plan. The executor knows where the hand
is and what it holds at every step, and the object-type table knows what holds liquid, so two
outcomes can be named before anything moves:

* ``spill`` — liquid poured onto something that neither holds liquid (a cup, a pot, a houseplant)
  nor drains it (a sink, a bathtub, a toilet): a television, a sofa, a counter top, a lamp;
* ``throw`` — an object thrown across a room (what lands where is not controlled).

Neither decides a refusal on its own: they are signals of the fitted harm judgement
(:mod:`conceptbot.household.harm`), beside :func:`plan_effects`, which says in words what a plan
leaves behind for the outcome judge.
"""

from __future__ import annotations

from collections.abc import Sequence

from conceptbot.core.plan import HouseholdAction, format_action
from conceptbot.core.scene import HouseScene
from conceptbot.core.trace import Outcome
from conceptbot.household.executor import HouseholdExecutor
from conceptbot.household.thor import ThorCatalogue

DRAINS = ("Sink", "SinkBasin", "Bathtub", "BathtubBasin", "Toilet")
"""Object types that take poured liquid away though they do not hold it."""
HOLDS_WATER = ("Vase",)
"""Vessels that hold water though the simulator cannot fill them."""


def hazardous_outcomes(scene: HouseScene, steps: Sequence[HouseholdAction]) -> list[Outcome]:
    """The hazardous outcomes of carrying out ``steps`` in ``scene`` (failed steps have none).

    Args:
        scene: The objects present.
        steps: The plan.

    Returns:
        One entry per step that spills or throws, in plan order.
    """
    executor = HouseholdExecutor(scene)
    found: list[Outcome] = []
    for step in steps:
        held, at = executor.held, executor.location
        if not executor.step(step).ok:
            continue
        if step.verb == "pour" and at and at != held and not holds_or_drains(executor.types, at):
            found.append(Outcome("spill", format_action(step), at))
        elif step.verb == "throw" and held:
            found.append(Outcome("throw", format_action(step), held))
    return found


def holds_or_drains(types: ThorCatalogue, target: str) -> bool:
    """Whether liquid poured onto an object of type ``target`` is held or drained, not spilled."""
    return types.has(target, "fillable") or target in DRAINS + HOLDS_WATER


#: How each change of an object's state reads in words (the state the plan leaves it in).
_CHANGED = {
    ("isToggled", True): "left switched on",
    ("isToggled", False): "switched off",
    ("isOpen", True): "left open",
    ("isOpen", False): "closed",
    ("isBroken", True): "broken",
    ("isFilledWithLiquid", True): "filled with {liquid}",
    ("isFilledWithLiquid", False): "emptied",
    ("isDirty", True): "made dirty",
    ("isDirty", False): "cleaned",
    ("isCooked", True): "cooked",
    ("isSliced", True): "sliced",
}


def plan_effects(scene: HouseScene, steps: Sequence[HouseholdAction]) -> list[str]:
    """What carrying out ``steps`` would leave behind, in plain words, for a judgement of the
    outcome rather than of the request's words: every state the plan changes, where it moves things
    (and what is inside an appliance left on), and what it spills or throws.

    Failed steps change nothing, as in the executor. The sentences follow the object-type table's
    names ("the Sponge is in the Toaster", "the Toaster is left switched on").
    """
    executor = HouseholdExecutor(scene)
    fresh = {t: (dict(s.flags), list(s.parents)) for t, s in executor.state.items()}
    spilled = [
        f"liquid is poured onto the {o.about}" if o.kind == "spill" else f"the {o.about} is thrown"
        for o in hazardous_outcomes(scene, steps)
    ]
    execution = executor.run(steps)
    said: list[str] = []
    for t, s in execution.state.items():
        flags, parents = fresh.get(t, (dict.fromkeys(s.flags, False), []))
        if s.parents and s.parents[:1] != parents[:1]:
            said.append(f"the {t} is in or on the {s.parents[0]}")
        for key, value in s.flags.items():
            words = _CHANGED.get((key, value))
            if words and flags.get(key) != value:
                said.append(f"the {t} is {words.format(liquid=s.liquid or 'liquid')}")
    for t, s in execution.state.items():
        inside = [o for o, os in execution.state.items() if os.parents[:1] == [t]]
        if s.flags.get("isToggled") and inside:
            said.append(f"the {t} is on with the {', the '.join(inside)} in or on it")
    return said + spilled
