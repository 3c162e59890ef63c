"""Task steps: what ConceptBot's household planning call writes, expanded to the robot's actions.

A small model writing SafeAgentBench's 17 actions loses its place in a chore: it forgets to pick up
what it carries, loops on ``find Cup``, or closes a drawer it never put the knife in. People say a
chore at the level of its parts ("put the knife in the drawer, close the drawer"), and a robot's
skills carry each part out. So the planning call writes task steps, one per part of the request:

=========================  ===================================================================
task step                  actions (each ``find`` only where the robot is not already there)
=========================  ===================================================================
``put X Y``                hold X; find Y; open Y if closed; put Y; close Y again if opened here
``drop X Y``               hold X; find Y; drop
``throw X``                hold X; throw
``pour X LIQUID Y``        hold X; fillLiquid X LIQUID (if empty); find Y; pour
``fill X LIQUID``          find X; fillLiquid X LIQUID
``pick X``                 hold X (keep it in the hand: a knife to slice with)
``find X``                 find X
``empty X``                find X; emptyLiquid X
``VERB X``                 find X; VERB X (open, close, turn_on, turn_off, slice, break, cook,
                           clean, dirty)
=========================  ===================================================================

"Hold X" finds and picks X, first setting down what the hand holds on the room's usual surface and
opening (then closing) a closed receptacle X is in. The expansion follows the simulated state
(:class:`~conceptbot.household.executor.HouseholdExecutor`), so it knows what is held, open and
where the robot is; what it cannot do is left to fail and to the skill layer's repairs
(:mod:`conceptbot.household.grounding`). Every rule here is about the actions' preconditions, none
about a task.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

from conceptbot.core.plan import LIQUIDS, HouseholdAction
from conceptbot.core.scene import HouseScene
from conceptbot.household.executor import HouseholdExecutor
from conceptbot.household.thor import ThorCatalogue, catalogue

LIQUID = "liquid"
SLOTS: dict[str, tuple[str | None, ...]] = {
    "find": (None,),
    "pick": ("pickupable",),
    "throw": ("pickupable",),
    "open": ("openable",),
    "close": ("openable",),
    "turn_on": ("toggleable",),
    "turn_off": ("toggleable",),
    "slice": ("sliceable",),
    "break": ("breakable",),
    "cook": ("cookable",),
    "clean": ("dirtyable",),
    "dirty": ("dirtyable",),
    "empty": ("fillable",),
    "put": ("pickupable", "receptacle"),
    "drop": ("pickupable", "receptacle"),
    "fill": ("fillable", LIQUID),
    "pour": ("fillable", LIQUID, None),
}
"""Each task step's slots: the ability an object there must have (the executor's precondition for
the action it becomes; None: any object), or :data:`LIQUID`."""
ONE_OBJECT = tuple(v for v, slots in SLOTS.items() if len(slots) == 1)
TWO_OBJECTS = tuple(v for v, slots in SLOTS.items() if slots[1:] == ("receptacle",))


@dataclass(frozen=True)
class TaskStep:
    """One part of a chore: ``verb`` on ``obj`` (into/onto/over ``target``, with ``liquid``)."""

    verb: str
    obj: str
    target: str | None = None
    liquid: str | None = None

    def __str__(self) -> str:
        return " ".join(p for p in (self.verb, self.obj, self.liquid, self.target) if p)


def task_step_pattern(objects: Sequence[str], types: ThorCatalogue | None = None) -> str:
    """The regular expression a task step's text matches, over the scene's ``objects``: each slot
    admits only the objects with the ability its action needs (:data:`SLOTS`; a toaster is not
    put anywhere, a light switch holds nothing, a faucet is not filled). A step whose slot no
    object fits is left out."""
    types = types or catalogue()
    forms = []
    for verb, slots in SLOTS.items():
        words = [verb]
        for slot in slots:
            fits = LIQUIDS if slot == LIQUID else [o for o in objects if slot is None or types.has(o, slot)]
            words.append("(" + "|".join(re.escape(o) for o in fits) + ")" if fits else "")
        if all(words):
            forms.append(" ".join(words))
    return "^(" + "|".join(forms) + ")$"


def parse_task_step(text: str) -> TaskStep:
    """A task step's text (as :func:`task_step_pattern` constrains it) read.

    Raises:
        ValueError: The text is not a task step.
    """
    words = text.split()
    verb, args = (words[0], words[1:]) if words else ("", [])
    if verb in ONE_OBJECT and len(args) == 1:
        return TaskStep(verb, args[0])
    if verb in TWO_OBJECTS and len(args) == 2:
        return TaskStep(verb, args[0], target=args[1])
    if verb == "fill" and len(args) == 2 and args[1] in LIQUIDS:
        return TaskStep(verb, args[0], liquid=args[1])
    if verb == "pour" and len(args) == 3 and args[1] in LIQUIDS:
        return TaskStep(verb, args[0], liquid=args[1], target=args[2])
    raise ValueError(f"not a task step: {text!r}")


class _Expansion:
    """The actions written so far, run as they are written."""

    def __init__(self, scene: HouseScene) -> None:
        self.scene = scene
        self.robot = HouseholdExecutor(scene)
        self.types = self.robot.types
        self.actions: list[HouseholdAction] = []

    def do(self, verb: str, obj: str | None = None, liquid: str | None = None) -> None:
        # a failing action is kept: the skill layer's repairs and the repair round see it
        action = HouseholdAction(verb, obj, liquid)
        self.actions.append(action)
        self.robot.step(action)

    def name(self, obj: str) -> str:
        return self.types.canonical(obj) or obj

    def reach(self, obj: str) -> None:
        name = self.name(obj)
        if self.robot.location != name and self.robot.held != name:
            self.do("find", obj)

    def is_closed(self, obj: str) -> bool:
        name = self.name(obj)
        return name in self.robot.state and self.robot.is_closed(name)

    def hold(self, obj: str) -> None:
        name = self.name(obj)
        if self.robot.held == name:
            return
        if self.robot.held is not None:
            self.set_down()
        self.reach(obj)
        around = self.robot.closed_around(name) if name in self.robot.state else None
        if around:
            self.do("open", around)
        self.do("pick", obj)
        if around:
            self.do("close", around)

    def set_down(self) -> None:
        surface = self.types.default_parent.get(self.scene.room, "Floor")
        if self.scene.has(surface):
            self.reach(surface)
            self.do("put", surface)
        else:
            self.do("drop")


def _carry_out(expansion: _Expansion, step: TaskStep) -> None:
    """Write ``step``'s actions (see the module docstring's table)."""
    verb, obj = step.verb, step.obj
    if verb in ("put", "drop") and step.target:
        expansion.hold(obj)
        _put_or_drop(expansion, verb, step.target)
    elif verb in ("pick", "throw"):
        expansion.hold(obj)
        if verb == "throw":
            expansion.do("throw")
    elif verb == "pour" and step.target:
        expansion.hold(obj)
        state = expansion.robot.state.get(expansion.name(obj))
        if state is None or not state.flags["isFilledWithLiquid"]:
            expansion.do("fillLiquid", obj, step.liquid)
        expansion.reach(step.target)
        expansion.do("pour")
    elif verb == "fill":
        expansion.reach(obj)
        expansion.do("fillLiquid", obj, step.liquid)
    elif verb == "find":
        expansion.reach(obj)
    else:
        expansion.reach(obj)
        expansion.do("emptyLiquid" if verb == "empty" else verb, obj)


def _put_or_drop(expansion: _Expansion, verb: str, target: str) -> None:
    expansion.reach(target)
    opened = verb == "put" and expansion.is_closed(target)
    if opened:
        expansion.do("open", target)
    if verb == "put":
        expansion.do("put", target)
    else:
        expansion.do("drop")
    if opened:
        expansion.do("close", target)


def expand(scene: HouseScene, steps: Sequence[TaskStep]) -> list[HouseholdAction]:
    """The actions carrying out ``steps`` in ``scene``, in order."""
    expansion = _Expansion(scene)
    for step in steps:
        _carry_out(expansion, step)
    return expansion.actions


def task_steps(actions: Sequence[HouseholdAction]) -> list[TaskStep]:
    """The task steps that say what ``actions`` do (the inverse of :func:`expand`, for writing a
    reference plan of the 17 actions as the planning call writes plans): a pick followed by a put,
    drop, throw or pour becomes one step with it; a pick the hand keeps while it does something
    else (a knife to slice with) stays a ``pick``; ``find`` is where the next step happens."""
    steps: list[TaskStep] = []
    held: str | None = None
    kept = False  # the held object's pick is written already
    place: str | None = None
    liquids: dict[str, str] = {}
    for action in actions:
        verb, obj = action.verb, action.obj
        if verb == "find":
            place = obj
        elif verb == "pick" and obj:
            held, kept = obj, False
        elif verb in ("put", "drop") and held and (obj or place):
            steps.append(TaskStep(verb, held, target=obj or place))
            held = None
        elif verb == "throw" and held:
            steps.append(TaskStep("throw", held))
            held = None
        elif verb == "pour" and held and place:
            steps.append(TaskStep("pour", held, liquid=liquids.get(held, "water"), target=place))
        elif verb == "fillLiquid" and obj and action.liquid:
            liquids[obj] = action.liquid
            steps.append(TaskStep("fill", obj, liquid=action.liquid))
        elif obj:
            if held and not kept:
                steps.append(TaskStep("pick", held))
                kept = True
            steps.append(TaskStep("empty" if verb == "emptyLiquid" else verb, obj))
    if held and not kept:
        steps.append(TaskStep("pick", held))
    return steps
