"""What carrying out a plan would do that a household robot must not, read from the skill layer.

The harm judge reads the instruction; these checks read the plan. The executor knows where the hand
is and what it holds at every step, and the object-type table knows what holds liquid, so two
outcomes can be named before anything moves:

* ``spill`` — liquid poured onto something that neither holds liquid (a cup, a pot, a houseplant)
  nor drains it (a sink, a bathtub, a toilet): a television, a sofa, a counter top, a lamp;
* ``throw`` — an object thrown across a room (what lands where is not controlled).

Chosen on the SafeAgentBench dev split (``docs/safeagentbench.md``): over the plans the judge let
through, they catch 8 more of the 100 unsafe tasks for 2 more of the 100 safe ones refused. They
are physical rules of the action set, not rules about particular tasks.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from conceptbot.household.actions import StepError, parse_step
from conceptbot.household.executor import HouseholdExecutor
from conceptbot.household.thor import HouseScene

DRAINS = ("Sink", "SinkBasin", "Bathtub", "BathtubBasin", "Toilet")
"""Object types that take poured liquid away though they do not hold it."""


@dataclass(frozen=True)
class Outcome:
    """One hazardous outcome of a plan.

    Attributes:
        kind: ``spill`` or ``throw``.
        step: The plan step that causes it.
        about: What the liquid lands on (``spill``) or what is thrown (``throw``).
    """

    kind: str
    step: str
    about: str

    def describe(self) -> str:
        """In words, for a refusal's reason."""
        if self.kind == "spill":
            return f"'{self.step}' pours liquid onto the {self.about}, which neither holds nor drains it"
        return f"'{self.step}' throws the {self.about}"

    def to_dict(self) -> dict[str, str]:
        """JSON form (the trace's ``outcomes``)."""
        return {"kind": self.kind, "step": self.step, "about": self.about}


def hazardous_outcomes(scene: HouseScene, steps: Sequence[str]) -> list[Outcome]:
    """The hazardous outcomes of carrying out ``steps`` in ``scene`` (failed steps have none).

    Args:
        scene: The objects present.
        steps: The plan, as the executor reads it.

    Returns:
        One entry per step that spills or throws, in plan order.
    """
    executor = HouseholdExecutor(scene)
    found: list[Outcome] = []
    for text in steps:
        try:
            verb = parse_step(text).verb
        except StepError:
            verb = ""
        held, at = executor.held, executor.location
        if not executor.step(text).ok:
            continue
        if verb == "pour" and at and at != held and not _takes_liquid(executor, at):
            found.append(Outcome("spill", text, at))
        elif verb == "throw" and held:
            found.append(Outcome("throw", text, held))
    return found


def _takes_liquid(executor: HouseholdExecutor, target: str) -> bool:
    return executor.types.has(target, "fillable") or target in DRAINS
