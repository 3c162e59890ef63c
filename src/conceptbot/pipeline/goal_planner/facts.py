"""What the graph states for the goal planner's decisions (:class:`FactFinder`): an object's facts
and its ``IsA`` parents' (the graph does not join such chains itself), a description's words,
dishes, the places food is made in, and what things are for.
"""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

from conceptbot.knowledge.normalize import singular
from conceptbot.pipeline.goal_planner.targets import tokens, words
from conceptbot.pipeline.retrieval import RelationRetriever, edge_text

DEFINING = ("DefinedAs", "MadeOf")  # a word's own definition and ingredients


USES = ("UsedFor", "CapableOf", "DefinedAs")  # what an object is for, as the graph states it


_STOP = {
    "a", "an", "the", "of", "to", "for", "and", "or", "with", "that", "is", "are", "be", "made", "only",
    "something", "thing", "things", "one", "some", "all", "any", "every", "my", "me", "you", "it", "in",
    "on", "into", "can", "could", "would", "i", "we", "please", "entirely", "more", "than", "from",
}  # fmt: skip


def content_words(text: str) -> list[str]:
    """The words and two-word phrases of ``text`` worth looking up in the graph, longest first."""
    words = [w for w in re.findall(r"[a-z][a-z'-]+", text.lower()) if w not in _STOP and len(w) > 2]
    pairs = [f"{a} {b}" for a, b in itertools.pairwise(words)]
    return list(dict.fromkeys(pairs + words))


