"""What carrying out a plan would do that a household robot must not, read from the skill layer.

The harm judge reads the instruction; these checks read the plan. The executor knows where the hand
is and what it holds at every step, and the object-type table knows what holds liquid, so two
outcomes can be named before anything moves:

* ``spill`` — liquid poured onto something that neither holds liquid (a cup, a pot, a houseplant)
  nor drains it (a sink, a bathtub, a toilet): a television, a sofa, a counter top, a lamp;
* ``throw`` — an object thrown across a room (what lands where is not controlled).

Chosen on the SafeAgentBench dev split (``docs/notes/2026-11-30-safeagentbench-v3-plan-outcome-check.md``):
over the plans the judge let through, they catch 8 more of the 100 unsafe tasks for 2 more of the 100
safe ones refused. They are physical rules of the action set, not rules about particular tasks.

:func:`requested_outcomes` reads the same two outcomes from the instruction's words, for the plans
that leave the hazardous step out (v4; on dev 4 more unsafe tasks refused for 1 more safe one).
"""

from __future__ import annotations

import re
from collections.abc import Sequence

from conceptbot.core.plan import HouseholdAction, format_action
from conceptbot.core.scene import HouseScene
from conceptbot.core.trace import Outcome
from conceptbot.household.executor import HouseholdExecutor
from conceptbot.household.thor import ThorCatalogue, catalogue

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


POUR_VERBS = frozenset({"pour", "pours", "pouring", "spill", "spills", "splash", "splashes", "dump"})
THROW_VERBS = frozenset({"throw", "throws", "throwing", "toss", "tosses", "hurl", "fling"})
ONTO = frozenset({"on", "onto", "over", "into", "in"})
"""Prepositions that name where poured liquid lands."""
_STOP = frozenset({"using", "from", "with", "while", "after", "before", "to", "so"})
_PRONOUNS = frozenset({"it", "them"})
_CLAUSE = re.compile(r"[,;.!?]|\bthen\b|\band\b")


def requested_outcomes(instruction: str, types: ThorCatalogue | None = None) -> list[Outcome]:
    """The same two outcomes, read from what the instruction asks rather than from the plan.

    A small planner often leaves the hazardous step out ("Throw the mug." planned as a drop), and a
    plan that does not do what was asked is no reason to carry out the rest of it. The instruction
    is read clause by clause (split at punctuation, "and", "then"):

    * a throwing verb is a ``throw`` of the object named after it (not "throw ... away", not into a
      garbage can: that is putting rubbish away);
    * a pouring verb followed by "on", "onto", "over", "into" or "in" and an object that neither
      holds liquid nor drains it is a ``spill`` onto that object.

    "It" stands for the object named last before it. Anything not recognised is no outcome.

    Args:
        instruction: The request, in words.
        types: The object-type table (the bundled one by default).

    Returns:
        One entry per clause that asks for a spill or a throw, in order.
    """
    types = types or catalogue()
    found: list[Outcome] = []
    last_named = ""
    for clause in _CLAUSE.split(instruction):
        words = re.findall(r"[a-z]+", clause.lower())
        named = _objects_in(words, types)
        throw = next((i for i, w in enumerate(words) if w in THROW_VERBS), None)
        pour = next((i for i, w in enumerate(words) if w in POUR_VERBS), None)
        if throw is not None and "away" not in words and all(n != "GarbageCan" for _, n in named):
            thrown = _object_after(words, named, throw, last_named, stop=frozenset())
            found.append(Outcome("throw", clause.strip(), thrown or "object"))
        elif pour is not None:
            at = next((i for i in range(pour + 1, len(words)) if words[i] in ONTO), None)
            target = _object_after(words, named, at, last_named, _STOP) if at is not None else ""
            if target and not holds_or_drains(types, target):
                found.append(Outcome("spill", clause.strip(), target))
        if named:
            last_named = named[-1][1]
    return found


def _objects_in(words: list[str], types: ThorCatalogue) -> list[tuple[int, str]]:
    """(word index, object type) for each object named in ``words``, longest name first."""
    found: list[tuple[int, str]] = []
    i = 0
    while i < len(words):
        for n in (3, 2, 1):
            name = types.canonical("".join(words[i : i + n])) if i + n <= len(words) else None
            if name:
                found.append((i, name))
                i += n
                break
        else:
            i += 1
    return found


def _object_after(
    words: list[str], named: list[tuple[int, str]], at: int, last_named: str, stop: frozenset[str]
) -> str:
    """The object named within a few words after index ``at`` ("it": the one named before)."""
    for j in range(at + 1, min(at + 6, len(words))):
        if words[j] in stop:
            break
        if words[j] in _PRONOUNS:
            before = [n for k, n in named if k < at]
            return before[-1] if before else last_named
        hit = [n for k, n in named if k == j]
        if hit:
            return hit[0]
    return ""


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
