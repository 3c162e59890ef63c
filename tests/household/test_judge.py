"""The harm judge: a scored yes/no decision, and the ConceptBot household planner built on it."""

from __future__ import annotations

import json
import math

import jsonschema
import pytest

from conceptbot.household.judge import HarmJudge, HarmVerdict, safety_text
from conceptbot.household.planner import ConceptBotHouseholdPlanner, PlainHouseholdPlanner, response_schema
from conceptbot.household.thor import house_scene
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.pipeline.retrieval import RelationRetriever
from tests.pipeline.fakes import DictGraph, risk_reply

KITCHEN = house_scene("FloorPlan1", ["Candle", "Mug", "Microwave"])


def _reply(refuse: bool, steps: list[str]) -> str:
    return json.dumps({"reasoning": "r", "refuse": refuse, "steps": steps})


def test_the_verdict_compares_the_log_odds_of_yes_with_the_threshold() -> None:
    llm = FakeLLM(scores=[[math.log(0.8), math.log(0.2)], [math.log(0.3), math.log(0.7)]])
    judge = HarmJudge(llm, threshold=1.0)
    risky, _ = judge.judge(
        "Put the mug with a fork in the microwave.", KITCHEN, "Risk analysis: fork, danger 5/5"
    )
    assert risky.log_odds == pytest.approx(math.log(4)) and risky.refuse  # log 4 = 1.39 >= 1.0
    assert risky.p_dangerous == pytest.approx(0.8) and risky.to_dict()["refuse"] is True
    ordinary, _ = judge.judge("Put the mug in the microwave.", KITCHEN)
    assert not ordinary.refuse and ordinary.log_odds < 0
    asked = llm.score_requests[0]
    assert asked.options == ("Yes", "No")
    system, user = asked.messages
    assert safety_text() in system.content and "start a fire" in system.content
    assert "Instruction: Put the mug with a fork in the microwave." in user.content
    assert "danger 5/5" in user.content and "Microwave" in user.content
    assert not HarmVerdict(0.99, 1.0).refuse and HarmVerdict(1.0, 1.0).refuse


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
    planner, planner_llm, judge_llm = _conceptbot([[math.log(0.9), math.log(0.1)]], [])
    plan = planner.plan("Put the lit candle in the microwave.", KITCHEN)
    assert plan.refused and plan.steps == [] and planner_llm.requests == []
    assert plan.trace["judge"]["refuse"] and plan.trace["config"] == "conceptbot"
    assert "judged dangerous (P = 0.90)" in plan.reason and "danger 4/5" in plan.reason
    evidence = judge_llm.score_requests[0].messages[-1].content
    assert "Risk analysis" in evidence and "candle is used for light" in evidence
    assert set(plan.usage) >= {"ope", "urp", "judge", "total"}


def test_an_instruction_judged_safe_must_be_planned() -> None:
    planner, planner_llm, _ = _conceptbot([[math.log(0.2), math.log(0.8)]], [_reply(False, ["find Candle"])])
    plan = planner.plan("Find the candle.", KITCHEN)
    assert not plan.refused and plan.steps == ["find Candle"] and not plan.trace["judge"]["refuse"]
    schema = json.loads(planner_llm.requests[0].json_schema or "{}")
    with pytest.raises(jsonschema.ValidationError):  # the planning call cannot refuse any more
        jsonschema.validate({"reasoning": "", "refuse": True, "steps": []}, schema)
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate({"reasoning": "", "refuse": False, "steps": []}, schema)
    jsonschema.validate({"reasoning": "", "refuse": True, "steps": []}, response_schema(KITCHEN))
