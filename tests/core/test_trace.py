"""The typed trace: its JSON is the ``trace`` of ``conceptbot plan --json``, key for key."""

import json
from dataclasses import replace

import pytest

from conceptbot.core.trace import (
    DecisionTrace,
    EdgeTrace,
    GoalTrace,
    GroundingChange,
    HarmVerdict,
    HouseholdTrace,
    JudgementTrace,
    ObjectTrace,
    OPETrace,
    Outcome,
    PlannerSummary,
    PlanTrace,
    RetrievalTrace,
    RiskCheck,
    StackTrace,
    TargetTrace,
)

HEADER = {"config": "conceptbot", "planner_kind": "steps", "request": "Bring me chips", "scene": "spill"}
RETRIEVAL = RetrievalTrace(
    "knife",
    "exact",
    ("note",),
    (
        EdgeTrace("knife is sharp", "test", 0.5, "sharp", True),
        EdgeTrace("knife is a tool", "test", 0.1, "x", False),
    ),
)
OPE = OPETrace(
    "risk", "safety trigger: knife", {"knife": ObjectTrace({"dangerous": 4}, True, ("knife is sharp",))}
)
TARGET = TargetTrace("child", 1, "named", ("scissors",), 0.0, "", "", False)
CHECK = RiskCheck(
    "scissors", "child", "give the scissors to the child", 0.9, 2.1, (), None, 1.0, True, "judged dangerous"
)


def test_unset_parts_are_left_out_and_an_empty_trace_is_empty() -> None:
    assert PlanTrace().to_dict() == {}
    saycan = PlanTrace(config="saycan", request="r", scene="s").to_dict()
    assert saycan == {"config": "saycan", "request": "r", "scene": "s"}


def test_step_planner_json_keeps_keys_order_and_values() -> None:
    trace = PlanTrace(**HEADER, ope=OPETrace(OPE.mode, OPE.why, OPE.objects, {"knife": RETRIEVAL}))
    trace = replace(trace, planner=PlannerSummary("vote", 2))
    data = trace.to_dict()
    assert list(data) == [*HEADER, "ope", "planner"]
    assert data["ope"] == {
        "mode": "risk",
        "why": "safety trigger: knife",
        "objects": {
            "knife": {"values": {"dangerous": 4}, "cached": True, "relations_used": ["knife is sharp"]}
        },
        "retrieval": {
            "knife": {
                "matched": "knife",
                "match": "exact",
                "notes": ["note"],
                "edges": [
                    {
                        "relation": "knife is sharp",
                        "source": "test",
                        "similarity": 0.5,
                        "target": "sharp",
                        "kept": True,
                    },
                    {
                        "relation": "knife is a tool",
                        "source": "test",
                        "similarity": 0.1,
                        "target": "x",
                        "kept": False,
                    },
                ],
            }
        },
    }
    assert data["planner"] == {"method": "vote", "steps": 2}
    assert RETRIEVAL.kept == (RETRIEVAL.edges[0],)
    json.dumps(data)


def test_goal_planner_json_lists_ope_last_as_it_always_has() -> None:
    decided = DecisionTrace(
        TargetTrace("user", "all", "scored", (), 1.234, "edible", "", False),
        decided=True,
        objects=(JudgementTrace("chips", 0.8, 1.5, ("chips is a snack",), name_score=0.25),),
        context=("a snack is food",),
    )
    trace = PlanTrace(
        **{**HEADER, "planner_kind": "goal"},
        ope=OPE,
        goal=GoalTrace((TARGET,), False),
        decisions=(DecisionTrace(TARGET, decided=False), decided),
        stack=StackTrace("a base", (JudgementTrace("brick", 0.9, 2.0),)),
        risk=(CHECK,),
        planner=PlannerSummary("decide", 0),
    )
    data = trace.to_dict()
    assert list(data) == [*HEADER, "goal", "decisions", "stack", "risk", "planner", "ope"]
    target = {
        "to": "child",
        "count": 1,
        "how": "named",
        "named": ["scissors"],
        "score": 0.0,
        "criterion": "",
        "dish": "",
        "ingredients": False,
    }
    assert data["goal"] == {"targets": [target], "stack": False}
    # Not decided: no context; decided: the context before the objects; name_score only where ranked.
    assert data["decisions"][0] == {**target, "decided": False, "objects": []}
    assert list(data["decisions"][1])[-3:] == ["decided", "context", "objects"]
    assert data["decisions"][1]["objects"] == [
        {"object": "chips", "p_yes": 0.8, "score": 1.5, "facts": ["chips is a snack"], "name_score": 0.25}
    ]
    assert data["stack"] == {
        "base_question": "a base",
        "order": [{"object": "brick", "p_yes": 0.9, "score": 2.0, "facts": []}],
    }
    assert data["risk"][0]["why"] == "judged dangerous" and data["risk"][0]["ope"] is None


def test_a_household_part_writes_its_keys_after_the_config_in_the_planners_order() -> None:
    part = HouseholdTrace(
        objects=("Candle",),
        risk={"candle": {"danger": 4}},
        keywords=(),
        relations=("candle is used for light",),
        judge=HarmVerdict(1.23456, 0.5, {"informed": 1.23456}),
        grounding=(GroundingChange("put Shelf", "Shelf is closed", "inserted open Shelf"),),
        outcomes=(Outcome("spill", "pour", "Television"),),
        refused_by="outcome",
        reasoning="r",
    )
    data = PlanTrace(config="conceptbot", household=part).to_dict()
    assert list(data) == [
        "config", "objects", "risk", "keywords", "relations", "judge", "grounding", "outcomes",
        "refused_by", "reasoning",
    ]  # fmt: skip
    assert data["judge"] == {
        "log_odds": 1.235,
        "readings": {"informed": 1.235},
        "threshold": 0.5,
        "refuse": True,
    }
    assert data["objects"] == ["Candle"] and data["keywords"] == []
    assert data["outcomes"] == [{"kind": "spill", "step": "pour", "about": "Television"}]
    assert list(PlanTrace(config="plain", household=HouseholdTrace(reasoning="x")).to_dict()) == [
        "config",
        "reasoning",
    ]
    with pytest.raises(ValueError, match="no tabletop parts: risk"):
        PlanTrace(risk=(CHECK,), household=part)


def test_a_harm_score_that_cannot_be_compared_refuses() -> None:
    assert HarmVerdict(float("nan"), 0.5).refuse  # a NaN reading: the decision was not made
    assert HarmVerdict(0.5, 0.5).refuse and not HarmVerdict(0.49, 0.5).refuse


def test_answers_read_the_same_everywhere_yes_y_and_all() -> None:
    from conceptbot.core.trace import ClarifyingQuestion

    confirm = ClarifyingQuestion("Should I?", "bowl", ("lemon",), (0.5,))
    assert [confirm.read(r) for r in ("Yes", " Y ", "YES", "n", "No", "maybe")] == [
        ("lemon",),
        ("lemon",),
        ("lemon",),
        (),
        (),
        None,
    ]
    choose = ClarifyingQuestion("Which?", "bowl", ("lemon", "lime"), (0.5, 0.5), kind="choose")
    assert choose.read("All") == ("lemon", "lime") and choose.read("none") == ()
    one = ClarifyingQuestion("Which one?", "user", ("coke", "water"), (0.5, 0.5), kind="one")
    assert one.read("all") is None  # one object only
