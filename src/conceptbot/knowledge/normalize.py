"""Concept normalisation and the multi-word fallback rule, shared by every KnowledgeGraph backend.

``normalize`` turns any object name into ConceptNet's readable form: lower case, underscores and
runs of spaces become one space, surrounding punctuation and leading articles go ("The Green
Hellebore" -> "green hellebore").

``lookup`` asks a backend for a name, trying in order (the first that has edges wins):

1. ``exact``  the normalised phrase ("ceramic bowl");
2. ``lemma``  the phrase with its last word singularised ("ceramic bowls" -> "ceramic bowl");
3. ``head``   the head noun, i.e. the last word, singularised ("ceramic bowl" -> "bowl"); the
              modifiers ("ceramic") then fill up to half of the limit with their own edges, so a
              material or colour is not lost (``head+modifier``); a multi-word modifier phrase is
              tried whole before its words ("death cap mushroom" -> "death cap", then "death");
4. ``modifier`` only the modifiers, when the head noun is unknown.

English compounds put the head noun last, which is why the last word is the head.

Words kept plural (``_KEEP``: "scissors", "tweezers", "tongs") are the concept themselves, so their
singular is not tried as another name. But the two offline sources name them differently: WordNet
by the word ("scissors"), ConceptNet 4's OMCS statements by a lemmatiser's singular ("scissor
UsedFor cut", "scissor HasProperty sharp"). So where the concept matched for such a word has only
WordNet's statements, OMCS's statements about its singular are added, named as the word; and where
the word has none at all, its singular is tried as a ``lemma``. A word that OMCS knows as written
("glasses", "jeans") keeps its own statements only: OMCS's "glass" mixes drinking glasses with
spectacles.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from dataclasses import replace

from conceptbot.knowledge.base import ConceptEdges, Edge

Fetch = Callable[[str, Sequence[str] | None, int], list[Edge]]
#: The source that names concepts by the word as written; the others' English is lemmatised.
WORD_SOURCE = "wordnet"

_ARTICLES = ("a ", "an ", "the ", "some ")
_IRREGULAR = {
    "knives": "knife",
    "leaves": "leaf",
    "loaves": "loaf",
    "halves": "half",
    "shelves": "shelf",
    "wolves": "wolf",
    "lives": "life",
    "wives": "wife",
    "mice": "mouse",
    "geese": "goose",
    "children": "child",
    "teeth": "tooth",
    "feet": "foot",
    "men": "man",
    "women": "woman",
    "people": "person",
    "dice": "die",
    "oxen": "ox",
    "cacti": "cactus",
    "fungi": "fungus",
}
# Words that look plural but are the concept itself.
_KEEP = {
    "scissors",
    "glasses",
    "pants",
    "jeans",
    "tongs",
    "pliers",
    "shorts",
    "trousers",
    "tweezers",
    "shears",
    "clippers",
    "pincers",
    "secateurs",
    "news",
    "series",
    "species",
    "chess",
    "glass",
    "grass",
    "gas",
    "bus",
    "lens",
    "dress",
    "class",
    "cross",
    "moss",
    "mass",
    "boss",
    "brass",
    "bass",
    "cactus",
    "octopus",
    "asparagus",
    "hummus",
    "couscous",
    "molasses",
    "citrus",
    "hibiscus",
    "lotus",
    "analysis",
    "crisis",
    "iris",
    "tennis",
    "always",
    "clothes",
    "binoculars",
    "headphones",
    "earphones",
    "goggles",
    "sunglasses",
    "oats",
}


def normalize(text: str) -> str:
    """Readable concept form: lower case, single spaces, no leading article or outer punctuation."""
    text = text.replace("_", " ").strip().lower()
    text = re.sub(r"\s+", " ", text)
    text = text.strip(" .,;:!?\"'()[]{}")
    for article in _ARTICLES:
        if text.startswith(article) and len(text) > len(article):
            text = text[len(article) :]
            break
    return text


def singular(word: str) -> str:
    """A conservative English singular of one word (unknown shapes are left alone)."""
    return _singular(word, keep=True)


def lemmatised(word: str) -> str:
    """A lemmatiser's singular of one word, kept plurals included ("scissors" -> "scissor"): how
    ConceptNet 4's OMCS statements name it. Other words: :func:`singular`."""
    return _singular(word, keep=False)


