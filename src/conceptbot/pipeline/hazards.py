"""Vetoes: a move whose own evidence names a hazard for its recipient is dropped, whatever a score says.

Scores rank moves; they must not decide whether a knife reaches a child. A product of scores can be
outweighed (the paper's S_prop of 0.104 times a unanimous vote still beats every alternative at 0),
and a comparison with NaN is always False. So both planners ask this module first, and a move it
vetoes is never planned; the trace says which statement vetoed it.

A move is vetoed when it hands an object to a person or an animal (:func:`is_person`) and:

* **OPE's Risk Index** rates the object's interaction with that recipient at the top of the scale
  (5/5, from either side: the object names the recipient, or the recipient's answer names the object);
* the recipient is a child or an animal (:func:`is_vulnerable`) and
    - the Risk Index rates the object's own danger 5/5, or gave no usable rating (a risk decision
      that cannot be made refuses the move);
    - the Yes/No properties say it is ``dangerous`` or ``poisonous``;
    - **the knowledge graph** states a hazard about the object itself: an ``IsA``, ``HasProperty``,
      ``DefinedAs``, ``HasA`` or ``CapableOf`` edge with the object (exactly, or its lemma) as head
      whose tail uses a hazard word (``sharp``, ``poisonous``, ``hot``, ``weapon``, "choking
      hazard", ...) or a harm verb (``CapableOf hurt``), with no negation ("not sharp", "non-toxic"),
      and that does not name a different recipient ("poisonous to dogs" vetoes a dog, not a child);
      a contrary statement at least as strong ("edible", "safe") cancels it, and a WordNet gloss
      counts only for a word with one sense.

An adult user who asks for a knife gets the knife: the object's own danger and the graph's general
hazards count for children and animals only; an interaction rating of 5 with the user counts for
everyone. The words are data (``hazard_terms.json``), general English, not tuned on benchmark items.
A graph concept matched only through a word of the name ("safety scissors" via "scissors") is not
evidence about the object, so it cannot veto.
"""

from __future__ import annotations

import json
import re
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache
from importlib import resources
from typing import Any

from conceptbot.core.plan import PickAndPlace, format_action
from conceptbot.core.trace import Veto
from conceptbot.knowledge.base import Edge, KnowledgeGraph
from conceptbot.pipeline.ope import ObjectProperties
from conceptbot.pipeline.ope_answers import RiskIndex, YesNoProperties
from conceptbot.pipeline.vocabulary import PERSON_WORDS

TOP = 5  # the top of the Risk Index
ANIMALS = ("dog", "cat", "puppy", "kitten", "pet")
_ADULT = ("user", "person", "human", "man", "woman")
_MORE_PEOPLE = ("toddler", "man", "woman", "girl", "boy", "infant")
_EXACT = ("exact", "lemma")  # graph matches that are about the object itself


def is_person(name: str) -> bool:
    """Whether a destination is a person or an animal (things are handed to it)."""
    return any(w in PERSON_WORDS or w in _MORE_PEOPLE or w in ANIMALS for w in name.lower().split())


def is_vulnerable(name: str) -> bool:
    """Whether a destination is someone who must not be handed dangerous things: a child or an
    animal (an adult user who asks for a knife gets the knife)."""
    return is_person(name) and not any(w in _ADULT for w in name.lower().split())


@cache
def hazard_terms() -> dict[str, Any]:
    """The vocabulary of ``hazard_terms.json``."""
    text = resources.files("conceptbot.pipeline").joinpath("hazard_terms.json").read_text(encoding="utf-8")
    return json.loads(text)


def _tokens(text: str) -> list[str]:
    return re.findall(r"[a-z][a-z']*", text.lower().replace("-", " - "))


def _has_phrase(seq: list[str], phrase: str) -> bool:
    key = phrase.split()
    return any(seq[i : i + len(key)] == key for i in range(len(seq) - len(key) + 1))


def _groups_named(seq: list[str]) -> set[str]:
    groups: dict[str, list[str]] = hazard_terms()["groups"]
    return {group for group, names in groups.items() if any(n in seq for n in names)}


def recipient_groups(target: str) -> set[str]:
    """The groups a recipient belongs to (``child``, ``dog``, ``cat``, ``pet``)."""
    named = _groups_named(_tokens(target))
    return named | ({"pet"} if named & {"dog", "cat"} else set())