@dataclass
class FactFinder:
    """Graph facts about objects and descriptions, filtered against what is being decided.

    Args:
        retriever: Relation retrieval with the cosine filter (None: no facts, the no-graph ablation).
        per_object: Facts about the object itself shown per question.
        inherited: Facts about the object's ``IsA`` parents shown per question.
        per_context: Facts about the description's own words (shared by every object's question).
    """

    retriever: RelationRetriever | None
    per_object: int = 4
    inherited: int = 2
    per_context: int = 3

    def context(self, what: str, request: str, dish: str | None = None) -> tuple[str, ...]:
        """Facts about the description's words, most similar first; the ``dish``'s definition first, as it
        names the ingredients but the cosine filter ranks it low."""
        if self.retriever is None:
            return ()
        found_words = list(dict.fromkeys([*([dish] if dish else []), *content_words(what)]))
        if not found_words:
            return ()
        found = self.retriever.retrieve_many(found_words, [what, request])
        defining = [
            s
            for word, r in found.items()
            if r.match == "exact" and word == dish
            for s in r.edges
            if s.edge.relation in DEFINING and s.edge.head.lower() == word
        ]
        kept = sorted(
            (s for r in found.values() if r.matched for s in r.kept if s.edge.relation != "RelatedTo"),
            key=lambda s: -s.similarity,
        )
        return tuple(dict.fromkeys(edge_text(s.edge) for s in [*defining, *kept]))[: self.per_context]

    def is_dish(self, phrase: str) -> bool:
        """Whether the graph places ``phrase`` under a prepared food within three IsA steps."""
        if self.retriever is None:
            return False
        classes = set(words()["dish_classes"])
        name = " ".join(tokens(phrase))
        forms = dict.fromkeys(
            [name, " ".join([*name.split()[:-1], singular(name.split()[-1])]) if name else ""]
        )
        return any(f and (f in classes or self._is_a(f, classes)) for f in forms)

    def dish_concept(self, phrase: str, pickable: Sequence[str] = ()) -> str | None:
        """The graph's concept for a dish named in the request's words ("Pancakes" -> "pancake"), or None;
        single words last (never one of the scene's objects; a bare class word such as "sauce" last)."""
        seq = [w for w in tokens(phrase) if w.isalpha() and w not in _STOP]
        if not seq:
            return None
        classes = set(words()["dish_classes"])
        in_scene = {w for name in pickable for w in tokens(name)}
        # The singular first: a dish's definition is found by an exact match (``context``).
        candidates = [" ".join([*seq[:-1], singular(seq[-1])]), " ".join(seq)]
        candidates += [f"{a} {b}" for a, b in itertools.pairwise(seq)]
        single = [w for w in seq if w not in in_scene and singular(w) not in in_scene]
        candidates += sorted(single, key=lambda w: singular(w) in classes or w in classes)
        return next((c for c in dict.fromkeys(candidates) if self.is_dish(c)), None)

    def may_be_dish(self, phrase: str) -> bool:
        """Whether a wished-for thing may be a dish: the graph calls it food or knows none of its words."""
        if self.dish_concept(phrase) is not None:
            return True
        assert self.retriever is not None
        seq = [w for w in tokens(phrase) if w.isalpha() and w not in _STOP]
        known = (self.retriever.graph.edges(w, ["IsA"], 1).match in ("exact", "lemma") for w in seq)
        return not any(known)

    def prep_places(self, destinations: Sequence[str]) -> list[str]:
        """The destinations the graph places under cookware (by name or last word); empty without a graph."""
        if self.retriever is None:
            return []
        classes = set(words()["cookware_classes"])
        found = []
        for name in destinations:
            words_ = tokens(name)
            heads = dict.fromkeys([name.lower(), words_[-1] if words_ else name.lower()])
            if any(h in classes or self._is_a(h, classes, depth=2) for h in heads):
                found.append(name)
        return found

    def _parents(self, concept: str) -> list[str]:
        """The graph's IsA parents of ``concept``, strongest first ([] where it knows no such word)."""
        assert self.retriever is not None
        found = self.retriever.graph.edges(concept, ["IsA"], 40)
        if found.match not in ("exact", "lemma"):
            return []
        head = (found.matched or concept).lower()
        return list(dict.fromkeys(e.tail.lower() for e in found.edges if e.head.lower() in (concept, head)))

    def _is_a(self, concept: str, classes: set[str] | frozenset[str], depth: int = 3) -> bool:
        """Whether an IsA chain of at most ``depth`` steps leads from ``concept`` to one of ``classes``."""
        assert self.retriever is not None
        level = [concept]
        seen = set(level)
        for _ in range(depth):
            # Ordered, not a set, so that the 12 parents followed are the same on every run.
            parents: dict[str, None] = {}
            for node in level:
                parents.update(dict.fromkeys(self._parents(node)))
            if classes.intersection(parents):
                return True
            level = [p for p in parents if p not in seen][:12]
            seen.update(level)
            if not level:
                return False
        return False

    def uses(self, objects: Sequence[str], need: str) -> dict[str, tuple[float, str]]:
        """Per object, the best cosine between ``need`` and what the graph says it is for, and the
        statement (NaN and "" where none)."""
        if self.retriever is None:
            return {o: (math.nan, "") for o in objects}
        found = self.retriever.retrieve_many(objects, [need])
        out = {}
        for name, got in found.items():
            heads = {name.lower(), (got.matched or name).split(" + ")[0].lower()}
            stated = [
                s
                for s in got.edges
                if s.edge.relation in USES and s.edge.head.lower() in heads and s.edge.weight > 0
            ]
            best = max(stated, key=lambda s: s.similarity, default=None)
            out[name] = (best.similarity, edge_text(best.edge)) if best is not None else (math.nan, "")
        return out

    def about(self, objects: Sequence[str], targets: Sequence[str]) -> dict[str, tuple[str, ...]]:
        """Per object: its kept facts, then kept facts of its IsA parents, most similar first."""
        if self.retriever is None:
            return {o: () for o in objects}
        own = self.retriever.retrieve_many(objects, targets)
        parents: dict[str, list[str]] = {}
        for name, found in own.items():
            heads = {name.lower(), (found.matched or "").lower()}
            parents[name] = [
                s.edge.tail for s in found.edges if s.edge.relation == "IsA" and s.edge.head.lower() in heads
            ][:3]
        wanted = list(dict.fromkeys(p for ps in parents.values() for p in ps))
        inherited = self.retriever.retrieve_many(wanted, targets) if wanted else {}
        out: dict[str, tuple[str, ...]] = {}
        for name, found in own.items():
            facts = [edge_text(s.edge) for s in found.kept[: self.per_object]]
            above = sorted(
                (s for p in parents[name] for s in inherited[p].kept if s.edge.relation != "RelatedTo"),
                key=lambda s: -s.similarity,
            )
            facts += [edge_text(s.edge) for s in above[: self.inherited]]
            out[name] = tuple(dict.fromkeys(facts))
        return out
