"""Things used together: a need's target also takes what its object is used with ("the toothpaste
with the toothbrush"), by the model's answer and the graph's link, and never on an answer that
cannot be read."""

from __future__ import annotations

import math

import pytest

from conceptbot.core.plan import format_actions
from conceptbot.core.scene import scene_from_dict
from conceptbot.core.usage import Usage
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.pipeline.goal_planner.choice import ChoiceWeights, ObjectChooser
from conceptbot.pipeline.goal_planner.companions import (
    CompanionWeights,
    candidates,
    graph_link,
    shipped_weights,
)
from conceptbot.pipeline.goal_planner.decide import Decider, FactFinder
from conceptbot.pipeline.goal_planner.planner import GoalPlanner
from conceptbot.pipeline.goal_planner.targets import Target, TargetsRead
from conceptbot.pipeline.retrieval import RelationRetriever
from tests.pipeline.fakes import DictGraph

BATHROOM = scene_from_dict(
    {
        "name": "bathroom",
        "pickable_objects": ["toothbrush", "toothpaste", "hairbrush"],
        "destinations": ["user"],
    }
)
PRIOR = [-1.0, -1.0]
SAFE = [-0.05, -3.0]
UNSAFE = [-3.0, -0.05]
YES = [-0.1, -3.0]
NO = [-3.0, -0.1]
HOLDER = [PRIOR, NO]  # "is it handed to a child or an animal?": no, to the adult asking
HELPS = [
    [-0.5, -1.0, -4.0],  # the name ranking: toothbrush best, toothpaste next, hairbrush far below
    [-2.0, -2.0, -2.0],  # and for the neutral request (the hairbrush, below the average, is not
]  # asked about as a companion)
GRAPH = DictGraph(
    {
        "toothpaste": [("toothpaste", "UsedFor", "clean tooth toothbrush")],
        "mitten": [("mitten", "IsA", "glove")],
    }
)


class _Need:
    """A target reader: the request is a need of the user's, taking one object."""

    def read(self, request: str, scene) -> TargetsRead:
        return TargetsRead(False, [Target("user", 1, "speaker", [], helps=True)], Usage(calls=0))


def _decider(llm: FakeLLM, finder: FactFinder) -> tuple[Decider, ObjectChooser]:
    """The decider, and a chooser that ranks by the names alone (these tests are about companions)."""
    decider = Decider(llm, finder)
    return decider, ObjectChooser(decider, None, ChoiceWeights({"names": 1.0}, 2.0))


def _plan(scores: list[list[float]], graph: DictGraph | None = GRAPH):
    llm = FakeLLM(scores=scores)
    finder = FactFinder(RelationRetriever(graph, FakeEmbedder(), theta=0.1) if graph is not None else None)
    decider, chooser = _decider(llm, finder)
    planner = GoalPlanner(_Need(), decider, chooser=chooser)
    result = planner.plan("I want to brush my teeth", BATHROOM)
    return format_actions(result.actions), result, llm


def test_a_need_takes_what_its_object_is_used_together_with() -> None:
    plan, result, llm = _plan([*HELPS, *HOLDER, YES, PRIOR, SAFE, PRIOR, SAFE])
    assert plan == ["pick_and_place(toothbrush, user)", "pick_and_place(toothpaste, user)", "done()"]
    (pair,) = result.trace.companions
    assert (pair.anchor, pair.object, pair.used) == ("toothbrush", "toothpaste", True)
    assert pair.graph == "toothpaste UsedFor clean tooth toothbrush"
    assert pair.p > 0.9
    asked = [m.content for r in llm.score_requests for m in r.messages if m.role == "user"]
    assert (
        sum("would they also need the toothpaste, used together with the toothbrush?" in q for q in asked)
        == 1
    )
    assert result.trace.to_dict()["companions"][0]["used"] is True
    assert "companions" in result.usage


