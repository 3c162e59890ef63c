"""The harm judge: a scored yes/no decision, and the ConceptBot household planner built on it."""

from __future__ import annotations

import json
import math
import re

import pytest

from conceptbot.household.harm import HarmModel
from conceptbot.household.judge import TWO_READINGS, HarmJudge, HarmVerdict, safety_text
from conceptbot.household.planner import ConceptBotHouseholdPlanner, PlainHouseholdPlanner
from conceptbot.household.thor import house_scene
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.pipeline.retrieval import RelationRetriever
from tests.household.steps import texts
from tests.pipeline.fakes import DictGraph, Recorder, risk_reply

KITCHEN = house_scene("FloorPlan1", ["Candle", "Mug", "Microwave"])


def _reply(refuse: bool, steps: list[str]) -> str:
    return json.dumps({"reasoning": "r", "refuse": refuse, "steps": steps})


def _odds(yes: float) -> list[float]:
    return [math.log(yes), math.log(1 - yes)]


def test_the_verdict_adds_four_readings_of_dangerous_and_compares_the_threshold() -> None:
    # informed, blind, other examples, "ordinary chore?" (Yes there means safe).
    llm = FakeLLM(scores=[_odds(0.6), _odds(0.8), _odds(0.7), _odds(0.9)])
    judge = HarmJudge(llm, threshold=1.0)
    risky, _ = judge.judge(
        "Put the mug with a fork in the microwave.", KITCHEN, "Risk analysis: fork, danger 5/5"
    )
    assert risky.readings["informed"] == pytest.approx(math.log(1.5))  # 0.6 / 0.4
    assert risky.readings["blind"] == pytest.approx(math.log(4))
    assert risky.readings["other_examples"] == pytest.approx(math.log(7 / 3))
    assert risky.readings["ordinary"] == pytest.approx(math.log(1 / 9))  # "ordinary": 0.9
    assert risky.log_odds == pytest.approx(math.log(1.5 * 4 * 7 / 3 / 9), rel=1e-9)
    assert not risky.refuse  # +0.44 < +1.0: the turned-round question pulls the score down
    assert risky.to_dict()["refuse"] is False and set(risky.to_dict()["readings"]) == set(risky.readings)
    informed, blind, other, ordinary = llm.score_requests
    assert all(r.options == ("Yes", "No") for r in llm.score_requests)
    assert safety_text() in informed.messages[0].content and "-> Yes" in informed.messages[0].content
    assert "Instruction: Put the mug with a fork in the microwave." in informed.messages[1].content
    assert "danger 5/5" in informed.messages[1].content and "danger 5/5" not in blind.messages[1].content
    assert "Microwave" in blind.messages[1].content and blind.messages[0] == informed.messages[0]
    assert other.messages[1] == blind.messages[1] and other.messages[0] != blind.messages[0]
    assert ordinary.messages[1].content.endswith(
        "Is carrying out this instruction an ordinary, harmless chore?\n"
    )
    assert not HarmVerdict(0.99, 1.0).refuse and HarmVerdict(1.0, 1.0).refuse


def test_without_evidence_the_blind_reading_counts_for_the_informed_one() -> None:
    llm = FakeLLM(scores=[_odds(0.3), _odds(0.5), _odds(0.5)])
    verdict, _ = HarmJudge(llm, threshold=1.0).judge("Put the mug in the microwave.", KITCHEN)
    assert verdict.readings["informed"] == verdict.readings["blind"] == pytest.approx(math.log(3 / 7))
    assert verdict.log_odds == pytest.approx(2 * math.log(3 / 7)) and not verdict.refuse
    assert len(llm.score_requests) == 3


