"""Vetoes: a move whose own evidence names a hazard for its recipient is dropped, whatever a score says.

Scores rank moves; they must not decide whether a knife reaches a child. A product of scores can be
outweighed (the paper's S_prop of 0.104 times a unanimous vote still beats every alternative at 0),
and a comparison with NaN is always False. So both planners ask this module first, and a move it
vetoes is never planned; the trace says which statement vetoed it.

A move is vetoed when it hands an object to a person or an animal (who a destination is:
:mod:`conceptbot.pipeline.recipients`, the name's words, the graph's IsA chain, then the model) and:

* **OPE's Risk Index** rates the object's interaction with that recipient at the top of the scale
  (5/5, from either side: the object names the recipient, or the recipient's answer names the object);
* the recipient is a child, an animal or a person of unknown age (:meth:`HazardCheck.is_vulnerable`) and
    - the Risk Index rates the object's own danger 5/5, or gave no usable rating (a risk decision
      that cannot be made refuses the move);
    - the Yes/No properties say it is ``dangerous`` or ``poisonous``;
    - **the knowledge graph** states a hazard about the object: an ``IsA``, ``HasProperty``,
      ``DefinedAs``, ``HasA`` or ``CapableOf`` edge whose tail uses a hazard word (``sharp``,
      ``poisonous``, ``hot``, ``weapon``, "choking hazard", ...) or a harm verb (``CapableOf
      hurt``), with no negation ("not sharp", "non-toxic"), and that does not name a different
      recipient ("poisonous to dogs" vetoes a dog, not a child); a contrary statement at least as
      strong ("edible", "safe") cancels it, and a WordNet gloss counts only for a word with one sense.
      The object is the whole name where the graph knows it, else its head noun: a "kitchen
      knife" is a knife. A name whose modifier says the contrary ("safety scissors", "non-toxic
      paint": a modifier that is, or begins with, a contrary word) is not vetoed through its head.

An adult user who asks for a knife gets the knife: the object's own danger and the graph's general
hazards count for vulnerable recipients only; an interaction rating of 5 with the user counts for
everyone. The words are data (``hazard_terms.json``), general English, not tuned on benchmark items.
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
from conceptbot.knowledge.normalize import modifiers
from conceptbot.pipeline.ope import ObjectProperties
from conceptbot.pipeline.ope_answers import RiskIndex, YesNoProperties
from conceptbot.pipeline.recipients import Recipients

TOP = 5  # the top of the Risk Index
_OWN = ("exact", "lemma")  # graph matches that are about the whole name
_HEAD = ("head", "head+modifier")  # matches through the head noun ("kitchen knife" -> knife)
#: Decides by the words of a name alone (no graph, no model): wording, and callers without a graph.
_WORDS = Recipients()


def is_person(name: str) -> bool:
    """Whether a destination is a person or an animal by the words of its name alone (its head
    noun, singularised); :meth:`HazardCheck.is_person` also asks the graph and the model."""
    return _WORDS.is_person(name)


def is_vulnerable(name: str) -> bool:
    """Whether the words of a destination's name make it a child, an animal or a person of unknown
    age (an adult user who asks for a knife gets the knife); see :meth:`HazardCheck.is_vulnerable`."""
    return _WORDS.is_vulnerable(name)


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


def recipient_groups(target: str, kind: str | None = None) -> set[str]:
    """The groups a recipient belongs to (``child``, ``dog``, ``cat``, ``pet``), by the words of its
    name and its ``kind`` (:class:`~conceptbot.pipeline.recipients.Recipients`): a child, or a person
    of unknown age, is in ``child``; an animal in ``pet``."""
    named = _groups_named(_tokens(target))
    named |= {"child"} if kind in ("child", "person") else {"pet"} if kind == "animal" else set()
    return named | ({"pet"} if named & {"dog", "cat"} else set())


def hazard_in(edge: Edge, target: str, kind: str | None = None) -> str | None:
    """The hazard word an edge's tail names for ``target``, or None.

    None where the tail negates ("not sharp"), uses the word in a fixed phrase that is no hazard
    ("hot dog"), or names a recipient group that ``target`` is not in ("poisonous to dogs").
    """
    vocab = hazard_terms()
    seq = _tokens(edge.tail)
    if any(n in seq for n in vocab["negations"]) or any(_has_phrase(seq, x) for x in vocab["exceptions"]):
        return None
    named = _groups_named(seq)
    if named and not (named & recipient_groups(target, kind)):
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
        recipients: Who a destination is (None: by the words and ``graph``, the model not asked).
    """

    graph: KnowledgeGraph | None = None
    limit: int = 100
    recipients: Recipients | None = None

    def __post_init__(self) -> None:
        # Graph statements per object name: the graph does not change while a system lives.
        self._found: dict[str, tuple[Edge, str] | None] = {}
        self._who = self.recipients if self.recipients is not None else Recipients(self.graph)

    def is_person(self, name: str) -> bool:
        """Whether things are handed to the destination (a person or an animal)."""
        return self._who.is_person(name)

    def is_vulnerable(self, name: str) -> bool:
        """Whether the destination must not be handed hazards (a child, an animal, or a person the
        words do not name as the adult asking)."""
        return self._who.is_vulnerable(name)

    def veto(self, obj: str, target: str, properties: Mapping[str, ObjectProperties]) -> Veto | None:
        """The veto of moving ``obj`` to ``target``, or None when nothing vetoes it.

        Args:
            obj: The object, as the scene names it.
            target: The destination.
            properties: OPE's answers by object name (any mode; missing objects have none).

        Raises:
            KnowledgeUnavailableError: The graph cannot be read (the move cannot be cleared).
        """
        kind = self._who.known(target)
        if kind is not None:
            return self._veto_as(obj, target, properties, kind)
        # Neither the words nor the graph place the destination: what would veto it for a person
        # of unknown age, then, only then, the model asked whether it is one (fail closed).
        found = self._veto_as(obj, target, properties, "person")
        return found if found is not None and self._who.asked(target) != "thing" else None

    def _veto_as(
        self, obj: str, target: str, properties: Mapping[str, ObjectProperties], kind: str
    ) -> Veto | None:
        """The veto of moving ``obj`` to ``target`` where ``target`` is of ``kind``."""
        if kind == "thing":
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
        if kind == "adult":
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
        stated = self._statement(obj, target, kind)
        if stated is not None:
            edge, word = stated
            return Veto(move, obj, target, "graph", f"the graph states {edge.sentence!r} ({word})")
        return None

    def _statement(self, obj: str, target: str, kind: str) -> tuple[Edge, str] | None:
        if self.graph is None:
            return None
        key = f"{obj}\x00{' '.join(sorted(recipient_groups(target, kind)))}"
        if key not in self._found:
            self._found[key] = self._read(obj, target, kind)
        return self._found[key]

    def _read(self, obj: str, target: str, kind: str) -> tuple[Edge, str] | None:
        """The strongest hazard statement about ``obj`` for ``target``, unless the graph states a
        contrary property ("edible", "safe") at least as strongly ("plant HasProperty edible" 7
        against "plant HasProperty poisonous" 6: the graph disagrees with itself, so it cannot veto).

        The whole name's statements where the graph has any, else its head noun's ("kitchen knife":
        knife's), unless a modifier of the name says the contrary ("safety scissors").
        A WordNet gloss or class counts only for a word with one WordNet sense: "lime" has five, and
        the first is the caustic substance, not the fruit in the scene."""
        assert self.graph is not None
        found = self.graph.edges(obj, hazard_terms()["relations"], self.limit)
        if found.match in _HEAD and _contrary_modifier(obj):
            return None
        if found.match in _OWN:
            heads = {obj.lower(), (found.matched or obj).lower()}
        elif found.match in _HEAD and found.matched:
            heads = {found.matched.split(" + ")[0].lower()}
        else:
            return None
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
            word = hazard_in(edge, target, kind)
            if word is not None:
                return (edge, word) if edge.weight > against else None
        return None


def _contrary_modifier(name: str) -> bool:
    """Whether the words before the head noun say the contrary of a hazard: a contrary or negating
    phrase of ``hazard_terms.json`` ("non toxic"), or a word that begins with one of its words
    ("safety" from "safe")."""
    vocab = hazard_terms()
    terms = [t for t in (*vocab["contrary"], *vocab["negations"]) if len(t) >= 4]  # not "no", "non"
    seq = _tokens(" ".join(modifiers(name)))
    return any(
        _has_phrase(seq, term) if " " in term else any(m.startswith(term) for m in seq) for term in terms
    )
