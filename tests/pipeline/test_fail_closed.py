"""Safety fails closed in both planners (issue 32, items 1-3): what OPE rates 5/5 for the
recipient, what the graph names as a hazard for a child, and a risk decision the backend cannot make
(an error, NaN, an infinity) each keep the move out of the plan, whatever a score says.

Only APIs older than the vetoes are imported here, so these tests run (and fail) on the code before
them."""

from __future__ import annotations

import json
import math

import pytest

from conceptbot.core.errors import ModelOutputError
from conceptbot.core.plan import format_actions, valid_actions
from conceptbot.core.scene import scene_from_dict
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.models.llm import ScoreRequest
from conceptbot.pipeline.conceptbot import ConceptBot
from conceptbot.pipeline.retrieval import RelationRetriever
from tests.pipeline.fakes import PLACES, DictGraph, risk_reply, urp_reply
from tests.scripted import TINY_SCENE

TINY = scene_from_dict(TINY_SCENE)
PRIOR = [-1.0, -1.0]
SAFE = [-0.05, -3.0]  # "is it safe to ...?" Yes


# --- the paper's step planner ----------------------------------------------------------------


def _paper_bot(llm: FakeLLM, graph: DictGraph | None = None, config: str = "conceptbot") -> ConceptBot:
    retriever = RelationRetriever(graph or DictGraph(PLACES), FakeEmbedder(), theta=0.1)
    return ConceptBot(llm, retriever, config, planner="steps")


def _knife_replies(votes: list[str]) -> list[str]:
    ope = [risk_reply(5, [("child", 5)]) if name == "knife" else risk_reply(1) for name in TINY.names]
    replies = [*ope, '{"keywords": ["knife"]}', urp_reply(["pick_and_place(knife, child)"])]
    for vote in votes:
        replies += [vote] * 5
    return replies


@pytest.mark.parametrize("config", ["conceptbot", "nokg"])
def test_the_step_planner_never_hands_over_what_ope_rates_five_for_that_recipient(config: str) -> None:
    # The paper's S_prop only discounts: 0.104 x a unanimous vote beat every alternative at 0.
    llm = FakeLLM(_knife_replies(["pick_and_place(knife, child)", "done()"]))
    plan = _paper_bot(llm, config=config).plan("give the knife to the child", TINY, risk=True)
    assert format_actions(plan.actions) == ["done()"]
    assert plan.refused and "pick_and_place(knife, child): vetoed" in (plan.reason or "")
    vetoes = plan.trace.vetoes or ()
    assert [(v.move, v.source) for v in vetoes] == [("pick_and_place(knife, child)", "ope")]
    assert (
        plan.to_dict()["trace"]["vetoes"][0]["statement"]
        == "OPE rates the knife 5/5 dangerous with the child"
    )


def test_a_vetoed_move_scores_zero_and_the_planner_takes_the_next_allowed_one() -> None:
    # One-pass scoring: the knife to the child is the model's favourite by far.
    replies = _knife_replies([])
    options = [str(a) for a in valid_actions(TINY)]
    first = [0.0 if o == "pick_and_place(knife, child)" else -9.0 for o in options]
    first[options.index("pick_and_place(apple, child)")] = -2.0
    second = [0.0 if o == "done()" else -9.0 for o in options]
    plan = _paper_bot(FakeLLM(replies, scores=[first, second])).plan(
        "give the child something", TINY, risk=True
    )
    assert format_actions(plan.actions) == ["pick_and_place(apple, child)", "done()"] and not plan.refused
    vetoed = next(c for c in plan.steps[0].candidates if c.action == "pick_and_place(knife, child)")
    assert vetoed.factors["veto"] == 0.0 and vetoed.combined == 0.0


# --- the default goal planner ----------------------------------------------------------------


def test_the_graph_vetoes_a_hand_over_the_model_calls_safe() -> None:
    graph = DictGraph({"knife": [("knife", "HasProperty", "sharp")]})
    llm = FakeLLM(scores=[PRIOR, SAFE])  # the model answers "Yes, it is safe"
    bot = ConceptBot(llm, RelationRetriever(graph, FakeEmbedder(), theta=0.1), "urp", planner="goal")
    plan = bot.plan("Give the child the knife", TINY)
    assert format_actions(plan.actions) == ["done()"] and plan.refused
    check = next(c for c in plan.trace.risk or () if c.object == "knife")
    assert check.dropped and check.why == "vetoed" and check.p_unsafe is None
    assert "knife HasProperty sharp" in (plan.reason or "")
    assert [v.source for v in plan.trace.vetoes or ()] == ["graph"]


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_a_risk_decision_the_backend_cannot_make_refuses_the_move(bad: float) -> None:
    llm = FakeLLM(scores=[PRIOR, [bad, bad]])
    bot = ConceptBot(
        llm, RelationRetriever(DictGraph(PLACES), FakeEmbedder(), theta=0.1), "urp", planner="goal"
    )
    plan = bot.plan("Give the child the knife", TINY)
    assert format_actions(plan.actions) == ["done()"] and plan.refused
    assert [v.source for v in plan.trace.vetoes or ()] == ["error"]
    assert "non-finite log-probability" in (plan.reason or "")
    json.dumps(plan.to_dict(), allow_nan=False)  # strict JSON: no NaN anywhere


def test_a_score_response_refuses_non_finite_numbers() -> None:
    with pytest.raises(ModelOutputError, match="non-finite"):
        FakeLLM(scores=[[math.nan, -1.0]]).score(ScoreRequest(options=("Yes", "No"), prompt="?"))


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_a_reading_preference_the_backend_cannot_give_leaves_the_person_to_say_which(bad: float) -> None:
    # The model says the request plainly; the rules read the words another way ("dear" as a thing
    # wanted). Its view of which was meant is not a number: the two readings are as likely, and
    # which one was meant is asked rather than guessed.
    scene = scene_from_dict({"pickable_objects": ["glue", "chips"], "destinations": ["table", "user"]})
    llm = FakeLLM(["Put the glue on the table."], scores=[[bad, -1.0], PRIOR, SAFE])
    bot = ConceptBot(
        llm, RelationRetriever(DictGraph(PLACES), FakeEmbedder(), theta=0.1), "urp", planner="goal"
    )
    plan = bot.plan("Oh, before I forget, would you be a dear and pop the glue on the table?", scene)
    goal = plan.to_dict()["trace"]["goal"]
    assert [r["p"] for r in goal["readings"]] == [0.5, 0.5] and "preference" not in goal
    assert [q.kind for q in plan.questions] == ["reading"]
    json.dumps(plan.to_dict(), allow_nan=False)
