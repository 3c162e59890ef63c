"""The goal planner: goal compilation, per-object decisions with graph facts, risk constraints."""

from __future__ import annotations

import json

import pytest

from conceptbot.core.scene import scene_from_dict
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.pipeline.conceptbot import ConceptBot
from conceptbot.pipeline.decide import Decider, FactFinder
from conceptbot.pipeline.goal import GoalCompiler, goal_schema, named_objects
from conceptbot.pipeline.goal_planner import GoalPlanner
from conceptbot.pipeline.retrieval import RelationRetriever
from tests.pipeline.fakes import DictGraph

SCENE = scene_from_dict(
    {
        "name": "craft",
        "pickable_objects": ["scissors", "safety scissors", "glue", "chips"],
        "destinations": ["child", "table"],
    }
)


@pytest.mark.parametrize(
    ("what", "expected"),
    [
        ("a bag of chips", ("chips",)),
        ("safety scissors", ("safety scissors",)),
        ("the glue and the scissors", ("glue", "scissors")),
        ("something to cut paper", ()),
        ("Scissors", ("scissors",)),
    ],
)
def test_named_objects(what: str, expected: tuple[str, ...]) -> None:
    assert named_objects(what, SCENE.pickable) == expected


def test_a_part_of_one_name_names_it() -> None:
    assert named_objects("the chips", ["multigrain chips", "apple"]) == ("multigrain chips",)
    assert named_objects("soda", ["lime soda", "orange soda"]) == ()


def test_the_schema_only_allows_the_scenes_destinations() -> None:
    items = goal_schema(SCENE)["properties"]["tasks"]["items"]["properties"]
    assert items["to"]["enum"] == ["child", "table"]
    assert items["how_many"]["enum"] == ["one", "all"]


def test_facts_include_what_the_graph_says_about_parents() -> None:
    graph = DictGraph(
        {
            "green hellebore": [("green hellebore", "IsA", "hellebore")],
            "hellebore": [("hellebore", "IsA", "poisonous plant"), ("hellebore", "HasProperty", "green")],
        }
    )
    finder = FactFinder(RelationRetriever(graph, FakeEmbedder(), theta=-1.0))
    facts = finder.about(["green hellebore"], ["poisonous"])["green hellebore"]
    assert "green hellebore is a hellebore" in facts and "hellebore is a poisonous plant" in facts
    assert FactFinder(None).about(["x"], ["y"]) == {"x": ()}


def test_decisions_are_calibrated_against_a_content_free_object() -> None:
    # Prior (content-free) log-odds +1: an object needs more than that to count as a fit.
    llm = FakeLLM(scores=[[-0.3, -1.3], [-0.1, -2.1], [-0.6, -0.8]])
    decider = Decider(llm, FactFinder(None))
    judgements, _, _ = decider.fits("give me a snack", "a snack", "one", ["chips", "glue"], SCENE)
    assert [j.subject for j in judgements] == ["chips", "glue"]
    assert judgements[0].score == pytest.approx(1.0) and judgements[1].score == pytest.approx(-0.8)
    assert judgements[0].p_yes > 0.85
    questions = [r.messages[-1].content for r in llm.score_requests]
    assert "Object: object" in questions[0] and "Object: chips" in questions[1]
    assert all('"a snack"' in q for q in questions)


def _goal(*tasks: tuple[str, str, str], stack: bool = False) -> str:
    return json.dumps({"tasks": [{"what": w, "how_many": c, "to": t} for w, c, t in tasks], "stack": stack})


def test_a_move_judged_dangerous_is_dropped_and_one_takes_the_next_best() -> None:
    scores = [
        [-1.0, -1.0],  # prior for "something to cut paper"
        [-0.1, -3.0],  # scissors: fits best
        [-0.2, -2.5],  # safety scissors: next
        [-3.0, -0.1],  # glue: no
        [-3.0, -0.1],  # chips: no
        [-0.05, -3.0],  # risk: give the scissors to the child -> dangerous
        [-3.0, -0.05],  # risk: give the safety scissors to the child -> fine
    ]
    llm = FakeLLM([_goal(("something to cut paper", "one", "child"))], scores=scores)
    planner = GoalPlanner(GoalCompiler(llm), Decider(llm, FactFinder(None)))
    result = planner.plan("Give my son something to cut paper", SCENE)
    assert result.actions == ["pick_and_place(safety scissors, child)", "done()"]
    dropped = [r for r in result.trace["risk"] if r["dropped"]]
    assert [(r["object"], r["why"]) for r in dropped] == [("scissors", "judged dangerous")]
    assert result.steps[0].chosen == "pick_and_place(safety scissors, child)"
    assert not result.refused


def test_named_objects_skip_the_decisions_and_a_blocked_only_move_is_a_refusal() -> None:
    llm = FakeLLM([_goal(("scissors", "one", "child"))], scores=[[-0.05, -3.0]])
    planner = GoalPlanner(GoalCompiler(llm), Decider(llm, FactFinder(None)))
    result = planner.plan("Give the child the scissors", SCENE)
    assert result.actions == ["done()"] and result.refused
    assert "give the scissors to the child: judged dangerous" in (result.reason or "")
    assert result.trace["decisions"][0]["decided"] is False


def test_all_selections_take_every_fitting_object_and_conflicts_go_to_the_best_fit() -> None:
    scores = [
        [-1.0, -1.0],  # prior "edible"
        [-3.0, -0.1],  # scissors
        [-3.0, -0.1],  # safety scissors
        [-1.0, -1.5],  # glue: weakly edible (+0.5)
        [-0.1, -3.0],  # chips: edible
        [-1.0, -1.0],  # prior "sticky"
        [-3.0, -0.1],
        [-3.0, -0.1],
        [-0.1, -3.0],  # glue: sticky (+2.9) beats edible (+0.5)
        [-3.0, -0.1],
    ] + [[-3.0, -0.1]] * 2  # two risk checks: fine
    llm = FakeLLM([_goal(("edible", "all", "table"), ("sticky", "all", "child"))], scores=scores)
    planner = GoalPlanner(GoalCompiler(llm), Decider(llm, FactFinder(None)))
    result = planner.plan("Food on the table, sticky things to the child", SCENE)
    assert result.actions == ["pick_and_place(chips, table)", "pick_and_place(glue, child)", "done()"]


def test_conceptbot_uses_the_goal_planner_when_asked() -> None:
    scores = [[-0.1, -3.0]]  # one risk check
    llm = FakeLLM([_goal(("glue", "one", "table"))], scores=scores)
    bot = ConceptBot(llm, RelationRetriever(DictGraph(), FakeEmbedder(), theta=0.1), "urp", planner="goal")
    plan = bot.plan("Put the glue on the table", SCENE)
    assert plan.trace["planner_kind"] == "goal" and plan.refused
    assert set(plan.usage) >= {"goal", "decide", "risk", "total"}
    json.dumps(plan.to_dict())
    default = ConceptBot(FakeLLM(scores=[]), None, "nokg")
    assert default.planner_kind == "steps"