def test_a_substitute_is_not_taken() -> None:
    plan, result, _ = _plan([*HELPS, *HOLDER, NO, PRIOR, SAFE])
    assert plan == ["pick_and_place(toothbrush, user)", "done()"]
    (pair,) = result.trace.companions
    assert not pair.used and pair.p < 0.5


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_an_answer_that_cannot_be_read_adds_nothing(bad: float) -> None:
    plan, result, _ = _plan([*HELPS, *HOLDER, [bad, -1.0], PRIOR, SAFE])
    assert plan == ["pick_and_place(toothbrush, user)", "done()"]
    (pair,) = result.trace.companions
    assert not pair.used and math.isnan(pair.p)
    assert result.trace.to_dict()["companions"][0]["p"] is None


def test_a_companion_the_risk_check_drops_is_not_moved() -> None:
    plan, result, _ = _plan([*HELPS, *HOLDER, YES, PRIOR, SAFE, PRIOR, UNSAFE])
    assert plan == ["pick_and_place(toothbrush, user)", "done()"]
    (pair,) = result.trace.companions
    assert not pair.used
    assert any(c.dropped and c.move.endswith("toothpaste to the user") for c in result.trace.risk)


def test_the_graph_links_things_by_use_not_by_kind() -> None:
    assert graph_link(GRAPH, "toothbrush", "toothpaste") == (
        True,
        "toothpaste UsedFor clean tooth toothbrush",
    )
    assert graph_link(GRAPH, "wool gloves", "mittens") == (False, "")  # a kind: substitutes
    assert graph_link(GRAPH, "box of toothpaste", "toothbrush")[0]  # a container phrase: its contents
    assert graph_link(None, "toothbrush", "toothpaste") == (False, "")


def test_candidates_are_the_next_that_help() -> None:
    ranked = [("toothbrush", 2.0), ("toothpaste", 1.0), ("soap", math.nan), ("towel", 0.5), ("comb", -1.0)]
    assert candidates(ranked, "toothbrush", 2) == ["toothpaste", "towel"]
    assert candidates(ranked, "toothbrush", 1) == ["toothpaste"]


def test_the_weights_combine_the_answer_and_the_link() -> None:
    weights = CompanionWeights(intercept=-1.0, model=2.0, graph=1.0)
    assert weights.p(0.5, False) == pytest.approx(0.5)
    assert weights.p(0.5, True) > 0.7
    assert math.isnan(weights.p(math.nan, True))
    shipped, ablation = shipped_weights(True), shipped_weights(False)
    assert shipped.model > 0 and ablation.model > 0 and ablation.graph == 0.0


def test_after_a_which_one_answer_what_goes_with_the_chosen_object_is_still_asked() -> None:
    llm = FakeLLM(scores=[*HELPS, *HOLDER, YES, PRIOR, SAFE, PRIOR, SAFE])
    finder = FactFinder(RelationRetriever(GRAPH, FakeEmbedder(), theta=0.1))
    decider, chooser = _decider(llm, finder)
    planner = GoalPlanner(_Need(), decider, coverage=1.0, chooser=chooser)  # every decision asked
    questions = []

    def person(question) -> str:
        questions.append(question)
        return "toothbrush"

    result = planner.plan("I want to brush my teeth", BATHROOM, ask=person)
    assert [q.kind for q in questions] == ["one"]
    assert format_actions(result.actions) == [
        "pick_and_place(toothbrush, user)",
        "pick_and_place(toothpaste, user)",
        "done()",
    ]


@pytest.mark.slow
def test_the_together_question_on_a_real_model(smollm2_path) -> None:
    """The question through llama.cpp's scoring: a probability and a finite log-odds per companion,
    the same on a second ask (plumbing; the 135M model is too weak to judge the pairs)."""
    from conceptbot.models.llamacpp import LlamaCppLLM

    llm = LlamaCppLLM(smollm2_path, model="smollm2-135m", n_ctx=1024)
    decider = Decider(llm, FactFinder(None))
    first, used = decider.together("I want to brush my teeth", "toothbrush", ["toothpaste", "hairbrush"])
    again, _ = decider.together("I want to brush my teeth", "toothbrush", ["toothpaste", "hairbrush"])
    assert [j.subject for j in first] == ["toothpaste", "hairbrush"]
    assert all(0.0 < j.p_yes < 1.0 and math.isfinite(j.score) and j.scoring for j in first)
    assert [j.score for j in first] == pytest.approx([j.score for j in again])
    assert used.calls == 2