def _singular(word: str, keep: bool) -> str:
    if (keep and word in _KEEP) or len(word) <= 3:
        return word
    if word in _IRREGULAR:
        return _IRREGULAR[word]
    if word.endswith("ies") and len(word) > 4:
        return word[:-3] + "y"
    if word.endswith(("ches", "shes", "sses", "xes", "zes", "oes")):
        return word[:-2]
    if word.endswith("s") and not word.endswith(("ss", "us", "is")):
        return word[:-1]
    return word


def candidates(text: str) -> list[tuple[str, str]]:
    """``(concept, kind)`` pairs to try, best first (see the module docstring)."""
    phrase = normalize(text)
    if not phrase:
        return []
    words = phrase.split(" ")
    lemma = " ".join([*words[:-1], singular(words[-1])])
    if lemma == phrase:  # a word kept plural: its lemmatised singular, only where it has no statements
        lemma = " ".join([*words[:-1], lemmatised(words[-1])])
    out = [(phrase, "exact")]
    if lemma != phrase:
        out.append((lemma, "lemma"))
    if len(words) > 1:
        out.append((singular(words[-1]), "head"))
    return out


def modifiers(text: str) -> list[str]:
    """The modifiers before the head noun: the whole modifier phrase first when it has several
    words (a compound such as "black widow" or "death cap" names a concept of its own), then each
    word ("black widow spider" -> ["black widow", "black", "widow"])."""
    words = [w for w in normalize(text).split(" ")[:-1] if w not in ("of", "and", "with", "for")]
    return ([" ".join(words)] if len(words) > 1 else []) + words


def lookup(text: str, fetch: Fetch, relations: Sequence[str] | None, limit: int) -> ConceptEdges:
    """Resolve ``text`` with the fallback rule and return the matched concept's edges.

    Args:
        text: The name asked for.
        fetch: The backend's raw query: ``fetch(concept, relations, limit) -> edges``.
        relations: Relation filter passed through to ``fetch``.
        limit: Maximum number of edges returned.
    """
    for concept, kind in candidates(text):
        edges = _unlemmatised(concept, fetch(concept, relations, limit), fetch, relations, limit)
        if not edges:
            continue
        if kind != "head":
            return ConceptEdges(text, concept, kind, tuple(edges[:limit]))
        # Head noun matched: let the modifiers contribute up to half of the edges.
        extra, used = _modifier_edges(text, fetch, relations, limit // 2)
        if not extra:
            return ConceptEdges(text, concept, "head", tuple(edges[:limit]))
        matched = " + ".join([concept, *used])
        return ConceptEdges(text, matched, "head+modifier", tuple(edges[: limit - len(extra)] + extra))
    collected, used = _modifier_edges(text, fetch, relations, limit)
    if collected:
        return ConceptEdges(text, " + ".join(used), "modifier", tuple(collected))
    return ConceptEdges(text, None, "none", ())


def _unlemmatised(
    concept: str, edges: list[Edge], fetch: Fetch, relations: Sequence[str] | None, limit: int
) -> list[Edge]:
    """``edges`` of a concept whose last word is kept plural and which only WordNet names, with the
    lemmatised sources' statements about its singular, named as the concept ("scissor UsedFor cut"
    as "scissors UsedFor cut"), strongest first (see the module docstring). Others: ``edges``."""
    words = concept.split(" ")
    single = lemmatised(words[-1])
    if not edges or words[-1] not in _KEEP or single == words[-1]:
        return edges
    if any(e.source != WORD_SOURCE for e in edges):
        return edges
    other = " ".join([*words[:-1], single])
    more = [
        replace(e, head=concept if e.head == other else e.head, tail=concept if e.tail == other else e.tail)
        for e in fetch(other, relations, limit)
        if e.source != WORD_SOURCE
    ]
    return sorted([*edges, *more], key=lambda e: -e.weight)[:limit]


def _modifier_edges(
    text: str, fetch: Fetch, relations: Sequence[str] | None, budget: int
) -> tuple[list[Edge], list[str]]:
    """Edges of the modifiers, in word order, at most ``budget``; and the modifiers that had some."""
    collected: list[Edge] = []
    used: list[str] = []
    for mod in modifiers(text):
        if len(collected) >= budget:
            break
        found = fetch(mod, relations, budget - len(collected))
        if found:
            used.append(mod)
            collected.extend(found[: budget - len(collected)])
    return collected, used
