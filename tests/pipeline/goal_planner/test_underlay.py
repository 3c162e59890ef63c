"""A mat or stand of the scene under what needs one: "put the casserole dish on the dining table",
the dish just out of the oven, puts the cork mat on the table first and the dish on the mat."""

from __future__ import annotations

import math

import pytest
from jsonschema import Draft202012Validator

from conceptbot.core.plan import format_actions, plan_schema
from conceptbot.core.scene import Scene, scene_from_dict
from conceptbot.core.usage import Usage
from conceptbot.models.fake import FakeEmbedder, FakeLLM
from conceptbot.pipeline.goal_planner.decide import Decider, FactFinder
from conceptbot.pipeline.goal_planner.planner import GoalPlanner
from conceptbot.pipeline.goal_planner.targets import Target, TargetsRead
from conceptbot.pipeline.retrieval import RelationRetriever
from tests.pipeline.fakes import DictGraph

#: The graph's word on the places: a table heat can mark; an oven, which is an appliance.
GRAPH = DictGraph(
    {
        "dining table": [("dining table", "IsA", "table")],
        "oven": [("oven", "IsA", "kitchen appliance")],
        "cork mat": [("cork mat", "UsedFor", "put a hot pot on")],
    }
)


def _facts() -> FactFinder:
    return FactFinder(RelationRetriever(GRAPH, FakeEmbedder(), 0.2))


DINNER = scene_from_dict(
    {
        "name": "dinner",
        "pickable_objects": ["casserole dish", "cork mat", "salad bowl"],
        "destinations": ["dining table", "cork mat", "user"],
        "entity_states": {"casserole dish": "just out of the oven, very hot"},
    }
)
PRIOR = [-1.0, -1.0]  # the content-free object
SAFE = [-0.05, -3.0]  # "is it safe to ...?" Yes
YES = [-0.5, -1.0]  # "is it too hot to put straight on the table?" P(Yes) 0.62
NO = [-1.5, -0.3]  # P(Yes) 0.23


class Named:
    """Targets as given (the reader is tested on its own)."""

    def __init__(self, targets: list[Target]) -> None:
        self.targets = targets

    def read(self, request: str, scene: Scene) -> TargetsRead:
        return TargetsRead(False, list(self.targets), Usage(calls=0))


def _plan(answer: list[float], scene: Scene = DINNER, obj: str = "casserole dish"):
    llm = FakeLLM(scores=[PRIOR, SAFE, PRIOR, answer])  # risk question, then the mat question
    planner = GoalPlanner(Named([Target("dining table", 1, "named", [obj])]), Decider(llm, _facts()))
    return planner.plan(f"Put the {obj} on the dining table.", scene), llm


def test_a_hot_dish_goes_on_its_mat_and_the_mat_first() -> None:
    result, llm = _plan(YES)
    assert format_actions(result.actions) == [
        "pick_and_place(cork mat, dining table)",
        "pick_and_place(casserole dish, cork mat)",
        "done()",
    ]
    # the question carries the object's state, and the trace says what was asked and decided
    asked = llm.score_requests[-1].messages[-1].content
    assert "casserole dish (just out of the oven, very hot)" in asked and "too hot" in asked
    [check] = result.trace.underlay
    assert (check.object, check.place, check.pad, check.used) == (
        "casserole dish",
        "dining table",
        "cork mat",
        True,
    )
    trace = result.trace.to_dict()
    assert trace["underlay"][0]["used"] is True and result.usage["underlay"].calls == 2
    schema = plan_schema()
    Draft202012Validator({**schema["properties"]["trace"], "$defs": schema.get("$defs", {})}).validate(
        {"underlay": trace["underlay"]}
    )


def test_no_mat_where_the_model_says_none_is_needed() -> None:
    result, _ = _plan(NO)
    assert format_actions(result.actions) == ["pick_and_place(casserole dish, dining table)", "done()"]
    assert [c.used for c in result.trace.underlay] == [False]


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_an_answer_that_cannot_be_read_adds_no_mat_and_shows_as_null(bad: float) -> None:
    result, _ = _plan([bad, bad])
    assert format_actions(result.actions) == ["pick_and_place(casserole dish, dining table)", "done()"]
    [check] = result.trace.to_dict()["underlay"]
    assert check["used"] is False and check["p_yes"] is None


def test_nothing_is_asked_in_a_scene_without_a_mat() -> None:
    bare = scene_from_dict(
        {"pickable_objects": ["casserole dish", "salad bowl"], "destinations": ["dining table", "user"]}
    )
    llm = FakeLLM(scores=[PRIOR, SAFE])
    planner = GoalPlanner(
        Named([Target("dining table", 1, "named", ["casserole dish"])]), Decider(llm, FactFinder(None))
    )
    result = planner.plan("Put the casserole dish on the dining table.", bare)
    assert format_actions(result.actions) == ["pick_and_place(casserole dish, dining table)", "done()"]
    assert result.trace.underlay is None and len(llm.score_requests) == 2
    assert "underlay" not in result.usage  # the usage keys are a contract: only where asked


def test_each_pad_serves_one_hot_object_and_is_never_its_own_place() -> None:
    two = scene_from_dict(
        {
            "pickable_objects": ["pie dish", "casserole dish", "cork mat"],
            "destinations": ["dining table", "cork mat"],
        }
    )
    targets = [Target("dining table", 2, "named", ["pie dish", "casserole dish"])]
    llm = FakeLLM(scores=[PRIOR, SAFE, PRIOR, SAFE, PRIOR, YES])
    result = GoalPlanner(Named(targets), Decider(llm, _facts())).plan("Serve both dishes.", two)
    # the first hot dish takes the one mat; the second has none left and is not asked about
    assert format_actions(result.actions) == [
        "pick_and_place(cork mat, dining table)",
        "pick_and_place(pie dish, cork mat)",
        "pick_and_place(casserole dish, dining table)",
        "done()",
    ]
    assert [c.object for c in result.trace.underlay] == ["pie dish"] and len(llm.score_requests) == 6


@pytest.mark.parametrize(("place", "facts"), [("oven", _facts), ("dining table", lambda: FactFinder(None))])
def test_no_mat_is_asked_about_where_the_graph_names_no_surface_heat_can_mark(place: str, facts) -> None:
    # an oven is an appliance; without a graph (the ablation) no place is known to be a surface
    scene = scene_from_dict(
        {
            "pickable_objects": ["casserole dish", "cork mat"],
            "destinations": [place, "cork mat"],
            "entity_states": {"casserole dish": "very hot"},
        }
    )
    llm = FakeLLM(scores=[PRIOR, SAFE])
    planner = GoalPlanner(Named([Target(place, 1, "named", ["casserole dish"])]), Decider(llm, facts()))
    result = planner.plan(f"Put the casserole dish on the {place}.", scene)
    assert format_actions(result.actions) == [f"pick_and_place(casserole dish, {place})", "done()"]
    assert not result.trace.underlay and len(llm.score_requests) == 2
