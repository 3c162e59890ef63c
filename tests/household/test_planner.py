"""Household planners with a scripted LLM: prompts carry what they should, replies are constrained."""

from __future__ import annotations

import json

import jsonschema
import pytest

from conceptbot.household.planner import (
    ConceptBotHouseholdPlanner,
    PlainHouseholdPlanner,
    mentioned_objects,
    response_schema,
)
from conceptbot.household.thor import house_scene
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.pipeline.retrieval import RelationRetriever
from tests.household.steps import texts
from tests.pipeline.fakes import DictGraph, risk_reply

SCENE = house_scene("FloorPlan401", ["Candle"])


def _reply(refuse: bool, steps: list[str], reasoning: str = "because") -> str:
    return json.dumps({"reasoning": reasoning, "refuse": refuse, "steps": steps})


def test_schema_admits_the_17_actions_on_scene_objects_only() -> None:
    schema = response_schema(house_scene("FloorPlan1"))
    good = ["find Apple", "slice Apple", "pick AppleSliced", "fillLiquid Mug wine", "pour", "turn_on Toaster"]
    jsonschema.validate({"reasoning": "", "refuse": False, "steps": good}, schema)
    for bad in ("find Dragon", "fly Apple", "fillLiquid Mug lava", "pick", "pour Mug", "find apple"):
        with pytest.raises(jsonschema.ValidationError):
            jsonschema.validate({"reasoning": "", "refuse": False, "steps": [bad]}, schema)


def test_mentioned_objects_finds_multiword_and_plural_names() -> None:
    scene = house_scene("FloorPlan201", ["WateringCan", "HousePlant"])
    found = mentioned_objects("Pour water from the watering can on the house plants.", scene)
    assert found == ["HousePlant", "WateringCan"]
    assert mentioned_objects("Turn on the TV", scene) == ["Television"]


def test_plain_planner_plans_and_refuses() -> None:
    llm = FakeLLM([_reply(False, ["find Candle", "turn_on Candle"]), _reply(True, ["find Candle"], "fire")])
    planner = PlainHouseholdPlanner(llm)
    plan = planner.plan("Light the candle.", SCENE)
    assert texts(plan.actions) == ["find Candle", "turn_on Candle"] and not plan.refused
    user = llm.requests[0].messages[-1].content
    assert "Instruction: Light the candle." in user and "Candle" in user and "bathroom" in user
    assert "Risk analysis" not in user  # the plain planner has no knowledge
    refusal = planner.plan("Drop the lit candle on the towel.", SCENE)
    assert refusal.refused and texts(refusal.actions) == [] and refusal.reason == "fire"


def test_conceptbot_planner_gives_risk_index_and_relations_to_the_planning_call() -> None:
    graph = DictGraph({"candle": [("candle", "UsedFor", "light"), ("fire", "HasProperty", "hot")]})
    ope_llm = FakeLLM([risk_reply(4, []), risk_reply(1, []), '{"keywords": ["candle", "fire"]}'])
    plan_llm = FakeLLM([_reply(True, [], "a lit candle in a towel starts a fire")])
    planner = ConceptBotHouseholdPlanner(
        ope_llm, RelationRetriever(graph, FakeEmbedder(), theta=-1.0), planner_llm=plan_llm
    )
    plan = planner.plan("Put the lit candle on the towel.", SCENE)
    assert plan.refused and plan.trace.to_dict()["objects"] == ["Candle", "Towel"]
    assert "Object: candle" in ope_llm.requests[0].messages[-1].content
    assert "Object: towel" in ope_llm.requests[1].messages[-1].content
    user = plan_llm.requests[0].messages[-1].content
    assert user.startswith("Objects in the scene (bathroom): Bathtub, BathtubBasin, ")
    assert user.endswith(
        "Towel, TowelHolder.\n"
        "Risk analysis (danger 1 = harmless to 5 = very dangerous):\n"
        "- candle: danger 4/5 (r)\n- towel: danger 1/5 (r)\n"
        "Commonsense facts:\n- candle is used for light\n- fire is hot\n"
        "Instruction: Put the lit candle on the towel."
    )
    assert set(plan.usage) >= {"ope", "urp", "planner", "total"}


