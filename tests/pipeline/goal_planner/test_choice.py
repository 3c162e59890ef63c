"""Choosing among the scene's objects: one ranking of all candidates from general signals."""

from __future__ import annotations

import math

import pytest

from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.pipeline.goal_planner.choice import (
    ChoiceWeights,
    ObjectChooser,
    shipped_weights,
    softmax,
    standardised,
)
from conceptbot.pipeline.goal_planner.decide import Decider, FactFinder
from conceptbot.pipeline.retrieval import RelationRetriever
from tests.pipeline.fakes import DictGraph

OBJECTS = ["tissue box", "stapler", "mug"]


def test_the_ranking_asks_two_prompts_whatever_the_number_of_objects() -> None:
    # The name ranking: the request's log-probability of each name, then a neutral request's.
    llm = FakeLLM(scores=[[-1.0, -3.0, -2.0], [-2.0, -2.0, -2.0]])
    chooser = ObjectChooser(Decider(llm, FactFinder(None)), None, ChoiceWeights({"names": 1.0}, 2.0))
    judgements, usage = chooser.rank("I can't stop sneezing.", "give to the user", OBJECTS)
    assert len(llm.score_requests) == 2 and usage.calls == 2
    assert all(r.options == tuple(OBJECTS) for r in llm.score_requests)
    by = {j.subject: j for j in judgements}
    assert [j.subject for j in judgements] == OBJECTS  # in the candidates' order; the planner sorts
    assert by["tissue box"].score > by["mug"].score > by["stapler"].score
    assert sum(j.p_one for j in judgements) == pytest.approx(1.0)
    assert by["tissue box"].p_one == by["tissue box"].p_yes and by["tissue box"].p_one > 0.5
    assert by["tissue box"].evidence.features["names"] == pytest.approx(1.0)
    assert "embed" not in by["tissue box"].evidence.features  # no embedder: the reading is missing


def test_the_graph_statement_of_use_can_overturn_the_names() -> None:
    graph = DictGraph(
        {"stapler": [("stapler", "UsedFor", "fasten paper")], "mug": [("mug", "UsedFor", "drink coffee")]}
    )
    finder = FactFinder(RelationRetriever(graph, FakeEmbedder(), theta=0.1))
    llm = FakeLLM(scores=[[-1.0, -1.2, -3.0], [-2.0, -2.0, -2.0]])  # the names prefer the tissue box a little
    weights = ChoiceWeights({"names": 1.0, "use": 2.0}, 1.0)
    judgements, _ = ObjectChooser(Decider(llm, finder), FakeEmbedder(), weights).rank(
        "I need to fasten paper", "give to the user", OBJECTS
    )
    best = max(judgements, key=lambda j: j.score)
    assert best.subject == "stapler" and any("fasten paper" in s for s in best.evidence.statements)
    assert {"names", "embed", "use"} <= set(best.evidence.features)


def test_standardising_and_the_softmax() -> None:
    assert standardised({"a": 1.0, "b": math.nan, "c": 3.0}) == {"a": -1.0, "b": 0.0, "c": 1.0}
    assert standardised({"a": 1.0, "b": math.nan}) == {"a": 0.0, "b": 0.0}  # one known: no ranking
    chances = softmax({"a": 1.0, "b": 0.0}, 2.0)
    assert chances["a"] == pytest.approx(1 / (1 + math.exp(-2.0)))


def test_the_shipped_weights_read_and_unknown_readings_are_refused() -> None:
    for graph in (True, False):
        found = shipped_weights(graph)
        assert found.sharpness > 0 and "names" in found.weights
    assert "use" not in shipped_weights(False).weights  # the ablation has no graph to read
    with pytest.raises(ValueError, match="unknown choice readings"):
        ChoiceWeights.from_dict({"weights": {"help": 1.0}, "sharpness": 1.0})
