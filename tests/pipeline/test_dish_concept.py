"""Which concept of the graph a dish named in the request's own words is (the goal reader gives the
words; the planner needs the concept, whose definition names the ingredients)."""

from __future__ import annotations

from conceptbot.models.fake import FakeEmbedder
from conceptbot.pipeline.goal_planner.decide import FactFinder
from conceptbot.pipeline.retrieval import RelationRetriever
from tests.pipeline.fakes import DictGraph

GRAPH = DictGraph(
    {
        "hollandaise": [("hollandaise", "IsA", "sauce")],
        "pancake": [("pancake", "IsA", "cake")],
        "tomato": [("tomato", "IsA", "salad")],  # the offline graph's own noise
        "lemonade": [("lemonade", "IsA", "beverage")],
    }
)
FACTS = FactFinder(RelationRetriever(GRAPH, FakeEmbedder(), 0.2))


def test_the_specific_word_of_a_dish_phrase_wins_over_its_class_word() -> None:
    assert FACTS.dish_concept("a hollandaise sauce") == "hollandaise"
    assert FACTS.dish_concept("Pancakes") == "pancake"


def test_a_word_of_the_scenes_objects_is_an_ingredient_not_the_dish() -> None:
    assert FACTS.dish_concept("a tomato and cucumber salad", ["tomato", "cucumber"]) == "salad"


def test_no_dish_without_a_graph_or_a_food_class() -> None:
    assert FACTS.dish_concept("some lemonade") is None
    assert FactFinder(None).dish_concept("a hollandaise sauce") is None


def test_a_wished_thing_the_graph_does_not_know_may_be_a_dish_one_it_knows_otherwise_is_not() -> None:
    assert FACTS.may_be_dish("a hollandaise sauce")
    assert FACTS.may_be_dish("a PB&J")  # not in the graph: the parse decides
    assert not FACTS.may_be_dish("some lemonade")  # known, as a beverage
