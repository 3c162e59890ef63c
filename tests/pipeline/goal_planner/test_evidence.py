"""Graph evidence for one object and one criterion, read without the model (issue 33, item 2)."""

from __future__ import annotations

import pytest

from conceptbot.pipeline.goal_planner.evidence import GraphEvidence, criterion_terms, stated
from tests.pipeline.fakes import DictGraph

GRAPH = DictGraph(
    {
        "death cap": [
            ("death cap", "DefinedAs", "extremely poisonous white fungus"),
            ("death cap", "IsA", "agaric"),
        ],
        "chanterelle": [("chanterelle", "DefinedAs", "widely distributed edible mushroom")],
        "green hellebore": [("green hellebore", "IsA", "hellebore")],
        "hellebore": [("hellebore", "IsA", "poisonous plant")],
        "paper cup": [("paper cup", "MadeOf", "paper"), ("paper cup", "IsA", "cup")],
        "jar": [("jar", "MadeOf", "glass")],
        "hollandaise": [("hollandaise", "DefinedAs", "eggs and butter with lemon juice")],
        "french toast": [("french toast", "DefinedAs", "bread slice dipped in egg and milk and fried")],
        "carton": [("carton", "IsA", "box")],
        "box": [("box", "IsA", "container")],
        "knife": [("knife", "IsA", "tool")],
        "mug": [("mug", "IsA", "container"), ("mug", "IsA", "crockery")],
        "tiramisu": [("tiramisu", "DefinedAs", "sponge cake soaked in coffee with mascarpone")],
        "pesto": [("pesto", "DefinedAs", "a sauce typically served with pasta"), ("pesto", "IsA", "sauce")],
        "mashed potato": [
            ("mashed potato", "DefinedAs", "potato boiled and then mashed"),
            ("mashed potato", "IsA", "potato"),
        ],
        "salad": [("salad", "DefinedAs", "food mixtures served with a dressing"), ("salad", "IsA", "food")],
        "sugar": [("sugar", "IsA", "food")],
        "mystery berry": [("mystery berry", "HasProperty", "not edible")],
        "ginger": [("ginger", "HasProperty", "inedible raw")],
    }
)


def _features(obj: str, criterion: str, graph: DictGraph | None = GRAPH) -> dict[str, float]:
    """The statement features that are set (not the criterion's kind)."""
    found = GraphEvidence(graph).read(obj, criterion).features
    return {k: v for k, v in found.items() if v and not k.startswith("is_")}


def test_the_criterion_kind_is_a_feature() -> None:
    assert GraphEvidence(None).read("lemon", "an ingredient of hollandaise").features["is_dish"] == 1.0
    assert GraphEvidence(None).read("steel bolt", "made of metal").features["is_material"] == 1.0
    assert GraphEvidence(None).read("yew", "poisonous").features["is_material"] == 0.0


def test_a_material_family_counts_its_members_as_the_same_material() -> None:
    assert _features("steel bolt", "made only of metal", graph=None) == {"name_yes": 1.0}
    assert _features("wool scarf", "made of fabric alone", graph=None) == {"name_yes": 1.0}
    assert _features("plastic folder", "made only of paper", graph=None) == {"name_no": 1.0}


def test_a_gloss_that_names_the_property_is_evidence_for_it_and_its_opposite_against() -> None:
    assert _features("death cap", "poisonous") == {"own_yes": 1.0}
    assert _features("chanterelle", "poisonous") == {"own_no": 1.0}
    assert _features("chanterelle", "safe to eat") == {"own_yes": 1.0}


def test_a_property_of_an_ancestor_counts_at_the_kind_level() -> None:
    assert _features("green hellebore", "toxic") == {"kind_yes": 1.0}


def test_a_negation_turns_a_statement_round() -> None:
    assert _features("mystery berry", "edible") == {"own_no": 1.0}
    assert _features("ginger", "edible") == {"own_no": 1.0}
    assert stated("non-toxic paint", criterion_terms("toxic")) == (False, True)


def test_materials_from_the_name_the_object_and_its_head_noun() -> None:
    assert _features("paper cup", "made entirely of paper") == {"own_yes": 1.0, "name_yes": 1.0}
    glass_jar = _features("glass jar", "made only of glass")
    assert glass_jar["name_yes"] == 1.0 and glass_jar["kind_yes"] == 1.0
    assert _features("paper cup", "made only of glass")["name_no"] == 1.0  # another material
    assert _features("wooden box", "made of wood", graph=None) == {"name_yes": 1.0}


def test_a_dish_gloss_names_its_ingredients() -> None:
    assert _features("eggs", "an ingredient of hollandaise") == {"dish_yes": 1.0}
    assert _features("lemon", "an ingredient of hollandaise") == {"dish_yes": 1.0}
    assert _features("olive oil", "an ingredient of hollandaise") == {"dish_no": 1.0}
    assert _features("lemon", "an ingredient of something unknown") == {}


def test_a_containers_name_says_what_it_holds() -> None:
    # "carton" is a container two IsA steps up: its other words are the contents.
    assert _features("milk carton", "an ingredient of french toast") == {"dish_yes": 1.0}
    assert _features("carton of eggs", "an ingredient of french toast") == {"dish_yes": 1.0}
    # A knife is no container: "bread knife" holds no bread; tableware says what it is for.
    assert _features("bread knife", "an ingredient of french toast") == {"dish_no": 1.0}
    assert _features("coffee mug", "an ingredient of tiramisu") == {"dish_no": 1.0}


def test_the_dishs_own_kind_names_no_ingredient() -> None:
    # "pesto: a sauce ..." names what pesto is; soy sauce is another sauce, not an ingredient.
    assert _features("soy sauce", "an ingredient of pesto") == {"dish_no": 1.0}
    # But a bag of potatoes holds what mashed potato is made of.
    assert _features("bag of potatoes", "an ingredient of mashed potato") == {"dish_yes": 1.0}
    # Salad and sugar are both food: that is no evidence that sugar goes in a salad.
    assert _features("sugar", "an ingredient of salad") == {"dish_no": 1.0}


def test_without_a_graph_only_the_name_counts() -> None:
    assert _features("death cap", "poisonous", graph=None) == {}


@pytest.mark.parametrize(
    ("criterion", "yes", "no"),
    [
        ("poisonous", "toxic", "edible"),
        ("safe to eat", "edible", "poisonous"),
        ("made entirely of wooden parts", "wood", "metal"),
    ],
)
def test_criterion_terms_bring_the_group_and_its_opposite(criterion: str, yes: str, no: str) -> None:
    terms = criterion_terms(criterion)
    assert (yes,) in terms.yes and (no,) in terms.no


def test_the_trace_form_lists_only_what_is_set_with_the_statements() -> None:
    found = GraphEvidence(GRAPH).read("death cap", "poisonous").to_dict()
    assert found == {
        "features": {"own_yes": 1.0, "is_poison": 1.0},  # what it states, and the criterion's kind
        "statements": ["own_yes: death cap DefinedAs extremely poisonous white fungus"],
    }


def test_whom_a_property_is_about_is_no_statement_of_it() -> None:
    # "poisonous to dogs": a dog ball's name says nothing about poison; "a fruit" alone is the criterion.
    assert _features("dog ball", "poisonous to dogs", graph=None) == {}
    assert ("dog",) not in criterion_terms("poisonous to dogs").yes
    assert ("fruit",) in criterion_terms("a fruit").yes
    assert _features("wooden toy", "safe and made of wood", graph=None) == {"name_yes": 1.0}