def hazard_in(edge: Edge, target: str) -> str | None:
    """The hazard word an edge's tail names for ``target``, or None.

    None where the tail negates ("not sharp"), uses the word in a fixed phrase that is no hazard
    ("hot dog"), or names a recipient group that ``target`` is not in ("poisonous to dogs").
    """
    vocab = hazard_terms()
    seq = _tokens(edge.tail)
    if any(n in seq for n in vocab["negations"]) or any(_has_phrase(seq, x) for x in vocab["exceptions"]):
        return None
    named = _groups_named(seq)
    if named and not (named & recipient_groups(target)):
        return None
    words = vocab["harm_verbs"] if edge.relation == "CapableOf" else vocab["terms"]
    return next((w for w in words if _has_phrase(seq, w)), None)


def _top_score(answer: RiskIndex, other: str) -> int:
    """The highest interaction score an answer gives ``other`` (a model may list a partner twice)."""
    return max((p.score for p in answer.dangerous_with if p.object == other), default=0)


@dataclass
class HazardCheck:
    """Decides vetoes (see the module docstring).

    Args:
        graph: The knowledge graph whose statements about an object can veto handing it over (None:
            the no-graph ablation; OPE alone decides).
        limit: Edges read per object.
    """

    graph: KnowledgeGraph | None = None
    limit: int = 100

    def __post_init__(self) -> None:
        # Graph statements per object name: the graph does not change while a system lives.
        self._found: dict[str, tuple[Edge, str] | None] = {}

    def veto(self, obj: str, target: str, properties: Mapping[str, ObjectProperties]) -> Veto | None:
        """The veto of moving ``obj`` to ``target``, or None when nothing vetoes it.

        Args:
            obj: The object, as the scene names it.
            target: The destination.
            properties: OPE's answers by object name (any mode; missing objects have none).

        Raises:
            KnowledgeUnavailableError: The graph cannot be read (the move cannot be cleared).
        """
        if not is_person(target):
            return None
        move = format_action(PickAndPlace(obj, target))
        found = properties.get(obj)
        partner = properties.get(target)
        answer = found.answer if found is not None else None
        other = partner.answer if partner is not None else None
        if isinstance(answer, RiskIndex) and _top_score(answer, target) >= TOP:
            return Veto(move, obj, target, "ope", f"OPE rates the {obj} {TOP}/5 dangerous with the {target}")
        if isinstance(other, RiskIndex) and _top_score(other, obj) >= TOP:
            return Veto(move, obj, target, "ope", f"OPE rates the {target} {TOP}/5 dangerous with the {obj}")
        if not is_vulnerable(target):
            return None
        if isinstance(answer, RiskIndex):
            if answer.danger is None:
                return Veto(move, obj, target, "ope", f"OPE gave no usable danger rating for the {obj}")
            if answer.danger >= TOP:
                return Veto(move, obj, target, "ope", f"OPE rates the {obj} {TOP}/5 dangerous")
        if isinstance(answer, YesNoProperties):
            held = [p for p in ("dangerous", "poisonous") if answer.has(p)]
            if held:
                return Veto(move, obj, target, "ope", f"OPE says the {obj} is {' and '.join(held)}")
        stated = self._statement(obj, target)
        if stated is not None:
            edge, word = stated
            return Veto(move, obj, target, "graph", f"the graph states {edge.sentence!r} ({word})")
        return None

    def _statement(self, obj: str, target: str) -> tuple[Edge, str] | None:
        if self.graph is None:
            return None
        key = f"{obj}\x00{' '.join(sorted(recipient_groups(target)))}"
        if key not in self._found:
            self._found[key] = self._read(obj, target)
        return self._found[key]

    def _read(self, obj: str, target: str) -> tuple[Edge, str] | None:
        """The strongest hazard statement about ``obj`` for ``target``, unless the graph states a
        contrary property ("edible", "safe") at least as strongly ("plant HasProperty edible" 7
        against "plant HasProperty poisonous" 6: the graph disagrees with itself, so it cannot veto).

        A WordNet gloss or class counts only for a word with one WordNet sense: "lime" has five, and
        the first is the caustic substance, not the fruit in the scene."""
        assert self.graph is not None
        found = self.graph.edges(obj, hazard_terms()["relations"], self.limit)
        if found.match not in _EXACT:
            return None
        heads = {obj.lower(), (found.matched or obj).lower()}
        own = [e for e in found.edges if e.head.lower() in heads and e.weight > 0]
        senses = sum(1 for e in own if e.source == "wordnet" and e.relation == "DefinedAs")
        contrary = set(hazard_terms()["contrary"])
        against = max(
            (e.weight for e in own if e.relation == "HasProperty" and " ".join(_tokens(e.tail)) in contrary),
            default=0.0,
        )
        for edge in own:  # strongest first
            if edge.source == "wordnet" and senses > 1:
                continue
            word = hazard_in(edge, target)
            if word is not None:
                return (edge, word) if edge.weight > against else None
        return None
