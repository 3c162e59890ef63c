"""The KnowledgeGraph protocol and the data it returns."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

#: The paper's relations for object properties (OPE), plus the ones URP finds useful.
PAPER_RELATIONS: tuple[str, ...] = (
    "IsA",
    "PartOf",
    "MadeOf",
    "HasProperty",
    "UsedFor",
    "CapableOf",
    "RelatedTo",
)

#: The paper's target properties (OPE): relations are kept for being close to one of these.
TARGET_PROPERTIES: tuple[str, ...] = (
    "fragile",
    "hold liquid",
    "dangerous",
    "safe",
    "deformable",
    "stable",
    "poisonous",
)

#: Source labels of edges.
SOURCES: tuple[str, ...] = ("omcs", "wordnet", "conceptnet5", "conceptnet-api", "wikipedia")

DEFAULT_LIMIT = 100  # the paper fetches up to 100 edges per concept


@dataclass(frozen=True)
class Edge:
    """One (head, relation, tail) assertion.

    Attributes:
        head: Head concept as readable text ("knife", "ice cream").
        relation: ConceptNet relation name without the ``/r/`` prefix ("IsA", "UsedFor").
        tail: Tail concept as readable text.
        weight: Confidence as given by the source (ConceptNet weights, usually 0.1-10).
        source: Where the edge came from: omcs, wordnet, conceptnet5, conceptnet-api, wikipedia.
    """

    head: str
    relation: str
    tail: str
    weight: float
    source: str

    @property
    def sentence(self) -> str:
        """A readable sentence for embedding and prompts, e.g. ``knife IsA sharp object``."""
        return f"{self.head} {self.relation} {self.tail}"


@dataclass(frozen=True)
class ConceptEdges:
    """The answer to a concept look-up.

    Attributes:
        query: The name that was asked for (e.g. "Ceramic Bowls").
        matched: The concept(s) whose edges were returned (e.g. "bowl + ceramic"); None if none.
        match: How it matched: ``exact``, ``lemma``, ``head``, ``head+modifier``, ``fallback`` or ``none``.
        edges: The edges, strongest first, at most the requested limit.
        notes: What happened on the way, for the trace ("wikipedia fallback unavailable: offline").
    """

    query: str
    matched: str | None
    match: str
    edges: tuple[Edge, ...]
    notes: tuple[str, ...] = ()

    def __bool__(self) -> bool:
        return bool(self.edges)


@runtime_checkable
class KnowledgeGraph(Protocol):
    """A source of commonsense edges about concepts.

    Attributes:
        name: Backend name (``sqlite``, ``conceptnet-api``, ...).
        version: What identifies the graph's contents, so answers derived from it can be cached
            (OPE results are keyed by it): changes whenever the edges may have changed. A built
            database gives ``"INSTALL:BUILT_AT"`` (e.g. ``"omcs+wordnet:2026-11-02T10:00:00"``); a
            graph whose contents are not versioned (a live API) gives ``""``.
    """

    name: str
    version: str

    def edges(
        self, concept: str, relations: Sequence[str] | None = None, limit: int = DEFAULT_LIMIT
    ) -> ConceptEdges:
        """Edges where ``concept`` is the head or the tail.

        Args:
            concept: Any object or keyword name; it is normalised (case, underscores, plurals,
                multi-word fallbacks) and the result says which concept matched.
            relations: Keep only these relation names (None: all).
            limit: At most this many edges, strongest first.

        Returns:
            The matched concept and its edges (empty, with ``match="none"``, when nothing is known).

        Raises:
            KnowledgeUnavailableError: The backing store is missing, corrupt or unreachable.
        """
        ...
