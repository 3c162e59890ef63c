"""The goal a request states, as typed values: where things go, which things, how many (what the
words settle and nothing more: a destination they do not name is ``None``)."""

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
        to: The destination as the scene names it, or None (the planner chooses).
        takes: ``named``, ``criterion``, ``remainder`` ("the rest"), ``ingredients``, ``need`` or ``all``.
        named: The scene objects the request names for it, in scene spelling.
        criterion: The request's words for which objects go ("poisonous"), "by <key>" in a sort, or "".
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
        dish: The dish the request asks to be made, in its words, or None.
        need: The request's words stating a need no object phrase names, or None.
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
