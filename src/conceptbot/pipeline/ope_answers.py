"""OPE's answer about one object, typed per mode, and what each kind of answer means downstream.

Each class reads the mode's JSON answer (as the model gave it, or as the cache holds it) with
:meth:`from_json`, and says how the planners use it: a one-line :meth:`summary` for prompts, whether
it is :meth:`notable`, the affordance penalty S_prop (:meth:`penalty`, see
:mod:`conceptbot.pipeline.affordance`), and the danger rating the goal planner and the household
planner weigh. The JSON itself is kept unchanged in :class:`~conceptbot.pipeline.ope.ObjectProperties`
(the trace and the cache hold it), so reading it never loses a field.

Parsing is lenient, as the old dict look-ups were: a missing field reads as "not said" (no property
held, no danger rating, no materials), never as an error.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Protocol

from conceptbot.pipeline.vocabulary import PROPERTY_NAMES

# S_prop factors (the module docstring of conceptbot.pipeline.affordance explains them).
FRAGILE = 0.8
DANGEROUS = 0.7
DANGEROUS_TO_PERSON = 0.4
DANGER_STEP = 0.12  # per danger point above 1
INTERACTION_STEP = 0.2  # per interaction point above 1


class OPEAnswer(Protocol):
    """What every mode's answer offers the planners."""

    reason: str

    def summary(self, name: str) -> str:
        """One line for prompts, e.g. ``knife: dangerous, safe``."""
        ...

    def move_summary(self, name: str, target: str) -> str:
        """The answer as evidence about moving the object to ``target``."""
        ...

    def notable(self) -> bool:
        """Whether the answer has something worth telling the planner."""
        ...

    def rated_danger(self) -> int:
        """The 1-5 danger rating; 0 where the mode does not rate danger."""
        ...

    def penalty(self, name: str, target: str, to_person: bool, partner: OPEAnswer | None) -> float:
        """S_prop of moving the object ``name`` to ``target`` (before clamping at 0).

        Args:
            name: The object, as the scene names it.
            target: The destination.
            to_person: Whether the destination is a person (a hand-over).
            partner: OPE's answer about the destination, if it has one.
        """
        ...


class AnswerType(Protocol):
    """An answer class: reads a mode's JSON answer."""

    def from_json(self, values: Mapping[str, Any]) -> OPEAnswer:
        """The typed answer."""
        ...


def _int(value: Any) -> int | None:
    try:
        return int(value)
    except (TypeError, ValueError):
        return None


@dataclass(frozen=True)
class YesNoProperties:
    """The ``properties`` mode: which of the Yes/No properties hold.

    Attributes:
        held: The properties answered "Yes", in :data:`~conceptbot.pipeline.vocabulary.PROPERTY_NAMES` order.
        reason: The model's reason, where it gave one (the schema asks for none).
    """

    held: tuple[str, ...]
    reason: str = ""

    @classmethod
    def from_json(cls, values: Mapping[str, Any]) -> YesNoProperties:
        """Read the mode's JSON answer (``{"fragile": "Yes", ...}``)."""
        held = tuple(p for p in PROPERTY_NAMES if values.get(p) == "Yes")
        return cls(held, str(values.get("reason", "")))

    def has(self, prop: str) -> bool:
        """Whether the property ``prop`` (a field name, ``hold_liquid``) holds."""
        return prop in self.held

    def summary(self, name: str) -> str:
        """Only the properties that hold: half the tokens of "fragile No, hold liquid No, ..." and the
        prompt of a 25-object scene stays short enough to evaluate quickly on a CPU."""
        held = [p.replace("_", " ") for p in self.held]
        return f"{name}: {', '.join(held) if held else 'none of the listed properties'}"

    def move_summary(self, name: str, target: str) -> str:
        """The summary: no property depends on where the object goes."""
        return self.summary(name)

    def notable(self) -> bool:
        """A property other than the "safe" and "stable" that hold for most things."""
        return any(p not in ("safe", "stable") for p in self.held)

    def rated_danger(self) -> int:
        """Not rated in this mode."""
        return 0

    def penalty(self, name: str, target: str, to_person: bool, partner: OPEAnswer | None) -> float:
        """Fixed factors: fragile x0.8, dangerous x0.7 (x0.4 when handed to a person)."""
        score = 1.0
        if self.has("fragile"):
            score *= FRAGILE
        if self.has("dangerous"):
            score *= DANGEROUS_TO_PERSON if to_person else DANGEROUS
        return score