def test_the_v3_judge_adds_two_readings_and_each_system_prompt_can_have_its_own_backend() -> None:
    llm = FakeLLM(scores=[_odds(0.6), _odds(0.8)])
    verdict, _ = HarmJudge(llm, questions=TWO_READINGS).judge("Open the fridge.", KITCHEN, "facts")
    assert verdict.log_odds == pytest.approx(math.log(6)) and list(verdict.readings) == ["informed", "blind"]
    main, other = FakeLLM(scores=[_odds(0.5)] * 3), FakeLLM(scores=[_odds(0.5)])
    HarmJudge(main, contexts={"household_judge_system_examples2": other}).judge("Open it.", KITCHEN)
    assert len(main.score_requests) == 2 and len(other.score_requests) == 1
    with pytest.raises(ValueError):
        HarmJudge(llm, questions=())


def test_both_planners_share_the_safety_instruction() -> None:
    llm = FakeLLM([_reply(False, ["find Mug"])])
    PlainHouseholdPlanner(llm).plan("Find the mug.", KITCHEN)
    assert safety_text() + ": plan it completely" in llm.requests[0].messages[0].content


READINGS_MODEL = HarmModel(
    {"informed": 1.0, "blind": 1.0, "other_examples": 1.0, "ordinary": 1.0}, 0.0, 0.5, {}
)
"""The four readings added, refused at +0.5 (the earlier judge's rule, as a fitted model)."""


def _conceptbot(judge_scores: list[list[float]], plan_replies: list[str], harm: HarmModel = READINGS_MODEL):
    graph = DictGraph({"candle": [("candle", "UsedFor", "light")]})
    ope = FakeLLM([risk_reply(4, []), '{"keywords": ["candle"]}'] * 2)
    planner_llm = FakeLLM(plan_replies)
    judge_llm = FakeLLM(scores=judge_scores)
    planner = ConceptBotHouseholdPlanner(
        ope,
        RelationRetriever(graph, FakeEmbedder(), theta=-1.0),
        planner_llm=planner_llm,
        judge=HarmJudge(judge_llm),
        harm=harm,
    )
    return planner, planner_llm, judge_llm


def test_a_dangerous_score_refuses_the_plan_of_what_was_asked() -> None:
    planner, planner_llm, judge_llm = _conceptbot(
        [[math.log(0.9), math.log(0.1)]] * 4, [_reply(False, ["put Candle Microwave"])]
    )
    plan = planner.plan("Put the lit candle in the microwave.", KITCHEN)
    assert plan.refused and texts(plan.actions) == [] and len(planner_llm.requests) == 1
    assert plan.trace.to_dict()["task_steps"] == ["put Candle Microwave"]  # as the call wrote it
    schema = planner_llm.requests[0].json_schema
    steps = (json.loads(schema) if isinstance(schema, str) else schema)["properties"]["steps"]
    assert re.match(steps["items"]["pattern"], "put Candle Microwave")
    assert not re.match(steps["items"]["pattern"], "pour") and steps["maxItems"] == 10
    assert plan.trace.to_dict()["judge"]["refuse"] and plan.trace.to_dict()["refused_by"] == "judge"
    assert plan.trace.config == "conceptbot"
    assert "judged dangerous (score +4.39, threshold +0.50). The plan would leave:" in plan.reason
    assert "the Candle is in or on the Microwave" in plan.reason  # the outcome that was weighed
    # The judgement weighs no evidence: neither OPE nor URP is asked, the judge sees no graph facts.
    assert all(
        "Risk analysis" not in r.messages[-1].content
        and "candle is used for light" not in r.messages[-1].content
        for r in judge_llm.score_requests
    )
    signals = plan.trace.to_dict()["judge"]["readings"]
    assert "risk" not in signals and signals["outcome"] == 0.0 and signals["no_plan"] == 0
    assert set(plan.usage) == {"judge", "planner", "total"}


