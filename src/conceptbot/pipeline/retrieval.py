"""Relation retrieval with the paper's semantic filtering (section III-A).

For a concept (a detected object, or a keyword of the request) the graph's edges of the paper's
relations are fetched, each edge is turned into a short sentence (:func:`edge_text`), and the
sentences and the *targets* are embedded. An edge's similarity is its highest cosine similarity to
any target; it is kept when that similarity is strictly above ``theta``::

    R_fil = {r in R_i : max_t cos(v_r, v_t) > theta}

Targets are the paper's object properties (``TARGET_PROPERTIES``) in the OPE module; in URP the
keyword edges are compared with the request text, and the object edges with the keywords.

``theta`` depends on the embedding model: the paper's 0.75 is for ``text-embedding-ada-002``, whose
cosines are compressed into a high band; other models need their own value, measured with
``conceptbot calibrate`` (:data:`DEFAULT_THETA`, :func:`default_theta`).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from conceptbot.knowledge.base import DEFAULT_LIMIT, PAPER_RELATIONS, Edge, KnowledgeGraph
from conceptbot.models.embedder import Embedder, cosine_matrix

#: Similarity threshold per embedding model name. Each value transfers the paper's choice to its
#: model: about 20 kept relations per object, as the paper's theta = 0.75 gives with ada-002 (about
#: 35 at 0.70, 3 at 0.80). Measured with ``conceptbot calibrate`` over the paper's 112 objects, the
#: ``TARGET_PROPERTIES`` and the offline graph (OMCS + WordNet, 5,672 edges of the paper's
#: relations, 5 objects unknown), as ``theta | mean | median | min | max | objects with none``.
DEFAULT_THETA: dict[str, float] = {
    # 0.25 | 21.8 | 9.5 | 0 | 92 | 18  (0.20: 35.5 mean; 0.30: 11.1; a 0.01 sweep gives 0.26: 19.3)
    "all-MiniLM-L6-v2": 0.25,
    # The paper's choice (section III-A); not re-measured here (needs the OpenAI API).
    "text-embedding-ada-002": 0.75,
    # The hashing test embedder: 0.20 | 20.2 | 14 | 0 | 100 | 20
    "fake-embedder": 0.20,
}

#: The model whose threshold applies to embedders with no entry in :data:`DEFAULT_THETA`.
FALLBACK_MODEL = "all-MiniLM-L6-v2"

#: Relations retrieved by default: the paper's seven, plus ``DefinedAs``. The offline graph's WordNet
#: glosses ("hollandaise DefinedAs eggs and butter with lemon juice") carry the facts that
#: ConceptNet 5 states as RelatedTo edges (its "hollandaise sauce RelatedTo egg"), so leaving them out
#: would hide exactly the knowledge the paper relies on.
RETRIEVAL_RELATIONS: tuple[str, ...] = (*PAPER_RELATIONS, "DefinedAs")

#: Spoken forms of the paper's relations, for :func:`edge_text`.
RELATION_TEXT: dict[str, str] = {
    "IsA": "is a",
    "PartOf": "is part of",
    "MadeOf": "is made of",
    "HasProperty": "is",
    "UsedFor": "is used for",
    "CapableOf": "can",
    "RelatedTo": "is related to",
    "DefinedAs": "means",
}

_CAMEL = re.compile(r"(?<=[a-z0-9])(?=[A-Z])|(?<=[A-Z])(?=[A-Z][a-z])")


def default_theta(embedder_model: str) -> float:
    """The threshold for an embedding model.

    Args:
        embedder_model: The embedder's ``model`` name; a ``sentence-transformers/`` prefix is
            ignored.

    Returns:
        The :data:`DEFAULT_THETA` entry, or for a model without one the all-MiniLM-L6-v2 value
        (the default, bundled embedder): run ``conceptbot calibrate`` to measure a better one.
    """
    name = embedder_model.removeprefix("sentence-transformers/")
    return DEFAULT_THETA.get(name, DEFAULT_THETA[FALLBACK_MODEL])


def relation_text(relation: str) -> str:
    """A relation name as words: the paper's relations from :data:`RELATION_TEXT`, any other
    camel-case name split and lower-cased (``AtLocation`` -> ``at location``)."""
    if relation in RELATION_TEXT:
        return RELATION_TEXT[relation]
    return " ".join(_CAMEL.sub(" ", relation).replace("_", " ").replace("/", " ").lower().split())


def edge_text(edge: Edge) -> str:
    """The sentence embedded for an edge: :attr:`Edge.sentence` with the relation spoken.

    ``knife IsA weapon`` reads ``knife is a weapon``, ``glass HasProperty fragile`` reads
    ``glass is fragile``, ``knife CapableOf cut`` reads ``knife can cut``; a relation outside
    :data:`RELATION_TEXT` is split at its capitals (``knife AtLocation kitchen`` ->
    ``knife at location kitchen``). Sentence embedders place such text nearer to property words
    than the raw relation names.
    """
    return f"{edge.head} {relation_text(edge.relation)} {edge.tail}"


@dataclass(frozen=True)
class ScoredEdge:
    """An edge with its similarity to the targets.

    Attributes:
        edge: The graph edge.
        similarity: The highest cosine similarity between :func:`edge_text` of the edge and any
            target text.
        target: The target that gave that similarity.
        kept: ``similarity > theta``.
    """

    edge: Edge
    similarity: float
    target: str
    kept: bool


@dataclass(frozen=True)
class Retrieval:
    """The filtered relations of one concept.

    Attributes:
        concept: The name asked for.
        matched: The graph concept(s) whose edges were scored; None when the graph knows nothing.
        match: How it matched (see :class:`~conceptbot.knowledge.base.ConceptEdges`).
        edges: Every scored edge, in the graph's order (strongest first).
        notes: The graph's notes for the trace.
    """

    concept: str
    matched: str | None
    match: str
    edges: tuple[ScoredEdge, ...]
    notes: tuple[str, ...] = ()

    @property
    def kept(self) -> tuple[ScoredEdge, ...]:
        """The kept edges, highest similarity first (ties in graph order)."""
        return tuple(sorted((e for e in self.edges if e.kept), key=lambda e: -e.similarity))


class RelationRetriever:
    """Fetch a concept's edges and keep those semantically close to the targets.

    Args:
        graph: Where the edges come from.
        embedder: Embeds edge sentences and targets (unit vectors; wrap it in a cache).
        theta: Keep edges whose similarity is strictly above this.
        relations: Only edges of these relations are considered (default: the paper's).
        limit: At most this many edges per concept from the graph (the paper fetches 100).
    """

    def __init__(
        self,
        graph: KnowledgeGraph,
        embedder: Embedder,
        theta: float,
        relations: Sequence[str] = RETRIEVAL_RELATIONS,
        limit: int = DEFAULT_LIMIT,
    ) -> None:
        if not -1.0 <= theta <= 1.0:
            raise ValueError(f"theta must be a cosine similarity in [-1, 1], got {theta}")
        self.graph = graph
        self.embedder = embedder
        self.theta = float(theta)
        self.relations = tuple(relations)
        self.limit = limit

    def retrieve(self, concept: str, targets: Sequence[str]) -> Retrieval:
        """Scored edges of ``concept`` (as head or tail) against ``targets``.

        The edge sentences and the targets are embedded in one batch call (none when the concept
        has no edges).

        Raises:
            ValueError: No targets.
            KnowledgeUnavailableError: The graph cannot be read.
            BackendUnavailableError: The embedder cannot be used.
        """
        return self.retrieve_many([concept], targets)[concept]

    def retrieve_many(self, concepts: Iterable[str], targets: Sequence[str]) -> dict[str, Retrieval]:
        """:meth:`retrieve` for many concepts, embedding all their edges in one batch call.

        Returns:
            One :class:`Retrieval` per distinct concept, in the order given.
        """
        targets = tuple(targets)
        if not targets:
            raise ValueError("at least one target text is needed")
        fetched = {}
        for concept in dict.fromkeys(concepts):
            found = self.graph.edges(concept, list(self.relations), self.limit)
            wanted = tuple(e for e in found.edges if e.relation in self.relations)[: self.limit]
            fetched[concept] = (found, wanted)
        texts = list(dict.fromkeys(edge_text(e) for _, wanted in fetched.values() for e in wanted))
        best: dict[str, tuple[float, str]] = {}
        if texts:
            # Targets first: one call, and targets repeated across requests hit the embed cache.
            vectors = self.embedder.embed([*targets, *texts])
            sims = cosine_matrix(vectors[len(targets) :], vectors[: len(targets)])
            top = sims.argmax(axis=1)
            best = {text: (float(sims[row, top[row]]), targets[top[row]]) for row, text in enumerate(texts)}
        out: dict[str, Retrieval] = {}
        for concept, (found, wanted) in fetched.items():
            scored = []
            for edge in wanted:
                similarity, target = best[edge_text(edge)]
                scored.append(ScoredEdge(edge, similarity, target, similarity > self.theta))
            out[concept] = Retrieval(concept, found.matched, found.match, tuple(scored), tuple(found.notes))
        return out
