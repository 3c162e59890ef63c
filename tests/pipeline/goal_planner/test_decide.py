"""The decider's described reading (the model's own description of an object put into the yes/no
question, where the fitted combination uses it) and its question for a need."""

from __future__ import annotations

import math

import pytest

from conceptbot.core.scene import Scene
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.pipeline.goal_planner.combine import Combination
from conceptbot.pipeline.goal_planner.decide import Decider, FactFinder
from conceptbot.pipeline.retrieval import RelationRetriever
from tests.pipeline.fakes import DictGraph

SCENE = Scene(objects=(), name="test")
DESCRIBED = Combination(("described",), (2.0,), 0.0)


def test_each_object_is_described_once_in_one_greedy_sentence() -> None:
    llm = FakeLLM(replies=["A foxglove is a plant;\n it is not safe to eat.", "Parsley is a herb."])
    found, usage = Decider(llm, FactFinder(None)).describe(["foxglove", "parsley", "foxglove"])
    assert found == {
        "foxglove": "A foxglove is a plant; it is not safe to eat.",
        "parsley": "Parsley is a herb.",
    }
    assert len(llm.requests) == 2 and usage.calls == 2
    assert all(r.temperature == 0.0 and r.max_tokens <= 64 for r in llm.requests)
    assert "foxglove" in llm.requests[0].messages[-1].content


def test_a_combination_with_the_described_reading_asks_with_the_description_and_traces_it() -> None:
    scores = [
        [-1.0, -1.0],  # content-free object, with graph facts (none here)
        [-1.0, -1.0],  # foxglove
        [-1.0, -1.0],  # parsley: the plain question cannot tell them apart
        [-1.0, -1.0],  # content-free object, no description
        [-0.2, -2.2],  # foxglove with its description: +2
        [-2.2, -0.2],  # parsley with its description: -2
    ]
    llm = FakeLLM(replies=["Foxglove is poisonous.", "Parsley is a herb you can eat."], scores=scores)
    decider = Decider(llm, FactFinder(None), combination=DESCRIBED)
    judgements, _, usage = decider.fits(
        "bin the poisonous plants", "poisonous", ["foxglove", "parsley"], SCENE
    )
    by = {j.subject: j for j in judgements}
    assert by["foxglove"].p_yes > 0.9 > 0.1 > by["parsley"].p_yes
    assert by["foxglove"].model == pytest.approx(0.0)  # the question alone said nothing
    assert by["foxglove"].to_dict()["described"] == "Foxglove is poisonous."
    asked = [r.messages[-1].content for r in llm.score_requests]
    assert "What is known about it: Foxglove is poisonous." in asked[4]
    assert "What is known about it" not in asked[3]  # the calibration object has no description
    assert usage.calls == 8


def test_a_combination_without_it_asks_for_no_description() -> None:
    llm = FakeLLM(scores=[[-1.0, -1.0], [-0.5, -1.5]])
    decider = Decider(llm, FactFinder(None), combination=Combination(("model",), (1.0,), 0.0))
    judgements, _, _ = decider.fits("bin the poisonous plants", "poisonous", ["foxglove"], SCENE)
    assert llm.requests == [] and "described" not in judgements[0].to_dict()
    assert judgements[0].score == pytest.approx(1.0)


def test_which_combinations_use_it() -> None:
    assert DESCRIBED.uses_described
    assert Combination(("model*described_z",), (1.0,), 0.0).uses_described
    assert not Combination(("model", "plain"), (1.0, 1.0), 0.0).uses_described


def test_the_plain_reading_is_standardised_in_its_group_like_the_model_s() -> None:
    # No graph here, so the plain reading is the question itself: +1 and -1 around a prior of 0.
    llm = FakeLLM(scores=[[-1.0, -1.0], [-0.5, -1.5], [-1.5, -0.5]])
    decider = Decider(
        llm, FactFinder(None), combination=Combination(("plain_gap", "plain_z"), (1.0, 0.5), 0.0)
    )
    judgements, _, _ = decider.fits("bin the poisonous plants", "poisonous", ["foxglove", "parsley"], SCENE)
    by = {j.subject: j.score for j in judgements}
    assert by["foxglove"] == pytest.approx(0.5)  # gap 0, z +1
    assert by["parsley"] == pytest.approx(-2.0 - 0.5)  # gap -2, z -1


def test_an_ingredient_question_asks_about_the_dish_as_it_was_said() -> None:
    # The graph's concept is "salad"; the person asked for a tomato and cucumber salad, and a kiwi
    # is an ingredient of the one but not of the other.
    llm = FakeLLM(scores=[[-1.0, -1.0]] * 4)  # the content-free object and the kiwi, twice
    decider = Decider(llm, FactFinder(None), combination=Combination(("model",), (1.0,), 0.0))
    decider.fits(
        "I fancy a tomato and cucumber salad.",
        "an ingredient of salad",
        ["kiwi"],
        SCENE,
        dish="salad",
        said="tomato and cucumber salad",
    )
    asked = [r.messages[-1].content for r in llm.score_requests]
    assert all("an ingredient of tomato and cucumber salad?" in a for a in asked)
    decider.fits("Make a salad.", "an ingredient of salad", ["kiwi"], SCENE, dish="salad")
    assert "an ingredient of salad?" in llm.score_requests[-1].messages[-1].content


def test_without_a_graph_nothing_is_stated_of_what_an_object_is_for() -> None:
    found = FactFinder(None).uses(["glue"], "I need to stick paper together")
    assert math.isnan(found["glue"][0]) and found["glue"][1] == ""


@pytest.mark.parametrize(
    ("criterion", "with_facts"),
    [("poisonous", True), ("safe for the toddler", False), ("child-safe", False), ("harmless", False)],
)
def test_a_criterion_of_safety_is_asked_without_the_objects_facts(criterion: str, with_facts: bool) -> None:
    # The graph knows the button battery; a safety question is asked without what it says (on the
    # judgement set the facts lowered the model's answer there), a poison question with it.
    graph = DictGraph({"button battery": [("button battery", "HasProperty", "poisonous if swallowed")]})
    llm = FakeLLM(scores=[[-1.0, -1.0], [-0.5, -1.5]])
    facts = FactFinder(RelationRetriever(graph, FakeEmbedder(), theta=-1.0))
    decider = Decider(llm, facts, combination=Combination(("model",), (1.0,), 0.0))
    judgements, _, _ = decider.fits("tidy the toys away", criterion, ["button battery"], SCENE)
    asked = llm.score_requests[-1].messages[-1].content
    assert ("Facts about it:" in asked) is with_facts and ("poisonous if swallowed" in asked) is with_facts
    assert bool(judgements[0].facts) is with_facts
    assert judgements[0].score == pytest.approx(1.0)
