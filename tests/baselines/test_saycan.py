import math

import pytest

from conceptbot.baselines.saycan import DONE_AFFORDANCE, SayCan
from conceptbot.core.plan import format_actions
from conceptbot.core.scene import scene_from_dict
from conceptbot.models.fake import FakeLLM
from tests.pipeline.fakes import Recorder, spill_scene

OPTIONS = [
    "robot.pick_and_place(chips, table)",
    "robot.pick_and_place(chips, user)",
    "robot.pick_and_place(sponge, table)",
    "robot.pick_and_place(sponge, user)",
    "robot.pick_and_place(knife, table)",
    "robot.pick_and_place(knife, user)",
    "done()",
]


def test_scores_are_llm_probability_times_binary_affordance_normalised() -> None:
    logprobs = [math.log(p) for p in (0.1, 0.4, 0.05, 0.05, 0.05, 0.05, 0.3)]
    llm = FakeLLM(scores=[logprobs, [0.0 if o == "done()" else -9.0 for o in OPTIONS]])
    plan = SayCan(llm).plan("Bring me chips", spill_scene())
    assert format_actions(plan.actions) == ["pick_and_place(chips, user)", "done()"]
    first = {c.action: c for c in plan.steps[0].candidates}
    total = 0.1 + 0.4 + 4 * 0.05 + 0.3 * DONE_AFFORDANCE
    assert first["pick_and_place(chips, user)"].combined == pytest.approx(0.4 / total)
    assert first["done()"].combined == pytest.approx(0.3 * DONE_AFFORDANCE / total)
    assert first["done()"].affordance == DONE_AFFORDANCE
    assert list(llm.score_requests[0].options) == OPTIONS


def test_prompt_lists_objects_request_and_history() -> None:
    llm = FakeLLM(scores=[[0.0] + [-9.0] * 6, [-9.0] * 6 + [0.0]])
    SayCan(llm).plan("Put the chips on the table", spill_scene())
    first, second = (r.prompt or "" for r in llm.score_requests)
    assert first.endswith("objects = [chips, sponge, knife, table, user]\n# Put the chips on the table\n")
    assert second.endswith("# Put the chips on the table\nrobot.pick_and_place(chips, table)\n")
    assert "robot.pick_and_place(blue block, green bowl)" in first  # the few-shot context


def test_undetected_objects_get_zero_affordance() -> None:
    scene = scene_from_dict(
        {
            "objects": ["apple", "user"],
            "pickable_objects": ["apple"],
            "destinations": ["user"],
            "detections": {"apple": {"confidence": 0.0}},
        }
    )
    llm = FakeLLM(scores=[[0.0, -5.0]])
    plan = SayCan(llm).plan("apple", scene)
    assert format_actions(plan.actions) == ["done()"] and plan.steps[0].candidates[0].action == "done()"


def test_feedback_makes_failed_options_infeasible_and_keeps_executed_steps() -> None:
    from conceptbot.core.plan import Feedback, PickAndPlace, valid_actions

    scene = spill_scene()
    actions = valid_actions(scene)
    order = [str(a) for a in actions]
    best = order.index("pick_and_place(chips, user)")
    second = order.index("pick_and_place(sponge, user)")
    scores = [[0.0 if i == best else (-0.5 if i == second else -9.0) for i in range(len(order))]]
    scores.append([0.0 if a == "done()" else -9.0 for a in order])
    plan = SayCan(FakeLLM(scores=scores)).plan(
        "r",
        scene,
        feedback=Feedback(executed=(PickAndPlace("knife", "table"),), failed=((actions[best], "slipped"),)),
    )
    assert format_actions(plan.actions) == [
        "pick_and_place(knife, table)",
        "pick_and_place(sponge, user)",
        "done()",
    ]


def test_each_step_is_announced_and_reported_to_the_observer() -> None:
    scores = [[0.0 if o == "robot.pick_and_place(chips, user)" else -9.0 for o in OPTIONS]]
    scores.append([0.0 if o == "done()" else -9.0 for o in OPTIONS])
    seen = Recorder()
    plan = SayCan(FakeLLM(scores=scores)).plan("Bring me chips", spill_scene(), observer=seen)
    assert seen.names() == [
        "SayCan: step 1 (7 candidates, saycan)",
        "event:step",
        "SayCan: step 2 (7 candidates, saycan)",
        "event:step",
    ]
    assert [entry[2] for entry in seen.seen if entry[0] == "event"] == [s.to_dict() for s in plan.steps]
