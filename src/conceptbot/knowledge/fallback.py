"""A KnowledgeGraph that asks a fallback (Wikipedia) when the primary graph knows too little.

The paper's rule: when ConceptNet has too little about an object, extract knowledge from its
Wikipedia page. "Too little" here means fewer than ``min_edges`` edges for the exact concept or its
lemma: a head-noun or modifier match ("safety scissors" -> "scissors") is a guess about another
concept, so it also triggers the fallback. When the fallback cannot be reached (offline), the
primary's answer is returned with a note, and the fallback is not tried again in this process.
"""

from __future__ import annotations

from collections.abc import Sequence

from conceptbot.core.errors import KnowledgeUnavailableError
from conceptbot.knowledge.base import DEFAULT_LIMIT, ConceptEdges, KnowledgeGraph


class FallbackGraph:
    """Primary graph first, fallback graph for concepts the primary barely knows.

    Args:
        primary: The main graph (SQLite ConceptNet, or the REST API).
        fallback: The fallback (Wikipedia), or None for none.
        min_edges: Fewer exact/lemma edges than this triggers the fallback.
    """

    def __init__(self, primary: KnowledgeGraph, fallback: KnowledgeGraph | None, min_edges: int = 5) -> None:
        self.primary = primary
        self.fallback = fallback
        self.min_edges = min_edges
        self.name = primary.name if fallback is None else f"{primary.name}+{fallback.name}"
        self.fallback_error: str | None = None

    @property
    def version(self) -> str:
        """The primary graph's version: the fallback is a live source with none of its own."""
        return self.primary.version

    def edges(
        self, concept: str, relations: Sequence[str] | None = None, limit: int = DEFAULT_LIMIT
    ) -> ConceptEdges:
        """Edges from the primary graph, completed from the fallback when needed."""
        result = self.primary.edges(concept, relations, limit)
        direct = result.match in ("exact", "lemma")
        if self.fallback is None or (direct and len(result.edges) >= self.min_edges):
            return result
        if self.fallback_error is not None:
            return _with_note(result, f"{self.fallback.name} fallback unavailable: {self.fallback_error}")
        try:
            extra = self.fallback.edges(concept, relations, limit)
        except KnowledgeUnavailableError as exc:
            self.fallback_error = exc.message
            return _with_note(result, f"{self.fallback.name} fallback unavailable: {exc.message}")
        if not extra.edges:
            return _with_note(result, f"{self.fallback.name} fallback found nothing for {concept!r}")
        # Fallback edges first: they are about the concept itself, not a head-noun guess.
        edges = (extra.edges + result.edges)[:limit]
        matched = extra.matched if not result.matched else f"{result.matched} + {extra.matched}"
        notes = (*result.notes, *extra.notes, f"{len(extra.edges)} edges from {self.fallback.name}")
        return ConceptEdges(result.query, matched, "fallback", edges, notes)


def _with_note(result: ConceptEdges, note: str) -> ConceptEdges:
    return ConceptEdges(result.query, result.matched, result.match, result.edges, (*result.notes, note))
