"""The harm judge: a scored yes/no decision, and the ConceptBot household planner built on it."""

from __future__ import annotations

import json
import math

import pytest

from conceptbot.household.judge import HarmJudge, HarmVerdict, safety_text
from conceptbot.household.planner import ConceptBotHouseholdPlanner, PlainHouseholdPlanner
from conceptbot.household.thor import house_scene
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.pipeline.retrieval import RelationRetriever
from tests.pipeline.fakes import DictGraph, Recorder, risk_reply

KITCHEN = house_scene("FloorPlan1", ["Candle", "Mug", "Microwave"])


def _reply(refuse: bool, steps: list[str]) -> str:
    return json.dumps({"reasoning": "r", "refuse": refuse, "steps": steps})


def test_the_verdict_adds_a_reading_with_evidence_to_one_without_and_compares_the_threshold() -> None:
    llm = FakeLLM(scores=[[math.log(0.8), math.log(0.2)], [math.log(0.6), math.log(0.4)]] * 2)
    judge = HarmJudge(llm, threshold=1.0)
    risky, _ = judge.judge(
        "Put the mug with a fork in the microwave.", KITCHEN, "Risk analysis: fork, danger 5/5"
    )
    assert risky.without_evidence == pytest.approx(math.log(4))  # 0.8 / 0.2
    assert risky.with_evidence == pytest.approx(math.log(1.5))  # 0.6 / 0.4
    assert risky.log_odds == pytest.approx(math.log(6)) and risky.refuse  # 1.79 >= 1.0
    assert risky.to_dict()["refuse"] is True
    blind, informed = llm.score_requests
    assert blind.options == informed.options == ("Yes", "No")
    assert safety_text() in informed.messages[0].content and "-> Yes" in informed.messages[0].content
    assert "Instruction: Put the mug with a fork in the microwave." in informed.messages[1].content
    assert "danger 5/5" in informed.messages[1].content and "danger 5/5" not in blind.messages[1].content
    assert "Microwave" in blind.messages[1].content
    assert not HarmVerdict(0.99, 1.0).refuse and HarmVerdict(1.0, 1.0).refuse


def test_without_evidence_the_one_reading_counts_twice() -> None:
    llm = FakeLLM(scores=[[math.log(0.3), math.log(0.7)]])
    verdict, _ = HarmJudge(llm, threshold=1.0).judge("Put the mug in the microwave.", KITCHEN)
    assert verdict.log_odds == pytest.approx(2 * math.log(3 / 7)) and not verdict.refuse
    assert len(llm.score_requests) == 1


def test_both_planners_share_the_safety_instruction() -> None:
    llm = FakeLLM([_reply(False, ["find Mug"])])
    PlainHouseholdPlanner(llm).plan("Find the mug.", KITCHEN)
    assert safety_text() + ": plan it completely" in llm.requests[0].messages[0].content


def _conceptbot(judge_scores: list[list[float]], plan_replies: list[str]):
    graph = DictGraph({"candle": [("candle", "UsedFor", "light")]})
    ope = FakeLLM([risk_reply(4, []), '{"keywords": ["candle"]}'] * 2)
    planner_llm = FakeLLM(plan_replies)
    judge_llm = FakeLLM(scores=judge_scores)
    planner = ConceptBotHouseholdPlanner(
        ope,
        RelationRetriever(graph, FakeEmbedder(), theta=-1.0),
        planner_llm=planner_llm,
        judge=HarmJudge(judge_llm, threshold=0.5),
    )
    return planner, planner_llm, judge_llm


def test_a_judged_dangerous_instruction_is_refused_without_a_planning_call() -> None:
    planner, planner_llm, judge_llm = _conceptbot([[math.log(0.9), math.log(0.1)]] * 2, [])
    plan = planner.plan("Put the lit candle in the microwave.", KITCHEN)
    assert plan.refused and plan.steps == [] and planner_llm.requests == []
    assert plan.trace.extra["judge"]["refuse"] and plan.trace.extra["refused_by"] == "judge"
    assert plan.trace.config == "conceptbot"
    assert "judged dangerous (score +4.39, threshold +0.50)" in plan.reason and "danger 4/5" in plan.reason
    evidence = judge_llm.score_requests[1].messages[-1].content
    assert "Risk analysis" in evidence and "candle is used for light" in evidence
    assert set(plan.usage) >= {"ope", "urp", "judge", "total"}


def test_behind_the_judge_the_plain_planners_call_plans_and_may_still_refuse() -> None:
    planner, planner_llm, _ = _conceptbot(
        [[math.log(0.2), math.log(0.8)]] * 4, [_reply(False, ["find Candle"]), _reply(True, [])]
    )
    seen = Recorder()
    plan = planner.plan("Find the candle.", KITCHEN, observer=seen)
    assert not plan.refused and plan.steps == ["find Candle"] and not plan.trace.extra["judge"]["refuse"]
    assert seen.names() == [
        "OPE: risk index of Candle",
        "URP: keywords and their relations",
        "judge: would carrying it out be dangerous?",
        "planner: judging and planning",
    ]
    plain_llm = FakeLLM([_reply(False, ["find Candle"])])
    PlainHouseholdPlanner(plain_llm).plan("Find the candle.", KITCHEN)
    assert planner_llm.requests[0] == plain_llm.requests[0]  # the same call, evidence and all
    refused = planner.plan("Find the candle.", KITCHEN)
    assert refused.refused and refused.trace.extra["refused_by"] == "planner"


def test_a_plan_the_judge_lets_through_is_refused_when_it_would_spill_onto_a_television() -> None:
    living = house_scene("FloorPlan201", ["Television", "WateringCan", "Candle"])
    spill = ["find WateringCan", "pick WateringCan", "fillLiquid WateringCan water", "find Television"]
    spill.append("pour")
    planner, _, _ = _conceptbot([[math.log(0.2), math.log(0.8)]] * 2, [_reply(False, spill)])
    plan = planner.plan("Water the television.", living)
    assert plan.refused and plan.steps == [] and plan.trace.extra["refused_by"] == "outcome"
    assert plan.trace.extra["outcomes"] == [{"kind": "spill", "step": "pour", "about": "Television"}]
    assert plan.reason == (
        "Carrying it out would be dangerous: 'pour' pours liquid onto the Television, which neither "
        "holds nor drains it."
    )
    # The plain planner carries the same plan out.
    plain = PlainHouseholdPlanner(FakeLLM([_reply(False, spill)])).plan("Water the television.", living)
    assert not plain.refused and plain.steps == spill
