"""The goal a request states, as typed values: where things go, which things, how many.

A :class:`Goal` is what the request's words settle and nothing more: a destination the words do not
name is ``None`` (the planner chooses it by scoring), and so is the number of objects a need calls
for (``"all"``: as many as it takes).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

#: How a target's objects are chosen (see :class:`GoalTarget`).
Takes = Literal["named", "criterion", "remainder", "ingredients", "need", "all"]
TAKES: tuple[str, ...] = ("named", "criterion", "remainder", "ingredients", "need", "all")
#: The count of a target that takes every object that fits.
ALL: Literal["all"] = "all"
Count = int | Literal["all"]


@dataclass(frozen=True)
class GoalTarget:
    """One destination of the goal and the objects that go there.

    Attributes:
        to: The destination as the scene names it, or None: the request names none and the planner
            chooses it by scoring (a need, a dish, "throw away", "out of the toddler's reach").
        takes: ``named``: only the objects it names; ``criterion``: the objects ``criterion``
            describes; ``remainder``: whatever no other target takes ("the rest"); ``ingredients``:
            the dish's ingredients; ``need``: whatever meets the need; ``all``: every object.
        named: The scene objects the request names for it, in scene spelling.
        criterion: The request's words that say which objects go ("poisonous", "made entirely of
            glass", "something to write with"), "by <key>" for a place in a sort by a key ("by
            material"), a need's part for one of several needs ("I'm chilly"), "" otherwise (a
            place in a sort the words give nothing else for: its name decides).
        count: How many objects the words ask for, or ``"all"``.
    """

    to: str | None
    takes: Takes
    named: tuple[str, ...] = ()
    criterion: str = ""
    count: Count = ALL

    def __post_init__(self) -> None:
        if self.takes not in TAKES:
            raise ValueError(f"unknown takes {self.takes!r} (one of {', '.join(TAKES)})")
        if self.count != ALL and not (isinstance(self.count, int) and self.count >= 1):
            raise ValueError(f"count must be a positive int or 'all', not {self.count!r}")

    def to_dict(self) -> dict[str, Any]:
        """JSON form (the goal set's)."""
        data: dict[str, Any] = {
            "to": self.to,
            "takes": self.takes,
            "named": list(self.named),
            "criterion": self.criterion,
            "count": self.count,
        }
        return data

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> GoalTarget:
        """Read the JSON form.

        Raises:
            ValueError: A field is missing or invalid.
        """
        try:
            return cls(
                to=data["to"],
                takes=data["takes"],
                named=tuple(data.get("named", ())),
                criterion=data.get("criterion", ""),
                count=data.get("count", ALL),
            )
        except KeyError as exc:
            raise ValueError(f"goal target without {exc.args[0]!r}: {dict(data)}") from exc


@dataclass(frozen=True)
class Goal:
    """What a request asks for.

    Attributes:
        stack: The request asks for a pile (the objects go on each other, not to a destination).
        dish: The dish the request asks to be made, in its words ("guacamole", "fruit salad"), or None.
        need: The request's words stating a need no object phrase names ("my phone battery is almost
            empty"), or None.
        targets: Where things go; order carries no meaning.
    """

    stack: bool = False
    dish: str | None = None
    need: str | None = None
    targets: tuple[GoalTarget, ...] = field(default_factory=tuple)

    def to_dict(self) -> dict[str, Any]:
        """JSON form (the goal set's)."""
        return {
            "stack": self.stack,
            "dish": self.dish,
            "need": self.need,
            "targets": [t.to_dict() for t in self.targets],
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Goal:
        """Read the JSON form.

        Raises:
            ValueError: A field is invalid.
        """
        return cls(
            stack=bool(data.get("stack", False)),
            dish=data.get("dish"),
            need=data.get("need"),
            targets=tuple(GoalTarget.from_dict(t) for t in data.get("targets", ())),
        )
