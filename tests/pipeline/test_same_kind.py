"""What the graph says of places: whether two nouns are the same kind of thing, for places a person
calls by another word than the scene's ("the right baskets" where the scene has bins)."""

from __future__ import annotations

from conceptbot.models.fake import FakeEmbedder
from conceptbot.pipeline.goal_planner.decide import FactFinder
from conceptbot.pipeline.retrieval import RelationRetriever
from tests.pipeline.fakes import DictGraph

GRAPH = DictGraph(
    {
        "basket": [("basket", "IsA", "container"), ("basket", "IsA", "game")],
        "bin": [("bin", "IsA", "container"), ("bin", "IsA", "box")],
        "crate": [("crate", "IsA", "box")],
        "shelf": [("shelf", "IsA", "support")],
        "table": [("table", "IsA", "flat surface")],
        "desk": [("desk", "IsA", "furniture")],
        "oven": [("oven", "IsA", "kitchen appliance")],
        "sofa": [("sofa", "IsA", "furniture"), ("sofa", "IsA", "seat")],
        "seat": [("seat", "IsA", "receptacle")],
    }
)
FACTS = FactFinder(RelationRetriever(GRAPH, FakeEmbedder(), 0.2))


def test_a_shared_parent_or_a_parent_makes_the_same_kind() -> None:
    assert FACTS.same_kind("basket", "bin")  # both IsA container
    assert FACTS.same_kind("crate", "bin")  # both IsA box
    assert FACTS.same_kind("box", "bin")  # bin IsA box
    assert FACTS.same_kind("Bin", "bin")


def test_other_kinds_unknown_words_and_no_graph_are_not() -> None:
    assert not FACTS.same_kind("shelf", "bin")
    assert not FACTS.same_kind("gizmo", "bin")  # the graph does not know it
    assert not FactFinder(None).same_kind("basket", "bin")
