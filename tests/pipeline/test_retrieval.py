"""RelationRetriever: the paper's semantic filtering, on an in-memory graph and the hashing embedder."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pytest

from conceptbot.knowledge.base import PAPER_RELATIONS, TARGET_PROPERTIES, ConceptEdges, Edge, KnowledgeGraph
from conceptbot.models.fake import FakeEmbedder
from conceptbot.pipeline.retrieval import (
    DEFAULT_THETA,
    RelationRetriever,
    Retrieval,
    default_theta,
    edge_text,
)


def edge(head: str, relation: str, tail: str, weight: float = 1.0) -> Edge:
    return Edge(head, relation, tail, weight, "omcs")


class TinyGraph:
    """A KnowledgeGraph over a dict; it ignores the relation filter, so the retriever must apply it."""

    name = "tiny"
    version = ""

    def __init__(self, edges: dict[str, list[Edge]]) -> None:
        self._edges = edges
        self.calls: list[tuple[str, tuple[str, ...] | None, int]] = []

    def edges(self, concept: str, relations: Sequence[str] | None = None, limit: int = 100) -> ConceptEdges:
        self.calls.append((concept, None if relations is None else tuple(relations), limit))
        found = self._edges.get(concept, [])
        if not found:
            return ConceptEdges(concept, None, "none", (), ("nothing known",))
        return ConceptEdges(concept, concept, "exact", tuple(found))


KNIFE = [
    edge("knife", "AtLocation", "kitchen", 9.0),
    edge("knife", "HasProperty", "dangerous", 5.0),
    edge("knife", "UsedFor", "cut bread", 4.0),
    edge("knife", "IsA", "weapon", 3.0),
    edge("blade", "PartOf", "knife", 2.0),
]
GLASS = [edge("glass", "HasProperty", "fragile", 4.0), edge("glass", "IsA", "solid", 1.0)]


def cosine(embedder: FakeEmbedder, a: str, b: str) -> float:
    vectors = embedder.embed([a, b])
    return float(vectors[0] @ vectors[1])


@pytest.fixture
def graph() -> TinyGraph:
    return TinyGraph({"knife": KNIFE, "glass": GLASS})


def test_tiny_graph_is_a_knowledge_graph(graph: TinyGraph) -> None:
    assert isinstance(graph, KnowledgeGraph)


@pytest.mark.parametrize(
    ("relation", "text"),
    [
        ("IsA", "knife is a weapon"),
        ("PartOf", "knife is part of weapon"),
        ("MadeOf", "knife is made of weapon"),
        ("HasProperty", "knife is weapon"),
        ("UsedFor", "knife is used for weapon"),
        ("CapableOf", "knife can weapon"),
        ("RelatedTo", "knife is related to weapon"),
        ("AtLocation", "knife at location weapon"),
        ("ReceivesAction", "knife receives action weapon"),
        ("HasA", "knife has a weapon"),
        ("NotDesires", "knife not desires weapon"),
    ],
)
def test_edge_text_speaks_the_relation(relation: str, text: str) -> None:
    assert edge_text(edge("knife", relation, "weapon")) == text


def test_similarity_is_the_max_over_targets(graph: TinyGraph) -> None:
    embedder = FakeEmbedder()
    targets = ("fragile", "dangerous", "hold liquid")
    result = RelationRetriever(graph, embedder, theta=0.0).retrieve("knife", targets)
    reference = FakeEmbedder()
    assert [s.edge for s in result.edges] == [e for e in KNIFE if e.relation in PAPER_RELATIONS]
    for scored in result.edges:
        per_target = {t: cosine(reference, edge_text(scored.edge), t) for t in targets}
        best = max(per_target, key=per_target.get)
        assert scored.target == best
        assert scored.similarity == pytest.approx(per_target[best], abs=1e-6)
    danger = next(s for s in result.edges if s.edge.tail == "dangerous")
    assert danger.target == "dangerous" and danger.similarity > 0.5  # shares the word


def test_theta_filters_strictly_and_kept_is_sorted(graph: TinyGraph) -> None:
    probe = RelationRetriever(graph, FakeEmbedder(), theta=0.0).retrieve("knife", TARGET_PROPERTIES)
    sims = sorted({s.similarity for s in probe.edges}, reverse=True)
    assert len(sims) >= 3
    theta = sims[1]  # exactly the second highest similarity: that edge is not kept
    result = RelationRetriever(graph, FakeEmbedder(), theta=theta).retrieve("knife", TARGET_PROPERTIES)
    assert [s.similarity for s in result.kept] == [sims[0]]
    assert all(s.kept == (s.similarity > theta) for s in result.edges)
    looser = RelationRetriever(graph, FakeEmbedder(), theta=float(np.nextafter(theta, -1))).retrieve(
        "knife", TARGET_PROPERTIES
    )
    assert [s.similarity for s in looser.kept] == sims[:2]
    everything = RelationRetriever(graph, FakeEmbedder(), theta=-1.0).retrieve("knife", TARGET_PROPERTIES)
    kept = [s.similarity for s in everything.kept]
    assert kept == sorted(kept, reverse=True) and len(kept) == len(everything.edges)


def test_relation_filter_and_limit_reach_the_graph(graph: TinyGraph) -> None:
    retriever = RelationRetriever(graph, FakeEmbedder(), theta=0.0, relations=("IsA", "PartOf"), limit=7)
    result = retriever.retrieve("knife", TARGET_PROPERTIES)
    assert graph.calls == [("knife", ("IsA", "PartOf"), 7)]
    assert {s.edge.relation for s in result.edges} == {"IsA", "PartOf"}
    assert result.matched == "knife" and result.match == "exact"
    short = RelationRetriever(graph, FakeEmbedder(), theta=0.0, limit=2).retrieve("knife", TARGET_PROPERTIES)
    assert [s.edge.relation for s in short.edges] == ["HasProperty", "UsedFor"]


def test_retrieve_many_embeds_once(graph: TinyGraph) -> None:
    embedder = FakeEmbedder()
    retriever = RelationRetriever(graph, embedder, theta=0.3)
    results = retriever.retrieve_many(["knife", "glass", "zzyzx", "knife"], TARGET_PROPERTIES)
    assert list(results) == ["knife", "glass", "zzyzx"]
    assert len(embedder.calls) == 1
    texts = embedder.calls[0]
    assert texts[: len(TARGET_PROPERTIES)] == TARGET_PROPERTIES
    edges = [e for e in KNIFE + GLASS if e.relation in PAPER_RELATIONS]
    assert sorted(texts[len(TARGET_PROPERTIES) :]) == sorted(edge_text(e) for e in edges)
    single = RelationRetriever(graph, FakeEmbedder(), theta=0.3).retrieve("glass", TARGET_PROPERTIES)
    assert [(s.edge, s.target, s.kept) for s in results["glass"].edges] == [
        (s.edge, s.target, s.kept) for s in single.edges
    ]
    assert [s.similarity for s in results["glass"].edges] == pytest.approx(
        [s.similarity for s in single.edges]
    )
    unknown = results["zzyzx"]
    assert unknown == Retrieval("zzyzx", None, "none", (), ("nothing known",)) and unknown.kept == ()


def test_nothing_to_embed_means_no_call(graph: TinyGraph) -> None:
    embedder = FakeEmbedder()
    result = RelationRetriever(graph, embedder, theta=0.5).retrieve("zzyzx", ["dangerous"])
    assert result.edges == () and embedder.calls == []


def test_bad_arguments(graph: TinyGraph) -> None:
    with pytest.raises(ValueError, match="target"):
        RelationRetriever(graph, FakeEmbedder(), theta=0.5).retrieve("knife", [])
    with pytest.raises(ValueError, match="theta"):
        RelationRetriever(graph, FakeEmbedder(), theta=1.5)


def test_default_theta_per_model() -> None:
    assert default_theta("text-embedding-ada-002") == 0.75  # the paper's value
    assert default_theta("all-MiniLM-L6-v2") == DEFAULT_THETA["all-MiniLM-L6-v2"]
    assert default_theta("sentence-transformers/all-MiniLM-L6-v2") == DEFAULT_THETA["all-MiniLM-L6-v2"]
    assert default_theta("some-new-model") == DEFAULT_THETA["all-MiniLM-L6-v2"]
    assert default_theta("fake-embedder") == DEFAULT_THETA["fake-embedder"]
    assert 0.0 < DEFAULT_THETA["all-MiniLM-L6-v2"] < 0.75  # MiniLM cosines are lower than ada-002's
