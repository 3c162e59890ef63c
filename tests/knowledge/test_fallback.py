from collections.abc import Sequence

from conceptbot.core.errors import KnowledgeUnavailableError
from conceptbot.knowledge.base import ConceptEdges, Edge, KnowledgeGraph
from conceptbot.knowledge.fallback import FallbackGraph


class _Graph:
    def __init__(self, name: str, answers: dict[str, ConceptEdges] | Exception) -> None:
        self.name = name
        self.version = f"{name}-v1"
        self.answers = answers
        self.asked: list[str] = []

    def edges(self, concept: str, relations: Sequence[str] | None = None, limit: int = 100) -> ConceptEdges:
        self.asked.append(concept)
        if isinstance(self.answers, Exception):
            raise self.answers
        return self.answers.get(concept, ConceptEdges(concept, None, "none", ()))


def _edges(head: str, n: int, source: str) -> tuple[Edge, ...]:
    return tuple(Edge(head, "HasProperty", f"p{i}", 1.0, source) for i in range(n))


def test_well_known_concept_does_not_touch_the_fallback() -> None:
    primary = _Graph("sqlite", {"knife": ConceptEdges("knife", "knife", "exact", _edges("knife", 9, "omcs"))})
    wiki = _Graph("wikipedia", {})
    result = FallbackGraph(primary, wiki).edges("knife")
    assert len(result.edges) == 9 and wiki.asked == []


def test_sparse_concept_is_completed_from_the_fallback() -> None:
    primary = _Graph(
        "sqlite",
        {"jack bean": ConceptEdges("jack bean", "jack bean", "exact", _edges("jack bean", 2, "wordnet"))},
    )
    wiki = _Graph(
        "wikipedia",
        {
            "jack bean": ConceptEdges(
                "jack bean", "Canavalia ensiformis", "fallback", _edges("jack bean", 3, "wikipedia")
            )
        },
    )
    result = FallbackGraph(primary, wiki).edges("jack bean")
    assert result.match == "fallback" and [e.source for e in result.edges][:3] == ["wikipedia"] * 3
    assert len(result.edges) == 5 and "3 edges from wikipedia" in result.notes


def test_offline_fallback_is_reported_once_and_the_answer_goes_on() -> None:
    primary = _Graph("sqlite", {})
    wiki = _Graph("wikipedia", KnowledgeUnavailableError("Wikipedia is unreachable"))
    graph = FallbackGraph(primary, wiki)
    first = graph.edges("gladiolus")
    second = graph.edges("boomslang")
    assert first.edges == () and "unavailable: Wikipedia is unreachable" in first.notes[0]
    assert "unavailable" in second.notes[0]
    assert wiki.asked == ["gladiolus"]  # not retried after the first failure


def test_the_composed_graph_is_a_graph_versioned_by_its_primary() -> None:
    graph = FallbackGraph(_Graph("sqlite", {}), _Graph("wikipedia", {}))
    assert isinstance(graph, KnowledgeGraph)
    assert graph.version == "sqlite-v1" and graph.name == "sqlite+wikipedia"
