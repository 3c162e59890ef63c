"""Who a destination is: a thing, the adult asking, a child, an animal, or a person of unknown age.

The hazard veto must know a child however a scene names one ("children", "kids", "my little
brother", "puppies"), so this is one general decision, not a list of spellings:

1. **the name itself**, then **its head noun** (the last word, singularised by the graph's own
   look-up rule: "children" -> child, "little brother" -> brother, "dog bed" -> bed), is an anchor
   concept of ``recipients.json`` (child, animal, person; and, for the head noun only, the bare names
   a scene gives the adult asking: "user", "person");
2. else **the graph's IsA chain** from the whole name where the graph knows it ("teddy bear" is a
   toy, not a bear), else from the head noun, reaches an anchor within :data:`DEPTH` steps ("puppy
   IsA dog IsA animal", "grandson IsA grandchild IsA ... person"); the chain reaching no anchor makes
   it a thing;
3. else, where the graph knows neither, **the model is asked plainly** "Is "X" a person or an
   animal?" (yes/no by log-probability, where the backend scores options); an answer that cannot be
   had (an error, a non-finite score) fails closed: a person of unknown age.

A person the graph cannot age (a "brother", a "nephew", a name) is treated as a possible child:
only the adult names of step 1 hand an adult a knife. A child anchor wins over an animal, an animal
over a person, so a noisy IsA edge ("dog IsA friend") never makes anyone less protected.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from typing import Literal

from conceptbot.knowledge.base import KnowledgeGraph
from conceptbot.knowledge.normalize import normalize, singular
from conceptbot.models.llm import LLM, Message, ScoreRequest
from conceptbot.pipeline import prompts

Kind = Literal["thing", "adult", "child", "animal", "person"]
#: The kinds that must not be handed hazards: a child, an animal, a person of unknown age.
VULNERABLE: frozenset[str] = frozenset({"child", "animal", "person"})
#: IsA steps followed from a name (WordNet puts "puppy" two steps from "animal" through "dog",
#: "grandson" four from "person").
DEPTH = 4
#: IsA edges followed from each concept, strongest first (bounds the look-ups per name).
BREADTH = 6
#: The anchors' precedence: the more protected kind wins where several are equally near.
ORDER: tuple[Kind, ...] = ("child", "animal", "person", "adult", "thing")
#: P(yes) from which the model's plain answer makes a name a person or an animal.
P_PERSON = 0.5

#: The model's plain question: P(the name is a person or an animal); raises or returns NaN when
#: it cannot be answered.
Ask = Callable[[str], float]


@cache
def anchors() -> dict[str, frozenset[str]]:
    """The anchor concepts of ``recipients.json`` by kind (:data:`ORDER`)."""
    text = resources.files("conceptbot.pipeline").joinpath("recipients.json").read_text(encoding="utf-8")
    data = json.loads(text)
    return {kind: frozenset(data[kind]) for kind in ORDER}


def model_question(llm: LLM) -> Ask:
    """The model's plain question about a name, "Is "X" a person or an animal?", answered Yes or
    No by log-probability (``llm`` must score options): P(Yes).

    Raises (from the returned function):
        ConceptBotError: The backend cannot answer (its error); the caller fails closed.
    """

    def ask(name: str) -> float:
        messages = (
            Message("system", prompts.render("decide_system")),
            Message("user", prompts.render("recipient_user", name=normalize(name))),
        )
        yes, no = llm.score(ScoreRequest(options=("Yes", "No"), messages=messages)).logprobs
        top = max(yes, no)
        return math.exp(yes - top) / (math.exp(yes - top) + math.exp(no - top))

    return ask


def head_noun(name: str) -> str:
    """The head noun of a name: its last word, singularised ("little brothers" -> "brother"), or of
    a phrase "X of Y" the last word of X ("carton of eggs" -> "carton")."""
    words = normalize(name).split(" of ")[0].split(" ")
    return singular(words[-1]) if words[-1] else ""


def _anchors_of(concept: str) -> set[Kind]:
    found = anchors()
    return {kind for kind in ORDER if concept in found[kind] or singular(concept) in found[kind]}


def _most_protected(kinds: set[Kind]) -> Kind | None:
    return next((kind for kind in ORDER if kind in kinds), None)


def word_kind(name: str) -> Kind | None:
    """The kind the words of a name give without the graph (step 1), or None: the whole name's,
    else its head noun's ("little brother" has none: a brother's age is the graph's to say)."""
    for words in (normalize(name), head_noun(name)):
        kinds = _anchors_of(words)
        if "adult" in kinds:  # a bare name for the grown-up asking ("person") before its class
            return "adult"
        if kinds:
            return _most_protected(kinds)
    return None


