"""Graph evidence: what the knowledge graph states about one object and one criterion, read without
the model, as features that :mod:`.combine` weighs beside the model's answer (a small model given
the facts as prompt text often ignores them).

The criterion's words (and their ``evidence_terms.json`` group; the opposite group counts against)
are looked for in statements about the object, its ``IsA`` kinds and its name; a negated term counts
the other way. Each feature is 0, 0.5 (an ambiguous gloss) or 1, with the statements that set it.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from typing import Any

from conceptbot.knowledge.base import Edge, KnowledgeGraph
from conceptbot.knowledge.normalize import singular

RELATIONS = ["DefinedAs", "IsA", "HasProperty", "MadeOf", "UsedFor", "CapableOf", "Synonym"]
_STATING = ("DefinedAs", "IsA", "HasProperty", "MadeOf", "UsedFor", "CapableOf")
_EXACT = ("exact", "lemma")
_HEAD = ("head", "head+modifier")
DEPTH = 3  # IsA steps up from the object
PER_LEVEL = 12  # parents followed per step, strongest first
WINDOW = 3  # words before a term that a negation reaches
AMBIGUOUS = 0.5  # the weight of a gloss of a word with several WordNet senses
CONTAINER = "container"  # the graph's kind whose members' names say what they hold ("milk carton")
# Kinds of container whose names say what they are for, not what they hold ("salad bowl").
TABLEWARE = frozenset({"dish", "crockery", "tableware", "cooking utensil", "kitchen utensil", "drink vessel"})
_INGREDIENT = re.compile(r"^(?:an?\s+)?ingredients?\s+(?:of|for|in)\s+(?:an?\s+|the\s+)?(.+)$")

#: The features, in the order :meth:`Evidence.vector` gives them.
FEATURES = (
    "own_yes",
    "own_no",
    "kind_yes",
    "kind_no",
    "name_yes",
    "name_no",
    "dish_yes",
    "dish_no",
    "is_dish",
    "is_material",
    "is_several",
    "materials_named",
    "is_poison",
    "is_food",
    "is_safe",
)
#: The features that need no graph (the no-graph ablation keeps these).
GRAPH_FREE = (
    "name_yes", "name_no", "is_dish", "is_material", "is_several", "materials_named", "is_poison", "is_food",
    "is_safe",
)  # fmt: skip


@cache
def terms_vocabulary() -> dict[str, Any]:
    """The vocabulary of ``evidence_terms.json``."""
    text = resources.files("conceptbot.pipeline").joinpath("evidence_terms.json").read_text(encoding="utf-8")
    return json.loads(text)


def words_of(text: str) -> list[str]:
    """Lower-case words, singular, hyphens kept inside words ("non-toxic")."""
    return [singular(w) for w in re.findall(r"[a-z][a-z'-]*", text.lower())]


def _phrase_at(seq: Sequence[str], phrase: Sequence[str]) -> list[int]:
    n = len(phrase)
    return [i for i in range(len(seq) - n + 1) if list(seq[i : i + n]) == list(phrase)]


@dataclass(frozen=True)
class Terms:
    """What to look for: phrases (as word lists) that state the criterion, and those against it."""

    yes: tuple[tuple[str, ...], ...]
    no: tuple[tuple[str, ...], ...]
    dish: str = ""
    material: bool = False
    several: bool = False
    groups: tuple[str, ...] = ()


def _phrases(items: Iterable[str]) -> tuple[tuple[str, ...], ...]:
    return tuple(dict.fromkeys(tuple(words_of(i)) for i in items if words_of(i)))


def criterion_terms(criterion: str, graph: KnowledgeGraph | None = None) -> Terms:
    """The terms for and against ``criterion`` (see the module docstring)."""
    vocab = terms_vocabulary()
    text = criterion.lower().strip()
    dish = _INGREDIENT.match(text)
    if dish:
        return Terms((), (), dish.group(1).strip(" ."))
    forms = {**vocab["material_forms"], **vocab["spellings"]}
    seq = [forms.get(w, w) for w in words_of(text)]
    if any(_phrase_at(seq, words_of(p)) for p in vocab["several_materials"]):
        return Terms((), (), several=True)
    yes: list[str] = []
    no: list[str] = []
    used = [False] * len(seq)
    groups = vocab["groups"]
    grouped = False
    found_groups: list[str] = []
    # Longest phrases first: "safe to eat" is food, not "safe".
    phrases = sorted(
        ((tuple(words_of(w)), name) for name, g in groups.items() for w in g["words"]),
        key=lambda item: -len(item[0]),
    )
    for phrase, name in phrases:
        for at in _phrase_at(seq, phrase):
            if not any(used[at : at + len(phrase)]):
                used[at : at + len(phrase)] = [True] * len(phrase)
                grouped = True
                found_groups.append(name)
                yes += groups[name]["words"]
                no += groups[groups[name]["opposite"]]["words"]
    ignore = set(vocab["ignore"])
    rest = [w for w, u in zip(seq, used, strict=True) if not u and w not in ignore and len(w) > 2]
    materials = set(vocab["materials"])
    families: dict[str, list[str]] = vocab["material_families"]
    named = [w for w in rest if w in materials or w in families]
    # Beside a property the other words say whom or what it is about ("poisonous to dogs"), so a
    # "dog ball" is no statement of it; alone they are the criterion ("a fruit").
    yes += named if grouped else rest
    if named:
        # A family's members state it ("steel" is a metal); a member states itself only.
        same = set(named) | {m for w in named for m in families.get(w, [])}
        yes += sorted(same - set(yes))
        no += [m for m in sorted(materials | set(families)) if m not in same and forms.get(m, m) not in same]
    if graph is not None and len(rest) == 1 and not grouped:
        # Synonyms of a word with one WordNet sense only: another sense's synonyms are other things.
        found = graph.edges(rest[0], ["Synonym", "DefinedAs"], 40)
        senses = sum(1 for e in found.edges if e.relation == "DefinedAs" and e.head.lower() == rest[0])
        if found.match in _EXACT and senses == 1:
            synonyms = [e for e in found.edges if e.relation == "Synonym"]
            yes += [e.head if e.tail.lower() == rest[0] else e.tail for e in synonyms]
    yes_p = _phrases(yes)
    against = tuple(p for p in _phrases(no) if p not in yes_p)
    return Terms(yes_p, against, material=bool(named), groups=tuple(dict.fromkeys(found_groups)))


def _negated(seq: Sequence[str], at: int) -> bool:
    vocab = terms_vocabulary()
    return any(w in vocab["negations"] for w in seq[max(0, at - WINDOW) : at])


def stated(text: str, terms: Terms) -> tuple[bool, bool]:
    """Whether ``text`` states the criterion (yes) and the contrary (no); a negated term ("non-toxic")
    counts the other way."""
    vocab = terms_vocabulary()
    forms = {**vocab["material_forms"], **vocab["spellings"]}
    seq = [forms.get(w, w) for w in words_of(text)]  # "wooden" states wood
    prefixes = terms_vocabulary()["negating_prefixes"]
    known = {p[0] for p in (*terms.yes, *terms.no) if len(p) == 1}
    yes = no = False
    for polarity, phrases in ((True, terms.yes), (False, terms.no)):
        for phrase in phrases:
            hits = _phrase_at(seq, phrase)
            for at in hits:
                says = polarity != _negated(seq, at)
                yes, no = (True, no) if says else (yes, True)
            if len(phrase) == 1:
                for word in (w for w in seq if w not in known):
                    base = next((word[len(p) :] for p in prefixes if word.startswith(p)), None)
                    if base and base.strip("-") == phrase[0]:
                        yes, no = (yes, True) if polarity else (True, no)
    return yes, no


@dataclass(frozen=True)
class Evidence:
    """What the graph and the object's name state about one object and one criterion.

    Attributes:
        object: The object.
        criterion: The criterion, in the request's words.
        features: Feature name -> value (0, 0.5 or 1), for every name in :data:`FEATURES`.
        statements: The statements that set a feature, as "feature: sentence".
    """

    object: str
    criterion: str
    features: dict[str, float] = field(default_factory=dict)
    statements: tuple[str, ...] = ()

    def vector(self, names: Sequence[str] = FEATURES) -> list[float]:
        """The features in ``names`` order."""
        return [self.features.get(n, 0.0) for n in names]

    def to_dict(self) -> dict[str, Any]:
        """JSON form for the trace: the features that are set, and the statements."""
        return {
            "features": {k: v for k, v in self.features.items() if v},
            "statements": list(self.statements),
        }


class GraphEvidence:
    """Reads :class:`Evidence` from a knowledge graph (None: the object's name only).

    Args:
        graph: The knowledge graph, or None for the no-graph ablation.
    """

    def __init__(self, graph: KnowledgeGraph | None) -> None:
        self.graph = graph
        # The graph does not change while a system lives: answers are cached per concept and criterion.
        self._edges: dict[str, tuple[str, str | None, tuple[Edge, ...]]] = {}
        self._terms: dict[str, Terms] = {}

    def _lookup(self, concept: str) -> tuple[str, str | None, tuple[Edge, ...]]:
        assert self.graph is not None
        if concept not in self._edges:
            found = self.graph.edges(concept, RELATIONS, 100)
            self._edges[concept] = (found.match, found.matched, found.edges)
        return self._edges[concept]

    def _own(self, concept: str, kinds: Sequence[str] = _EXACT) -> tuple[list[Edge], int]:
        """Edges stating something about ``concept`` itself, and its number of WordNet senses."""
        match, matched, edges = self._lookup(concept)
        if match not in kinds:
            return [], 0
        heads = {concept.lower(), (matched or concept).split(" + ")[0].lower()}
        own = [e for e in edges if e.head.lower() in heads and e.relation in _STATING and e.weight > 0]
        senses = sum(1 for e in own if e.source == "wordnet" and e.relation == "DefinedAs")
        return own, senses

    def _ancestors(self, concept: str) -> list[str]:
        """IsA ancestors up to :data:`DEPTH` steps, strongest first, :data:`PER_LEVEL` per step."""
        level, seen, out = [concept.lower()], {concept.lower()}, []
        for _ in range(DEPTH):
            parents: dict[str, None] = {}
            for node in level:
                own, _ = self._own(node, (*_EXACT, *_HEAD) if node == concept.lower() else _EXACT)
                parents.update(dict.fromkeys(e.tail.lower() for e in own if e.relation == "IsA"))
            level = [p for p in parents if p not in seen][:PER_LEVEL]
            seen.update(level)
            out += level
            if not level:
                break
        return out

    def read(self, obj: str, criterion: str) -> Evidence:
        """The evidence about ``obj`` (as the scene names it) for ``criterion``."""
        if criterion not in self._terms:
            self._terms[criterion] = criterion_terms(criterion, self.graph)
        terms = self._terms[criterion]
        features = dict.fromkeys(FEATURES, 0.0)
        statements: list[str] = []

        def note(name: str, value: float, sentence: str) -> None:
            if value > features[name]:
                features[name] = value
                statements.append(f"{name}: {sentence}")

        features["is_dish"] = 1.0 if terms.dish else 0.0
        features["is_material"] = 1.0 if terms.material else 0.0
        features["is_several"] = 1.0 if terms.several else 0.0
        for group in ("poison", "food", "safe"):
            features[f"is_{group}"] = 1.0 if group in terms.groups else 0.0
        if terms.several:
            self._materials(obj, features, statements)
            return Evidence(obj, criterion, features, tuple(statements))
        if terms.dish:
            self._dish(obj, terms.dish, note)
            return Evidence(obj, criterion, features, tuple(statements))
        yes, no = stated(obj, terms)
        if yes:
            note("name_yes", 1.0, f"the name {obj!r}")
        if no:
            note("name_no", 1.0, f"the name {obj!r}")
        if self.graph is None:
            return Evidence(obj, criterion, features, tuple(statements))
        own, senses = self._own(obj)
        for edge in own:
            value = (
                AMBIGUOUS if edge.relation == "DefinedAs" and edge.source == "wordnet" and senses > 1 else 1.0
            )
            yes, no = stated(edge.tail, terms)
            if yes:
                note("own_yes", value, edge.sentence)
            if no:
                note("own_no", value, edge.sentence)
        kinds = self._ancestors(obj)
        match, matched, _ = self._lookup(obj)
        if match in _HEAD and matched:
            head_own, _ = self._own(matched.split(" + ")[0])
            for edge in head_own:
                yes, no = stated(edge.tail, terms)
                if yes:
                    note("kind_yes", 1.0, edge.sentence)
                if no:
                    note("kind_no", 1.0, edge.sentence)
        for kind in kinds:
            yes, no = stated(kind, terms)
            if yes:
                note("kind_yes", 1.0, f"{obj} is a kind of {kind}")
            if no:
                note("kind_no", 1.0, f"{obj} is a kind of {kind}")
            kind_own, kind_senses = self._own(kind)
            for edge in kind_own:
                if edge.relation not in ("DefinedAs", "HasProperty") or (
                    edge.source == "wordnet" and kind_senses > 1
                ):
                    continue
                yes, no = stated(edge.tail, terms)
                if yes:
                    note("kind_yes", AMBIGUOUS, edge.sentence)
                if no:
                    note("kind_no", AMBIGUOUS, edge.sentence)
        return Evidence(obj, criterion, features, tuple(statements))

    def _materials(self, obj: str, features: dict[str, float], statements: list[str]) -> None:
        """For "made of several materials": how many materials (0-3) the name, MadeOf and gloss name."""
        vocab = terms_vocabulary()
        known = set(vocab["materials"]) | set(vocab["material_families"])
        forms = {**vocab["material_forms"], **vocab["spellings"]}

        def named(text: str) -> set[str]:
            return {forms.get(w, w) for w in words_of(text)} & known

        found = named(obj)
        if self.graph is not None:
            own, senses = self._own(obj, (*_EXACT, *_HEAD))
            for edge in own:
                if edge.relation == "MadeOf" or (edge.relation == "DefinedAs" and senses <= 1):
                    new = named(edge.tail) - found
                    if new:
                        found |= new
                        statements.append(f"materials_named: {edge.sentence}")
        features["materials_named"] = float(min(len(found), 3))

    def _holds(self, head: str) -> bool:
        """Whether a name with this head noun says what it holds: a container ("carton"), not tableware."""
        kinds = set(self._ancestors(head))
        return CONTAINER in kinds and not kinds & TABLEWARE

    def _dish(self, obj: str, dish: str, note: Any) -> None:
        """Whether the dish's gloss or MadeOf edges name the object, its head, its contents ("milk carton"
        -> milk) or a parent; a sibling of the dish ("soy sauce" for a sauce) is no ingredient."""
        if self.graph is None:
            return
        own, _ = self._own(dish)
        stating = [e for e in own if e.relation in ("DefinedAs", "MadeOf")]
        if not stating:
            return
        name = words_of(obj)
        dish_kinds = set(self._ancestors(dish))
        sibling = len(name) > 1 and name[-2] != "of" and name[-1] in dish_kinds
        names = [tuple(name)] + ([(name[-1],)] if name and not sibling else [])
        if len(name) > 1 and "of" not in name and self._holds(name[-1]):
            names.append(tuple(name[:-1]))
        # A kind the dish shares says nothing ("sugar" IsA "food" for a salad).
        parents = [tuple(words_of(p)) for p in self._ancestors(obj)[:PER_LEVEL] if p not in dish_kinds]
        for edge in stating:
            seq = words_of(edge.tail)
            if any(_phrase_at(seq, n) for n in names):
                note("dish_yes", 1.0, edge.sentence)
                return
            if any(p and _phrase_at(seq, p) for p in parents):
                note("dish_yes", AMBIGUOUS, edge.sentence)
                return
        note("dish_no", 1.0, f"{stating[0].sentence} (does not name the {obj})")