def test_the_planning_call_plans_what_was_asked_and_leaves_the_decision_to_the_judgement() -> None:
    planner, planner_llm, _ = _conceptbot(
        [[math.log(0.2), math.log(0.8)]] * 8, [_reply(False, ["find Candle"]), _reply(True, ["find Candle"])]
    )
    seen = Recorder()
    plan = planner.plan("Find the candle.", KITCHEN, observer=seen)
    assert not plan.refused and texts(plan.actions) == ["find Candle"]
    assert seen.names() == [
        "judge: would carrying it out be dangerous?",
        "planner: planning what was asked",
    ]
    request = planner_llm.requests[0]
    assert "Do not judge it" in request.messages[0].content and "refuse" not in request.messages[0].content
    assert request.json_schema is None or "refuse" not in request.json_schema
    # what the call writes about refusing does not refuse: only the judgement does
    again = planner.plan("Find the candle.", KITCHEN)
    assert not again.refused and texts(again.actions) == ["find Candle"]


WATER_PLANT = "pour WateringCan water HousePlant"  # the task step ConceptBot's planning call writes
POUR_ON_PLANT = [
    "find WateringCan",
    "pick WateringCan",
    "fillLiquid WateringCan water",
    "find HousePlant",
    "pour",
]
SPILLS = HarmModel({**READINGS_MODEL.weights, "spill": 5.0}, 0.0, 0.5, {})


def test_a_refusal_changes_with_what_the_plan_does_not_with_a_verb() -> None:
    living = house_scene("FloorPlan201", ["Television", "WateringCan", "HousePlant"])
    calm = [[math.log(0.3), math.log(0.7)]] * 4  # score -0.85 + 0.85 = 0: the readings alone let it go
    on_tv, on_plant = _reply(False, ["pour WateringCan water Television"]), _reply(False, [WATER_PLANT])
    planner, _, _ = _conceptbot(calm * 4, [on_tv, on_plant], SPILLS)
    onto_tv = planner.plan("Give it some water.", living)
    onto_plant = planner.plan("Give it some water.", living)
    assert onto_tv.refused and onto_tv.trace.to_dict()["refused_by"] == "judge"
    assert onto_tv.trace.to_dict()["outcomes"] == [{"kind": "spill", "step": "pour", "about": "Television"}]
    assert not onto_plant.refused and texts(onto_plant.actions) == POUR_ON_PLANT
    # the same plan and the same readings, asked with an alarming verb or a calm one: one decision
    planner, _, _ = _conceptbot(calm * 4, [on_plant] * 2, SPILLS)
    splash = planner.plan("Throw water at the house plant, drench it.", living)
    water = planner.plan("Water the house plant.", living)
    assert not splash.refused and not water.refused
    assert splash.trace.to_dict()["judge"] == water.trace.to_dict()["judge"]


def test_a_signal_that_cannot_be_read_refuses() -> None:
    planner, _, _ = _conceptbot([[math.log(0.2), math.log(0.8)]] * 4, [_reply(False, ["find Candle"])])
    planner.harm = HarmModel({**READINGS_MODEL.weights, "missing_signal": 1.0}, 0.0, 0.5, {})
    plan = planner.plan("Find the candle.", KITCHEN)
    assert plan.refused and "score +nan" in plan.reason


def test_the_outcome_judge_reads_what_a_plan_leaves_against_a_result_where_nothing_changed() -> None:
    from conceptbot.household.judge import OutcomeJudge

    llm = FakeLLM(scores=[_odds(0.5), _odds(0.9), _odds(0.2)])
    judge = OutcomeJudge(llm)
    fire, _ = judge.reading(
        KITCHEN, ["the Candle is in or on the Microwave", "the Microwave is left switched on"]
    )
    assert fire == pytest.approx(math.log(9))  # 0.9 against the content-free 0.5
    tidy, _ = judge.reading(KITCHEN, ["the Mug is in or on the Microwave"])
    assert tidy == pytest.approx(math.log(0.25))
    assert judge.reading(KITCHEN, [])[0] == 0.0  # nothing changed: nothing to judge
    assert "- the Microwave is left switched on" in llm.score_requests[1].messages[1].content
