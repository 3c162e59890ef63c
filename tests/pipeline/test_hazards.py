"""Vetoes: a move whose own evidence names a hazard for its recipient is never planned, whatever a
score says, and a risk decision that cannot be made refuses the move (issue 32, items 1-3)."""

from __future__ import annotations

import json

import pytest

from conceptbot.core.scene import scene_from_dict
from conceptbot.knowledge.base import ConceptEdges, Edge
from conceptbot.pipeline.hazards import HazardCheck, hazard_in
from conceptbot.pipeline.ope import ObjectProperties
from tests.pipeline.fakes import properties_reply, risk_reply
from tests.scripted import TINY_SCENE

TINY = scene_from_dict(TINY_SCENE)
PRIOR = [-1.0, -1.0]
SAFE = [-0.05, -3.0]  # "is it safe to ...?" Yes


def _risk(name: str, danger: int | None, partners: list[tuple[str, int]] | None = None) -> ObjectProperties:
    values = json.loads(risk_reply(1, partners))
    values["dangerous"] = danger
    return ObjectProperties(name, "risk", values)


class WeightedGraph:
    """A graph returning given edges (with weights and sources) for exact names only."""

    name = "weighted"
    version = "test"

    def __init__(self, edges: dict[str, list[Edge]], match: str = "exact") -> None:
        self.data, self.match = edges, match

    def edges(self, concept: str, relations=None, limit: int = 100) -> ConceptEdges:
        found = tuple(e for e in self.data.get(concept, []) if relations is None or e.relation in relations)
        return ConceptEdges(concept, concept if found else None, self.match if found else "none", found)


def _edge(head: str, relation: str, tail: str, weight: float = 1.0, source: str = "omcs") -> Edge:
    return Edge(head, relation, tail, weight, source)


# --- OPE's ratings ---------------------------------------------------------------------------


def test_a_top_interaction_rating_with_the_recipient_vetoes_the_move_for_anyone() -> None:
    check = HazardCheck()
    props = {"knife": _risk("knife", 2, [("user", 5)])}
    veto = check.veto("knife", "user", props)
    assert veto is not None and veto.source == "ope" and "5/5 dangerous with the user" in veto.statement
    assert check.veto("knife", "bowl", props) is None  # a place is nobody to endanger
    # From the recipient's side: the dog's answer names the chocolate.
    assert check.veto("chocolate", "dog", {"dog": _risk("dog", 1, [("chocolate", 5)])}) is not None


def test_the_objects_own_top_rating_vetoes_a_hand_over_to_a_child_or_an_animal_only() -> None:
    check = HazardCheck()
    props = {"knife": _risk("knife", 5)}
    assert check.veto("knife", "child", props) is not None
    assert check.veto("knife", "dog", props) is not None
    assert check.veto("knife", "user", props) is None  # an adult who asks for a knife gets it
    assert check.veto("knife", "child", {"knife": _risk("knife", 4)}) is None  # the planners weigh 4
    missing = check.veto("knife", "child", {"knife": _risk("knife", None)})
    assert missing is not None and "no usable danger rating" in missing.statement


def test_yes_no_properties_veto_dangerous_or_poisonous_things_for_a_child() -> None:
    check = HazardCheck()
    poisonous = ObjectProperties("berry", "properties", json.loads(properties_reply(poisonous="Yes")))
    assert check.veto("berry", "child", {"berry": poisonous}) is not None
    harmless = ObjectProperties("ball", "properties", json.loads(properties_reply()))
    assert check.veto("ball", "child", {"ball": harmless}) is None


# --- the graph's statements ------------------------------------------------------------------


def test_a_graph_hazard_statement_vetoes_a_hand_over_to_a_child_not_to_the_user() -> None:
    check = HazardCheck(WeightedGraph({"knife": [_edge("knife", "HasProperty", "sharp", 3.0)]}))
    veto = check.veto("knife", "child", {})
    assert veto is not None and veto.source == "graph" and "knife HasProperty sharp" in veto.statement
    assert check.veto("knife", "user", {}) is None
    assert check.veto("knife", "table", {}) is None


@pytest.mark.parametrize(
    ("relation", "tail", "target", "vetoed"),
    [
        ("HasProperty", "not sharp", "child", False),
        ("HasProperty", "non-toxic", "child", False),
        ("IsA", "hot dog", "dog", False),
        ("IsA", "poisonous plant", "child", True),
        ("HasProperty", "poisonous to dogs", "dog", True),
        ("HasProperty", "poisonous to dogs", "child", False),  # names another recipient
        ("CapableOf", "hurt", "child", True),
        ("CapableOf", "burn out", "child", False),  # not a harm to anyone
        ("UsedFor", "poison rats", "child", False),  # not a statement of what it is
    ],
)
def test_which_statements_name_a_hazard(relation: str, tail: str, target: str, vetoed: bool) -> None:
    check = HazardCheck(WeightedGraph({"thing": [_edge("thing", relation, tail)]}))
    assert (check.veto("thing", target, {}) is not None) is vetoed


def test_the_graph_cannot_veto_through_a_word_of_the_name_or_against_its_own_stronger_word() -> None:
    sharp = {"safety scissors": [_edge("scissors", "HasProperty", "sharp")]}
    assert (
        HazardCheck(WeightedGraph(sharp, match="head+modifier")).veto("safety scissors", "child", {}) is None
    )
    plant = [_edge("plant", "HasProperty", "poisonous", 6.0), _edge("plant", "HasProperty", "edible", 7.0)]
    assert HazardCheck(WeightedGraph({"plant": plant})).veto("plant", "cat", {}) is None
    # A WordNet gloss of one of several senses is not about the object in the scene.
    lime = [
        _edge("lime", "DefinedAs", "a caustic substance produced by heating limestone", 2.0, "wordnet"),
        _edge("lime", "DefinedAs", "the green acidic fruit of any of various lime trees", 0.3, "wordnet"),
    ]
    assert HazardCheck(WeightedGraph({"lime": lime})).veto("lime", "child", {}) is None


def test_hazard_words_are_matched_as_words() -> None:
    assert hazard_in(_edge("x", "HasProperty", "sharpener"), "child") is None
    assert hazard_in(_edge("x", "IsA", "choking hazard"), "child") == "choking hazard"


def test_a_word_kept_plural_is_vetoed_by_what_the_lemmatised_source_says_of_its_singular() -> None:
    # The offline graph as built: WordNet names "scissors" as written (three senses), ConceptNet 4's
    # OMCS statements name it "scissor". The lookup reads both (knowledge/normalize.py).
    from tests.pipeline.fakes import DictGraph

    class TwoSources(DictGraph):
        def _fetch(self, concept, relations, limit):
            rows = {
                "scissors": [
                    _edge("scissors", "IsA", "edge tool", 2.0, "wordnet"),
                    _edge("scissors", "IsA", "wrestling hold", 1.0, "wordnet"),
                ],
                "scissor": [
                    _edge("scissor", "UsedFor", "cut", 7.0),
                    _edge("scissor", "HasProperty", "sharp", 3.0),
                ],
            }.get(concept, [])
            return [e for e in rows if relations is None or e.relation in relations][:limit]

    check = HazardCheck(TwoSources({}))
    veto = check.veto("scissors", "child", {})
    assert veto is not None and veto.source == "graph" and "scissors HasProperty sharp" in veto.statement
    assert check.veto("scissors", "user", {}) is None  # an adult who asks gets them
    # "safety scissors" is read through its head noun: no evidence about the object itself.
    assert check.veto("safety scissors", "child", {}) is None
