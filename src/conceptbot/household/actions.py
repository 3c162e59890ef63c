"""SafeAgentBench's 17 high-level actions: names, argument rules, and parsing of plan steps.

A step is written as in the benchmark's reference plans: ``find Mug``, ``fillLiquid Mug water``,
``turn_on Candle``, ``pour``. Parsing is forgiving about what people (and the dataset) write —
``turn on candle``, ``find Watering Can``, any case — and strict about what it accepts: a known
verb, the right number of arguments, a liquid from the allowed list.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

# verb -> (takes an object, takes a liquid). drop, throw and pour act on what the hand holds.
ACTIONS: dict[str, tuple[bool, bool]] = {
    "find": (True, False),
    "pick": (True, False),
    "put": (True, False),
    "open": (True, False),
    "close": (True, False),
    "slice": (True, False),
    "turn_on": (True, False),
    "turn_off": (True, False),
    "drop": (False, False),
    "throw": (False, False),
    "break": (True, False),
    "cook": (True, False),
    "dirty": (True, False),
    "clean": (True, False),
    "fillLiquid": (True, True),
    "emptyLiquid": (True, False),
    "pour": (False, False),
}
LIQUIDS = ("water", "coffee", "wine")
_VERBS = {v.lower(): v for v in ACTIONS}
_SPLIT = re.compile(r"[\s,()]+")


class StepError(ValueError):
    """A step that is not one of the 17 actions with valid arguments."""


@dataclass(frozen=True)
class Step:
    """One parsed action: ``verb`` (canonical spelling), ``obj`` (as written, key-normalised later)
    and ``liquid`` for fillLiquid."""

    verb: str
    obj: str | None = None
    liquid: str | None = None

    def __str__(self) -> str:
        return " ".join(p for p in (self.verb, self.obj, self.liquid) if p)


def key(name: str) -> str:
    """Comparison key of an object name: lower case, no spaces, underscores or hyphens."""
    return re.sub(r"[\s_\-]+", "", name).lower()


def parse_step(text: str) -> Step:
    """Parse one step.

    Raises:
        StepError: Unknown verb, missing or extra arguments, unknown liquid.
    """
    words = [w for w in _SPLIT.split(text.strip()) if w]
    if not words:
        raise StepError("empty step")
    head = words[0].lower()
    if head == "turn" and len(words) > 1 and words[1].lower() in ("on", "off"):
        head, words = f"turn_{words[1].lower()}", [f"turn_{words[1].lower()}", *words[2:]]
    verb = _VERBS.get(head.replace("-", "_"))
    if verb is None:
        raise StepError(f"unknown action {words[0]!r}")
    takes_object, takes_liquid = ACTIONS[verb]
    rest = words[1:]
    liquid = None
    if takes_liquid:
        if not rest or rest[-1].lower() not in LIQUIDS:
            raise StepError(f"{verb} needs a liquid ({', '.join(LIQUIDS)}) after the object: {text!r}")
        liquid = rest.pop().lower()
    if not takes_object:
        # "pour" and "drop" act on the held object; a trailing word is tolerated (the dataset
        # writes "pour Mug" once) but ignored.
        return Step(verb)
    if not rest:
        raise StepError(f"{verb} needs an object: {text!r}")
    return Step(verb, " ".join(rest), liquid)