@dataclass(frozen=True)
class Partner:
    """An object of the scene this one is dangerous with, and how much (1-5)."""

    object: str
    score: int


@dataclass(frozen=True)
class RiskIndex:
    """The ``risk`` mode: the paper's Risk Index.

    Attributes:
        danger: The object's own danger, 1-5 (None when the answer has no usable rating).
        dangerous_with: Objects of the scene it is dangerous with.
        reason: The model's one-sentence reason.
    """

    danger: int | None
    dangerous_with: tuple[Partner, ...] = ()
    reason: str = ""

    @classmethod
    def from_json(cls, values: Mapping[str, Any]) -> RiskIndex:
        """Read the mode's JSON answer (``{"dangerous": 3, "dangerous_with": [...], "reason": ...}``)."""
        partners = tuple(Partner(str(d["object"]), int(d["score"])) for d in values.get("dangerous_with", []))
        return cls(_int(values.get("dangerous")), partners, str(values.get("reason", "")))

    def score_with(self, other: str) -> int | None:
        """The interaction score with ``other``, or None when none was given; the highest where the
        model listed ``other`` more than once (a safety decision takes the worst it was told)."""
        scores = [p.score for p in self.dangerous_with if p.object == other]
        return max(scores) if scores else None

    def summary(self, name: str) -> str:
        """``tray: danger 2/5, dangerous with oven (5)``."""
        others = ", ".join(f"{p.object} ({p.score})" for p in self.dangerous_with)
        return f"{name}: danger {self.danger}/5" + (f", dangerous with {others}" if others else "")

    def move_summary(self, name: str, target: str) -> str:
        """The danger and the interaction score with ``target`` only (the other partners are noise
        for a question about this move)."""
        score = self.score_with(target)
        text = f"{name}: danger {self.danger}/5"
        return text + (f", dangerous with the {target} {score}/5" if score is not None else "")

    def notable(self) -> bool:
        """Rated above 1, or dangerous with something."""
        return (1 if self.danger is None else self.danger) > 1 or bool(self.dangerous_with)

    def rated_danger(self) -> int:
        """The rating (0 when the answer had none)."""
        return self.danger or 0

    def penalty(self, name: str, target: str, to_person: bool, partner: OPEAnswer | None) -> float:
        """Scaled: danger d -> x(1 - 0.12 (d - 1)); each interaction score s between the object and
        ``target`` -> x(1 - 0.2 (s - 1)), judged from both sides (the destination may name the object)."""
        score = 1.0
        score *= 1.0 - DANGER_STEP * ((1 if self.danger is None else self.danger) - 1)
        for item in self.dangerous_with:
            if item.object == target:
                score *= 1.0 - INTERACTION_STEP * (item.score - 1)
        if isinstance(partner, RiskIndex):
            for item in partner.dangerous_with:
                if item.object == name:
                    score *= 1.0 - INTERACTION_STEP * (item.score - 1)
        return score


@dataclass(frozen=True)
class Materials:
    """The ``materials`` mode: what the object is made of.

    Attributes:
        materials: Materials from :data:`~conceptbot.pipeline.vocabulary.MATERIALS`.
        single_material: Whether it is made of one material only.
        reason: The model's one-sentence reason.
    """

    materials: tuple[str, ...]
    single_material: bool
    reason: str = ""

    @classmethod
    def from_json(cls, values: Mapping[str, Any]) -> Materials:
        """Read the mode's JSON answer (``{"materials": [...], "single_material": true, ...}``)."""
        materials = tuple(str(m) for m in values.get("materials", []))
        return cls(materials, bool(values.get("single_material")), str(values.get("reason", "")))

    def summary(self, name: str) -> str:
        """``cup: made of paper, wax (mixed materials)``."""
        single = "single material" if self.single_material else "mixed materials"
        return f"{name}: made of {', '.join(self.materials) or 'unknown'} ({single})"

    def move_summary(self, name: str, target: str) -> str:
        """The summary: materials do not depend on where the object goes."""
        return self.summary(name)

    def notable(self) -> bool:
        """Always: what things are made of is what a materials request is about."""
        return True

    def rated_danger(self) -> int:
        """Not rated in this mode."""
        return 0

    def penalty(self, name: str, target: str, to_person: bool, partner: OPEAnswer | None) -> float:
        """No penalty: materials say nothing about risk."""
        return 1.0