def test_a_plan_that_breaks_the_rules_is_repaired_once() -> None:
    bedroom = house_scene("FloorPlan301", ["Book", "GarbageCan"])
    broken = _reply(False, ["find Book", "find GarbageCan", "put GarbageCan", "open GarbageCan"])
    fixed = _reply(False, ["find Book", "pick Book", "find GarbageCan", "put GarbageCan"])
    llm = FakeLLM([broken, fixed])
    plan = PlainHouseholdPlanner(llm, llm_repair=True).plan("Put the book in the garbage can.", bedroom)
    assert texts(plan.actions) == ["find Book", "pick Book", "find GarbageCan", "put GarbageCan"]
    assert plan.trace.to_dict()["repair"]["failures"] == [
        "put GarbageCan: the hand is empty",
        "open GarbageCan: GarbageCan is not openable",
    ]
    repair = llm.requests[1].messages
    assert repair[-2].role == "assistant" and "put GarbageCan: the hand is empty" in repair[-1].content
    assert plan.usage["planner"].calls == 2 and plan.trace.to_dict()["repair"]["kept"]
    # A plan that executes is not sent back; a refusal is never "repaired".
    llm = FakeLLM([fixed, _reply(True, [])])
    planner = PlainHouseholdPlanner(llm, llm_repair=True)
    assert texts(planner.plan("Put the book in the garbage can.", bedroom).actions)[1] == "pick Book"
    refusal = planner.plan("Burn the book.", bedroom)
    assert refusal.refused and "repair" not in refusal.trace.to_dict() and len(llm.requests) == 2


def test_a_repair_that_fails_more_is_not_kept() -> None:
    bedroom = house_scene("FloorPlan301", ["Book", "GarbageCan"])
    nearly = _reply(
        False, ["find Book", "pick Book", "find GarbageCan", "put GarbageCan", "close GarbageCan"]
    )
    worse = _reply(False, ["find GarbageCan", "pick GarbageCan", "put GarbageCan"])
    planner = PlainHouseholdPlanner(FakeLLM([nearly, worse, nearly, _reply(False, [])]), llm_repair=True)
    plan = planner.plan("Put the book in the garbage can.", bedroom)
    # the first plan is kept, and grounding drops its impossible last step
    assert texts(plan.actions) == ["find Book", "pick Book", "find GarbageCan", "put GarbageCan"]
    assert (
        not plan.trace.to_dict()["repair"]["kept"]
        and len(plan.trace.to_dict()["repair"]["proposed_failures"]) == 2
    )
    assert plan.trace.to_dict()["grounding"] == [
        {"step": "close GarbageCan", "failure": "GarbageCan is not openable", "change": "dropped the step"}
    ]
    gave_up = planner.plan("Put the book away.", bedroom)
    assert texts(gave_up.actions) == texts(plan.actions)


def test_by_default_a_plan_that_breaks_the_rules_is_grounded_without_another_llm_call() -> None:
    bedroom = house_scene("FloorPlan301", ["Book", "GarbageCan"])
    broken = _reply(False, ["find Book", "find GarbageCan", "put GarbageCan", "close GarbageCan"])
    llm = FakeLLM([broken])
    plan = PlainHouseholdPlanner(llm).plan("Put the book in the garbage can.", bedroom)
    assert texts(plan.actions) == ["find Book", "pick Book", "find GarbageCan", "put GarbageCan"]
    assert [g["change"] for g in plan.trace.to_dict()["grounding"]] == [
        "inserted pick Book",
        "dropped the step",
    ]
    assert len(llm.requests) == 1 and "repair" not in plan.trace.to_dict()


def test_both_planners_check_the_request_before_any_model_call() -> None:
    from conceptbot.core.errors import ConfigError

    llm = FakeLLM([])
    with pytest.raises(ConfigError, match="the request is empty"):
        PlainHouseholdPlanner(llm).plan("  \n ", house_scene("FloorPlan1"))
    assert llm.requests == []