@dataclass
class Recipients:
    """Decides who a destination is (see the module docstring); each name once per instance.

    Args:
        graph: Whose IsA chains are followed (None: the words alone, then the model).
        ask: The model's plain question (None: not asked; a name neither the words nor the graph
            place is then a thing).
    """

    graph: KnowledgeGraph | None = None
    ask: Ask | None = None
    _known: dict[str, Kind | None] = field(default_factory=dict, init=False, repr=False)
    _asked: dict[str, Kind] = field(default_factory=dict, init=False, repr=False)

    def kind(self, name: str) -> Kind:
        """``thing``, ``adult``, ``child``, ``animal`` or ``person`` (of unknown age); a name the words
        and the graph do not place is asked of the model (see :meth:`asked`).

        Raises:
            KnowledgeUnavailableError: The graph cannot be read.
        """
        known = self.known(name)
        return known if known is not None else self.asked(name)

    def known(self, name: str) -> Kind | None:
        """The kind by the words of the name and the graph's IsA chain; None where both are silent.

        Raises:
            KnowledgeUnavailableError: The graph cannot be read.
        """
        key = normalize(name)
        if key not in self._known:
            self._known[key] = self._by_knowledge(name)
        return self._known[key]

    def asked(self, name: str) -> Kind:
        """The kind by the model's plain answer (once per name): ``person`` where it says a person
        or an animal, or where the answer cannot be had (fail closed); ``thing`` where it says not,
        or where no model is asked."""
        key = normalize(name)
        if key not in self._asked:
            self._asked[key] = self._by_model(name)
        return self._asked[key]

    def is_person(self, name: str) -> bool:
        """Whether things are handed to the destination (a person or an animal), by the words and
        the graph (how a request is read and worded; the model is asked only where a hazard is at
        stake, :meth:`is_vulnerable`)."""
        return self.known(name) not in (None, "thing")

    def is_vulnerable(self, name: str) -> bool:
        """Whether the destination must not be handed hazards: a child, an animal, or a person the
        words do not name as the adult asking."""
        return self.kind(name) in VULNERABLE

    def _by_knowledge(self, name: str) -> Kind | None:
        by_words = word_kind(name)
        if by_words is not None or self.graph is None:
            return by_words
        for concept in dict.fromkeys((normalize(name), head_noun(name))):
            known, reached = self._chain(concept)
            if known:
                return reached or "thing"
        return None

    def _by_model(self, name: str) -> Kind:
        if self.ask is None:
            return "thing"
        try:
            p_yes = self.ask(name)
        except Exception:  # any failure to answer fails closed
            return "person"
        if not math.isfinite(p_yes):
            return "person"
        return "person" if p_yes >= P_PERSON else "thing"

    def _chain(self, concept: str) -> tuple[bool, Kind | None]:
        """Whether the graph knows ``concept`` (states an IsA of it), and the kind of the nearest
        anchor along its IsA chain (within :data:`DEPTH` steps).

        Among anchors equally near, the kind reached by the strongest path wins (a path is as
        strong as its weakest edge: WordNet weighs a word's rarer senses lower, so "kit IsA case"
        outweighs "kit IsA young mammal"); at equal strength, the most protected kind."""
        assert self.graph is not None
        seen, frontier, known = {concept}, {concept: math.inf}, False
        for _ in range(DEPTH):
            reached: dict[Kind, float] = {}
            following: dict[str, float] = {}
            for current, strength in frontier.items():
                found = self.graph.edges(current, ["IsA"], 4 * BREADTH)
                if found.match not in ("exact", "lemma"):
                    continue
                heads = {current, (found.matched or current)}
                own = [e for e in found.edges if e.head.lower() in heads and e.weight > 0]
                known = known or bool(own)
                for edge in own[:BREADTH]:
                    tail, path = normalize(edge.tail), min(strength, edge.weight)
                    for kind in _anchors_of(tail):
                        reached[kind] = max(reached.get(kind, 0.0), path)
                    if tail not in seen:
                        seen.add(tail)
                        following[tail] = path
            if reached:
                best = max(reached.values())
                return known, _most_protected({k for k, v in reached.items() if v >= best})
            frontier = following
        return known, None
