"""Who a destination is, decided by its words, the graph's IsA chain, then the model (issue 64)."""

from __future__ import annotations

import math

import pytest

from conceptbot.knowledge.base import Edge
from conceptbot.pipeline.recipients import Recipients, head_noun, word_kind
from tests.pipeline.fakes import DictGraph
from tests.pipeline.test_hazards import WeightedGraph

GRAPH = DictGraph(
    {
        "puppy": [("puppy", "IsA", "dog")],
        "grandson": [("grandson", "IsA", "grandchild")],
        "grandchild": [("grandchild", "IsA", "descendant")],
        "descendant": [("descendant", "IsA", "relative")],
        "brother": [("brother", "IsA", "male sibling"), ("brother", "IsA", "relative")],
        "drawer": [("drawer", "IsA", "container"), ("drawer", "IsA", "artist")],
        "artist": [("artist", "IsA", "person")],
        "kit": [("kit", "IsA", "case"), ("kit", "IsA", "young mammal")],
        "case": [("case", "IsA", "container")],
        "young mammal": [("young mammal", "IsA", "mammal")],
        "teddy bear": [("teddy bear", "IsA", "plaything")],
        "bed": [("bed", "IsA", "furniture")],
    }
)


@pytest.mark.parametrize(
    ("name", "kind"),
    [
        ("children", "child"),
        ("kids", "child"),
        ("babies", "child"),
        ("my little sister's toddler", "child"),
        ("puppies", "animal"),  # puppy IsA dog
        ("grandson", "person"),  # four steps to "relative": a person the graph cannot age
        ("little brother", "person"),
        ("user", "adult"),
        ("people", "adult"),
        ("drawer", "thing"),  # "container" is as near as "artist" and the person is farther
        ("kit", "animal"),  # equally near and as strong: the more protected kind
        ("dog bed", "thing"),  # the head noun is the bed
        ("teddy bear", "thing"),  # the whole name first: a toy, not a bear
    ],
)
def test_a_recipient_is_known_however_the_scene_names_it(name: str, kind: str) -> None:
    assert Recipients(GRAPH).kind(name) == kind


def test_among_anchors_equally_near_the_strongest_path_wins() -> None:
    # WordNet weighs a word's rarer senses lower: a kit is a case before it is a young fox.
    edges = {
        "kit": [
            Edge("kit", "IsA", "case", 2.0, "wordnet"),
            Edge("kit", "IsA", "young mammal", 0.67, "wordnet"),
        ],
        "case": [Edge("case", "IsA", "container", 2.0, "wordnet")],
        "young mammal": [Edge("young mammal", "IsA", "mammal", 2.0, "wordnet")],
    }
    assert Recipients(WeightedGraph(edges)).kind("kit") == "thing"


def test_the_head_noun_is_the_last_word_singular_or_the_word_before_of() -> None:
    assert [head_noun(n) for n in ("little brothers", "carton of eggs", "Kitchen Knives")] == [
        "brother",
        "carton",
        "knife",
    ]
    assert word_kind("little brother") is None  # the words alone do not say a brother's age


class Model:
    """The plain question's answers, recorded."""

    def __init__(self, answer: float | Exception) -> None:
        self.answer, self.asked = answer, []

    def __call__(self, name: str) -> float:
        self.asked.append(name)
        if isinstance(self.answer, Exception):
            raise self.answer
        return self.answer


def test_the_model_is_asked_only_where_words_and_graph_are_silent_and_once() -> None:
    model = Model(0.9)
    who = Recipients(GRAPH, model)
    assert who.kind("Timmy") == "person" and who.is_vulnerable("Timmy")
    assert who.kind("Timmy") == "person" and who.kind("bed") == "thing" and who.kind("children") == "child"
    assert model.asked == ["Timmy"]
    assert not Recipients(GRAPH, Model(0.1)).is_vulnerable("zorblax")


@pytest.mark.parametrize("answer", [RuntimeError("backend down"), math.nan, math.inf])
def test_an_answer_the_model_cannot_give_is_a_person_who_may_be_a_child(answer: float | Exception) -> None:
    assert Recipients(GRAPH, Model(answer)).is_vulnerable("Timmy")


def test_reading_a_request_never_asks_the_model() -> None:
    model = Model(0.9)
    who = Recipients(GRAPH, model)
    assert not who.is_person("Timmy") and who.is_person("puppies") and not who.is_person("drawer")
    assert model.asked == []
